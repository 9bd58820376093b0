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

from pathlib import Path

import numpy as np

from hop_impedance.importers.frames import parse_axis, rotation_to_contract
from hop_impedance.recording import Recording

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
    mk, fp = recording.markers, recording.force
    marker_rate = 1e9 / float(np.median(np.diff(mk.stamp_ns)))
    force_rate = 1e9 / float(np.median(np.diff(fp.stamp_ns)))
    ratio = force_rate / marker_rate
    if abs(ratio - round(ratio)) > 1e-6:
        raise ValueError(f"force rate {force_rate:g} Hz is not an integer multiple of marker rate {marker_rate:g} Hz")
    ratio = int(round(ratio))
    if abs(int(mk.stamp_ns[0]) - int(fp.stamp_ns[0])) > 0.5e9 / force_rate:
        raise ValueError("markers and forces must start at the same instant to share C3D frames")
    n_frames = min(len(mk), len(fp) // ratio)

    centre = np.asarray(plate_centre_mm, float)
    pos_lab_mm = mk.positions_m[:n_frames] @ rot * 1000.0 + centre
    points = np.ones((4, pos_lab_mm.shape[1], n_frames))
    points[:3] = pos_lab_mm.transpose(2, 1, 0)

    axes = plate_frame(rot)
    n_an = n_frames * ratio
    force_plate = -(fp.force_n[:n_an] @ rot) @ axes  # action on the plate, plate frame
    moment_centre = -(fp.torque_nm[:n_an] @ rot) @ axes * 1000.0  # N mm about the top centre
    moment_origin = moment_centre - np.cross(force_plate, PLATE_ORIGIN_MM)
    analogs = np.concatenate([force_plate, moment_origin], axis=1).T[None]

    c3d = ezc3d.c3d()
    params = c3d["parameters"]
    params["POINT"]["RATE"]["value"] = [marker_rate]
    params["POINT"]["LABELS"]["value"] = list(labels or mk.names)
    params["POINT"]["UNITS"]["value"] = ["mm"]
    params["ANALOG"]["RATE"]["value"] = [force_rate]
    params["ANALOG"]["LABELS"]["value"] = ["Fx1", "Fy1", "Fz1", "Mx1", "My1", "Mz1"]
    params["ANALOG"]["UNITS"]["value"] = ["N"] * 3 + ["Nmm"] * 3
    plate = params["FORCE_PLATFORM"]
    plate["USED"]["value"] = np.array([1])
    plate["TYPE"]["value"] = np.array([2])
    plate["CORNERS"]["value"] = plate_corners_mm(centre, axes)[:, :, None]
    plate["ORIGIN"]["value"] = PLATE_ORIGIN_MM[:, None]
    plate["CHANNEL"]["value"] = np.arange(1, 7)[:, None]
    c3d.add_parameter("POINT", "X_SCREEN", [lab_forward])
    c3d.add_parameter("POINT", "Y_SCREEN", [lab_up])
    if recording.subject is not None:
        c3d.add_parameter("PROCESSING", "Bodymass", float(recording.subject.body_mass_kg))
        c3d.add_parameter("PROCESSING", "Height", float(recording.subject.body_height_m) * 1000.0)
        c3d.add_parameter("SUBJECTS", "NAMES", [recording.subject.subject_id])
    c3d["data"]["points"] = points
    c3d["data"]["analogs"] = analogs
    path = Path(path)
    c3d.write(str(path))
    return path
