"""Why the per-leg rigid fit filters on a 1 kHz grid (issue 21): each variant against OpenSim, real drop jump.

For each leg of the OpenCap drop jump (``Subject4_DJ1``, markers and plates at
100 Hz) the same least-squares rigid-leg pose (``per_leg.fit_leg_pose``) is
turned into kinematics in four ways, the v1 analysis run on the rebuilt
markers, and its joint moments compared with OpenSim's InverseDynamicsTool
driven by the segment angles and hip path of the analysis' own kinematics
(``compute_kinematics`` with the analysis' options, at the plate's samples):
max |ours - OpenSim| / peak over the contact, % per joint. What differs is
only how each reading of the motion turns into segment accelerations:

- ``markers``: rigid markers from the unfiltered pose, the analysis' own 12 Hz
  filter on each marker (the v1 way, applied to a rigid leg);
- ``pose100``: pose low-passed at 12 Hz at 100 Hz, rebuilt at 100 Hz, the
  analysis' 12 Hz marker filter on top;
- ``pose100-spline``: pose low-passed at 100 Hz, then cubic-spline interpolated
  to 1 kHz, marker filter a pass-through (``per_leg.PASS_THROUGH_HZ``);
- ``default``: ``per_leg.smooth_pose`` (spline to 1 kHz, then low-passed
  there), as ``analyze_legs`` does.

    .venv/bin/python bench/per_leg_kinematics.py

Needs OpenSim (requirements/test.txt) and the OpenSim model of the lumped check
(``test/biomech/opensim_model.py``).
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "biomech"))

from hop_impedance.biomech.analysis import analyze_recording, recording_span  # noqa: E402
from hop_impedance.biomech.filtering import fill_gaps, lowpass, sampling_rate_hz  # noqa: E402
from hop_impedance.biomech.force_plate import flight_intervals, flight_offsets, subtract_offsets  # noqa: E402
from hop_impedance.biomech.inverse_dynamics import EXTENSOR_SIGN  # noqa: E402
from hop_impedance.biomech.kinematics import compute_kinematics, sagittal_markers  # noqa: E402
from hop_impedance.biomech.per_leg import (  # noqa: E402
    PASS_THROUGH_HZ,
    RIGID_RATE_HZ,
    analyze_leg,
    fit_leg_pose,
    leg_pose_markers,
    smooth_pose,
)
from hop_impedance.importers.bilateral_import import import_opensim_bilateral  # noqa: E402
from hop_impedance.recording import MARKER_NAMES, MarkerSeries  # noqa: E402

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
CUTOFF_HZ = 12.0


def _variant(name: str, t: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(marker times, pose to rebuild the markers from, the analysis' marker cut-off)."""
    if name == "markers":
        return t, pose, CUTOFF_HZ
    smooth = lowpass(pose, sampling_rate_hz(t), CUTOFF_HZ)
    if name == "pose100":
        return t, smooth, CUTOFF_HZ
    if name == "pose100-spline":
        grid = t[0] + np.arange(int(round((t[-1] - t[0]) * RIGID_RATE_HZ)) + 1) / RIGID_RATE_HZ
        return grid, CubicSpline(t, smooth, axis=0)(grid), PASS_THROUGH_HZ
    grid, fine = smooth_pose(t, pose, CUTOFF_HZ)
    return grid, fine, PASS_THROUGH_HZ


def main() -> None:
    from opensim_model import run_inverse_dynamics

    raw = import_opensim_bilateral(OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt", mass_kg=60.0)
    print("variant         side   max |ours - OpenSim ID| / peak, % (ankle knee hip)")
    for name in ("markers", "pose100", "pose100-spline", "default"):
        for side in ("left", "right"):
            leg = raw.leg(side)
            model = analyze_leg(raw, side, rigid=False).model
            t = (leg.markers.stamp_ns - leg.start_ns) * 1e-9
            xz, _, _ = fill_gaps(t, sagittal_markers(leg.markers), 0.1)
            tm, rebuild, marker_cutoff = _variant(name, t, fit_leg_pose(xz, model))
            pts = leg_pose_markers(rebuild, model)
            pos = np.zeros(pts.shape[:2] + (3,))
            pos[..., 0], pos[..., 2] = pts[..., 0], pts[..., 1]
            markers = MarkerSeries(leg.start_ns + np.round(tm * 1e9).astype(np.int64), MARKER_NAMES, pos)
            options = replace(analyze_leg(raw, side, rigid=False).options, marker_cutoff_hz=marker_cutoff, body_model=model)
            analysis = analyze_recording(replace(leg, markers=markers), options)
            stance = next(s for s in analysis.stances if s.joints is not None)
            data = recording_span(leg)
            tf = data.force_t_s
            flights = flight_intervals([(s.touchdown_s, s.takeoff_s) for s in analysis.stances], float(tf[0]), float(tf[-1]))
            centres, offsets = flight_offsets(tf, data.wrench, flights, options.flight_margin_s)
            wrench = lowpass(subtract_offsets(tf, data.wrench, centres, offsets), sampling_rate_hz(tf), options.force_cutoff_hz)
            rigid = recording_span(replace(leg, markers=markers))
            kin, _ = compute_kinematics(rigid.marker_t_s, rigid.markers_xz, tf, model, marker_cutoff, options.max_gap_s)
            coords = np.column_stack([kin.points_xz[:, 3], kin.q])
            sel = (tf >= stance.touchdown_s) & (tf <= stance.takeoff_s)
            wide = (tf >= stance.touchdown_s - 0.1) & (tf <= stance.takeoff_s + 0.1)
            with tempfile.TemporaryDirectory() as work:
                out = run_inverse_dynamics(model, tf[wide], coords[wide, 2:6], coords[wide, :2], wrench[wide], Path(work))
            theirs = np.column_stack([out[n] for n in ("ankle", "knee", "hip")])[sel[wide]] * EXTENSOR_SIGN
            peak = np.max(np.abs(stance.joints.moment_nm), axis=0)
            rel = 100 * np.max(np.abs(stance.joints.moment_nm - theirs), axis=0) / peak
            print(f"{name:15s} {side:6s} " + " ".join(f"{v:6.2f}" for v in rel))


if __name__ == "__main__":
    main()
