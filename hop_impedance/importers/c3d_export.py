"""Write a contract recording as a lab-style C3D file with ezc3d.

Used to prove the C3D import (a recording written here and imported back must
give the same signals) and to hand simulated sessions to lab software. The
file looks like a Vicon Nexus export: markers in mm in a lab frame whose
axes are chosen by the caller (default: z up, the subject facing lab +Y), one
type-2 force plate whose analog channels are the force and moment *on the
plate* (the subject's action) in the plate's own frame (z pointing down, as
AMTI and Bertec plates are wired), in N and N mm about the transducer origin
``FORCE_PLATFORM:ORIGIN`` below the top surface.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hop_impedance.importers.frames import parse_axis, rotation_to_contract
from hop_impedance.recording import ForcePlateSeries, MarkerSeries, Recording

#: Plate half-sizes (mm) and transducer origin below the top centre (plate frame, mm).
PLATE_HALF_SIZE_MM = (300.0, 200.0)
PLATE_ORIGIN_MM = np.array([0.0, 0.0, -40.0])


def plate_frame(rotation_lab_to_contract: np.ndarray) -> np.ndarray:
    """Plate axes in lab coordinates, shape (3, 3), columns x, y, z: x = contract forward, z = down."""
    x = rotation_lab_to_contract[0]
    z = -rotation_lab_to_contract[2]
    return np.column_stack([x, np.cross(z, x), z])


def plate_corners_mm(centre_mm: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Corners (3, 4) ordered so that ezc3d's plate frame (x = c0 - c1, y = c0 - c3) equals ``axes``."""
    a, b = PLATE_HALF_SIZE_MM
    x, y = axes[:, 0], axes[:, 1]
    return np.column_stack([centre_mm + a * x + b * y, centre_mm - a * x + b * y,
                            centre_mm - a * x - b * y, centre_mm + a * x - b * y])


def write_c3d(
    recording: Recording,
    path: str | Path,
    *,
    lab_up: str = "+Z",
    lab_forward: str = "+Y",
    plate_centre_mm: tuple[float, float, float] = (250.0, 900.0, 0.0),
    labels: tuple[str, ...] | None = None,
) -> Path:
    """Write ``recording`` as a C3D file (markers + one type-2 force plate).

    Parameters
    ----------
    recording : Recording
        Contract recording with markers; the force rate must be an integer
        multiple of the marker rate and both streams must start together.
    path : str or Path
        Output file (``.c3d``).
    lab_up, lab_forward : str
        Lab axes (``"+Z"``, ``"-Y"`` ...) that the contract's z and x become.
    plate_centre_mm : tuple of float
        Lab position of the plate's top centre = the contract origin (mm).
    labels : tuple of str, optional
        Lab labels for the six contract markers (default: contract names).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        Force-only recording, non-integer rate ratio or misaligned starts.
    """
    import ezc3d

    if recording.markers is None:
        raise ValueError("write_c3d needs markers: C3D point data cannot be empty here")
    rot = rotation_to_contract(parse_axis(lab_up), parse_axis(lab_forward))
    frames = shared_frames(recording.markers, recording.force)
    centre = np.asarray(plate_centre_mm, float)
    axes = plate_frame(rot)

    c3d = ezc3d.c3d()
    _set_point_and_analog_parameters(c3d["parameters"], frames, labels or recording.markers.names)
    _set_plate_parameters(c3d["parameters"]["FORCE_PLATFORM"], centre, axes)
    c3d.add_parameter("POINT", "X_SCREEN", [lab_forward])
    c3d.add_parameter("POINT", "Y_SCREEN", [lab_up])
    if recording.subject is not None:
        c3d.add_parameter("PROCESSING", "Bodymass", float(recording.subject.body_mass_kg))
        c3d.add_parameter("PROCESSING", "Height", float(recording.subject.body_height_m) * 1000.0)
        c3d.add_parameter("SUBJECTS", "NAMES", [recording.subject.subject_id])
    c3d["data"]["points"] = point_data(recording.markers, rot, centre, frames.n_frames)
    c3d["data"]["analogs"] = plate_analogs(recording.force, rot, axes, frames.n_frames * frames.ratio)
    path = Path(path)
    c3d.write(str(path))
    return path


