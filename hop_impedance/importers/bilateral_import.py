"""Lab session -> contract v2 :class:`~hop_impedance.bilateral.BilateralRecording` (both legs, one wrench per foot).

The v1 import (:func:`~hop_impedance.importers.session.session_to_recording`)
sums the plates and keeps the right leg; it stays the default and is called
unchanged here for the v1 view. The left leg's markers come from a second call
with the left-side marker map and the same origin, checked to give the same
frame. Each plate's wrench is then expressed in that frame about the contract
origin with the same moment transfer as the sum (:func:`total_wrench` of one
plate), so the per-side wrenches add up to the v1 summed wrench.

Which plate is which foot: each loaded plate (vertical force above 20 N on
some sample) goes to the side whose ankle marker is laterally (contract y)
closest to the plate's force-weighted mean centre of pressure; several plates
under one foot are summed. A side that no plate carried (a leg in the air, or
off the plates, all trial long) gets an all-zero wrench: single-leg hopping.
The left leg's ``head`` is the right map's (v2 has one head marker, the HAT's
top; it is not part of either leg's inverse dynamics).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from hop_impedance.bilateral import SIDES, BilateralRecording
from hop_impedance.importers.frames import to_contract
from hop_impedance.importers.marker_mapping import MarkerMapping
from hop_impedance.importers.plates import total_wrench
from hop_impedance.importers.session import LabSession, PlateData, session_to_recording
from hop_impedance.recording import ForcePlateSeries, Recording

#: A plate is "loaded" (assigned to a foot) when its vertical force exceeds this on some sample (N).
LOADED_N = 20.0


def session_to_bilateral(
    session: LabSession, right: MarkerMapping, left: MarkerMapping, **options
) -> BilateralRecording:
    """Both legs and both plates of a lab session (contract v2).

    Parameters
    ----------
    session : LabSession
        Must have markers (the plates are assigned to feet by the ankle markers).
    right, left : MarkerMapping
        Marker maps of the right and the left leg (e.g. ``opencap_right``, ``opencap_left``).
    **options
        As for :func:`session_to_recording` (``up``, ``forward``, ``mass_kg``,
        ``height_m``, ``plates``, ``sex``); the v1 view is exactly what that
        function returns with the right map.

    Raises
    ------
    ValueError
        No markers, or the left map resolves the lab axes differently from the right one.
    """
    if session.marker_positions_m is None:
        raise ValueError(f"{session.source or 'session'}: per-leg import needs markers (to tell the feet's plates apart)")
    frame: dict = {}
    rec = session_to_recording(session, right, frame_out=frame, **options)
    left_rec = _left_leg_recording(session, left, rec, frame, options)
    # session_to_recording returns markers for a session with markers (checked above)
    assert rec.markers is not None and left_rec.markers is not None
    chosen = session.plates if options.get("plates") is None else [session.plates[i] for i in options["plates"]]
    per_plate = _plate_reactions(chosen, frame["rotation"], frame["origin"], rec.force.force_n)
    ankle_y = {
        "right": float(np.nanmedian(rec.markers.marker("ankle")[:, 1])),
        "left": float(np.nanmedian(left_rec.markers.marker("ankle")[:, 1])),
    }
    sums, notes = _wrench_per_foot(chosen, per_plate, ankle_y, rec.force)
    rec.warnings.extend(notes)
    plates = {side: ForcePlateSeries(rec.force.stamp_ns.copy(), f, m) for side, (f, m) in sums.items()}
    left_markers = left_rec.markers
    head = left_markers.names.index("head")
    left_markers.positions_m[:, head] = rec.markers.marker("head")  # contract v2: one head marker (one HAT)
    return BilateralRecording(rec, plates, left_markers)


def _left_leg_recording(session: LabSession, left: MarkerMapping, rec: Recording, frame: dict, options: dict) -> Recording:
    """The v1 import with the left map, the right one's subject and origin; the lab axes must agree."""
    assert rec.subject is not None  # session_to_recording always sets the subject
    left_options = {**options, "mass_kg": rec.subject.body_mass_kg, "height_m": rec.subject.body_height_m}
    left_frame: dict = {}
    left_rec = session_to_recording(replace(session, origin_m=frame["origin"]), left, frame_out=left_frame, **left_options)
    if not np.allclose(left_frame["rotation"], frame["rotation"], atol=1e-9):
        raise ValueError(
            f"{session.source or 'session'}: the left marker map gives other lab axes than the right one; give --up and --forward"
        )
    return left_rec


def _plate_reactions(
    chosen: list[PlateData], rotation: np.ndarray, origin: np.ndarray, summed_force_n: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each plate's (force N, moment N m about the contract origin) in contract axes, with the sign the
    v1 import gave the summed wrench (negated when the file gives the action on the plate)."""
    per_plate = []
    for p in chosen:
        f = to_contract(p.force_n, rotation)
        m = to_contract(p.moment_nm, rotation)
        r = np.broadcast_to(to_contract(p.point_m, rotation, origin), p.force_n.shape)
        per_plate.append(total_wrench(f[None], m[None], r[None], np.zeros(3)))
    raw_sum = sum(f for f, _ in per_plate)
    sign = -1.0 if np.allclose(raw_sum, -summed_force_n, atol=1e-6) and np.any(raw_sum) else 1.0
    return [(sign * f, sign * m) for f, m in per_plate]


def _wrench_per_foot(
    chosen: list[PlateData],
    per_plate: list[tuple[np.ndarray, np.ndarray]],
    ankle_y: dict[str, float],
    summed: ForcePlateSeries,
) -> tuple[dict[str, list[np.ndarray]], list[str]]:
    """Sum the loaded plates per foot (the side whose ankle is laterally closest to the plate's
    force-weighted mean centre of pressure); side -> [force, moment], and a note per decision."""
    sums = {side: [np.zeros_like(summed.force_n), np.zeros_like(summed.torque_nm)] for side in SIDES}
    notes = []
    for p, (f, m) in zip(chosen, per_plate):
        loaded = f[:, 2] > LOADED_N
        if not loaded.any():
            continue
        cop_y = m[loaded, 0] / f[loaded, 2]  # y of the point on z = 0 where the force acts: Mx = y Fz
        mean_y = float(np.sum(cop_y * f[loaded, 2]) / np.sum(f[loaded, 2]))
        side = min(SIDES, key=lambda s: abs(ankle_y[s] - mean_y))
        sums[side][0] += f
        sums[side][1] += m
        notes.append(f"plate {p.name or '?'} -> {side} foot (mean centre of pressure y {mean_y:+.3f} m, "
                     f"ankle y {ankle_y[side]:+.3f} m)")
    for side in SIDES:
        if not np.any(sums[side][0][:, 2] > LOADED_N):
            notes.append(f"no plate carried the {side} foot: its wrench is zero (leg in the air or off the plates)")
    return sums, notes

def bilateral_from_session(session: LabSession, markers=None, **options) -> BilateralRecording:
    """:func:`session_to_bilateral` with the right map chosen as the v1 import does and its ``_left`` twin.

    ``markers``: a shipped map name or YAML path or :class:`MarkerMapping` for
    the right leg (default: the first shipped map whose markers are all
    present); its name must end in ``_right`` and a shipped ``..._left`` map
    must exist (opencap, plugin_gait, qualisys_isb).
    """
    from hop_impedance.importers.marker_mapping import choose_mapping, load_marker_mapping

    if session.marker_positions_m is None:
        raise ValueError(f"{session.source or 'session'}: per-leg import needs markers (to tell the feet's plates apart)")
    right = choose_mapping(session.marker_labels, markers)
    if not right.name.endswith("_right"):
        raise ValueError(f"marker map {right.name!r} is not a right-leg map (*_right): both legs need a right and a left map")
    return session_to_bilateral(session, right, load_marker_mapping(right.name[: -len("_right")] + "_left"), **options)


def import_c3d_bilateral(path: str | Path, markers=None, **options) -> BilateralRecording:
    """Contract v2 recording from a C3D file with one plate per foot (see :func:`bilateral_from_session`)."""
    from hop_impedance.importers.c3d_import import c3d_session

    return bilateral_from_session(c3d_session(path), markers, **options)


def import_opensim_bilateral(trc_path: str | Path, mot_path: str | Path, markers=None, **options) -> BilateralRecording:
    """Contract v2 recording from an OpenSim TRC + GRF MOT pair with one plate per foot (see :func:`bilateral_from_session`)."""
    from hop_impedance.importers.opensim_import import opensim_session

    return bilateral_from_session(opensim_session(trc_path, mot_path), markers, **options)