@dataclass
class SharedFrames:
    """How markers and forces share C3D frames: one point frame holds ``ratio`` analog samples."""

    marker_rate_hz: float
    force_rate_hz: float
    ratio: int
    #: point frames written (the analog stream holds ``n_frames * ratio`` samples)
    n_frames: int


def shared_frames(markers: MarkerSeries, force: ForcePlateSeries) -> SharedFrames:
    """Rates and frame count of the file; the force rate must be an integer multiple of the marker rate
    and both streams must start at the same instant (ValueError otherwise)."""
    marker_rate = 1e9 / float(np.median(np.diff(markers.stamp_ns)))
    force_rate = 1e9 / float(np.median(np.diff(force.stamp_ns)))
    ratio = force_rate / marker_rate
    if abs(ratio - round(ratio)) > 1e-6:
        raise ValueError(f"force rate {force_rate:g} Hz is not an integer multiple of marker rate {marker_rate:g} Hz")
    ratio = int(round(ratio))
    if abs(int(markers.stamp_ns[0]) - int(force.stamp_ns[0])) > 0.5e9 / force_rate:
        raise ValueError("markers and forces must start at the same instant to share C3D frames")
    return SharedFrames(marker_rate, force_rate, ratio, min(len(markers), len(force) // ratio))


def point_data(markers: MarkerSeries, rotation_lab_to_contract: np.ndarray, centre_mm: np.ndarray, n_frames: int) -> np.ndarray:
    """ezc3d point array (4, markers, frames): contract positions turned into lab mm about the plate centre."""
    pos_lab_mm = markers.positions_m[:n_frames] @ rotation_lab_to_contract * 1000.0 + centre_mm
    points = np.ones((4, pos_lab_mm.shape[1], n_frames))
    points[:3] = pos_lab_mm.transpose(2, 1, 0)
    return points


def plate_analogs(force: ForcePlateSeries, rotation_lab_to_contract: np.ndarray, axes: np.ndarray, n_analog: int) -> np.ndarray:
    """ezc3d analog array (1, 6, samples): Fx Fy Fz (N) and Mx My Mz (N mm about the transducer origin)
    of the action on the plate, in the plate frame ``axes``."""
    rot = rotation_lab_to_contract
    force_plate = -(force.force_n[:n_analog] @ rot) @ axes  # action on the plate, plate frame
    moment_centre = -(force.torque_nm[:n_analog] @ rot) @ axes * 1000.0  # N mm about the top centre
    moment_origin = moment_centre - np.cross(force_plate, PLATE_ORIGIN_MM)
    return np.concatenate([force_plate, moment_origin], axis=1).T[None]


def _set_point_and_analog_parameters(params, frames: SharedFrames, labels: tuple[str, ...]) -> None:
    """POINT and ANALOG groups: rates, labels and units (markers in mm, forces N, moments N mm)."""
    params["POINT"]["RATE"]["value"] = [frames.marker_rate_hz]
    params["POINT"]["LABELS"]["value"] = list(labels)
    params["POINT"]["UNITS"]["value"] = ["mm"]
    params["ANALOG"]["RATE"]["value"] = [frames.force_rate_hz]
    params["ANALOG"]["LABELS"]["value"] = ["Fx1", "Fy1", "Fz1", "Mx1", "My1", "Mz1"]
    params["ANALOG"]["UNITS"]["value"] = ["N"] * 3 + ["Nmm"] * 3


def _set_plate_parameters(plate, centre_mm: np.ndarray, axes: np.ndarray) -> None:
    """FORCE_PLATFORM group of one type-2 plate on analog channels 1-6."""
    plate["USED"]["value"] = np.array([1])
    plate["TYPE"]["value"] = np.array([2])
    plate["CORNERS"]["value"] = plate_corners_mm(centre_mm, axes)[:, :, None]
    plate["ORIGIN"]["value"] = PLATE_ORIGIN_MM[:, None]
    plate["CHANNEL"]["value"] = np.arange(1, 7)[:, None]
