"""Per-leg inverse dynamics on the real bilateral OpenCap drop jump against OpenSim's InverseDynamicsTool (issue 21).

Each leg of ``Subject4_DJ1`` (two plates, one per foot; both legs' markers) is
analysed by :func:`hop_impedance.biomech.per_leg.analyze_legs`. OpenSim then
gets an equivalent planar model of that leg (the per-leg body model built into
the same four-body OpenSim model as the lumped check, ``opensim_model.py``),
the analysis' own joint angles and hip path, and that foot's plate wrench
(zeroed and low-passed as the analysis does); its ankle, knee and hip torques
must match ours within 2 % of each joint's peak at every stance sample.
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.biomech.analysis import AnalysisOptions, recording_span
from hop_impedance.biomech.filtering import lowpass, sampling_rate_hz
from hop_impedance.biomech.force_plate import flight_intervals, flight_offsets, subtract_offsets
from hop_impedance.biomech.inverse_dynamics import EXTENSOR_SIGN
from hop_impedance.biomech.kinematics import compute_kinematics

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
TRC, MOT = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
if importlib.util.find_spec("opensim") is None:  # not imported here: see opensim_model._opensim
    pytest.skip("OpenSim (PyPI 'opensim') is a test dependency", allow_module_level=True)
if not TRC.exists():
    pytest.skip("shared data set opencap_dropjump not present", allow_module_level=True)
from opensim_model import run_inverse_dynamics  # noqa: E402

from biomech_synth import markers_from_points  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402

from hop_impedance.bilateral import SIDES, BilateralRecording  # noqa: E402
from hop_impedance.biomech.kinematics import _POINT_IDX, segment_angles_from_points  # noqa: E402
from hop_impedance.biomech.per_leg import analyze_leg, analyze_legs  # noqa: E402
from hop_impedance.importers.bilateral_import import import_opensim_bilateral  # noqa: E402
from hop_impedance.recording import MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording  # noqa: E402


RATE_HZ = 1000.0
#: Low-pass of this comparison (Hz). The analysis filters each marker on its own; at the default 12 Hz the
#: filtered points of a rigid leg are no longer rigid in the landing impact (lengths off by up to 2.6 mm,
#: oscillating), whose second derivative a multibody tool cannot represent: up to 10 % of the hip's peak.
#: At 40 Hz (the recovery bench's noise-free cut-off) the filtered leg stays rigid.
CUTOFF_HZ = 40.0


def _rigid_leg(markers: MarkerSeries, model, t_s: np.ndarray) -> np.ndarray:
    """Six markers (len(t_s), 6, 3) of a rigid-link leg following this leg's raw motion, at times ``t_s``.

    Segment angles and the hip and head paths of the raw markers are
    interpolated (cubic spline) to ``t_s``; knee, ankle and toe are then placed
    down from the hip at the model's fixed lengths, the heel on the foot's
    fixed triangle.
    """
    tm = (markers.stamp_ns - markers.stamp_ns[0]) * 1e-9
    points = markers.positions_m[..., [0, 2]][:, _POINT_IDX]
    q = segment_angles_from_points(points)
    values = np.concatenate([q, points[:, 3], points[:, 4]], axis=1)
    ok = np.all(np.isfinite(values), axis=1)  # occluded frames (none in the contact) are bridged by the spline
    spline = CubicSpline(tm[ok], np.concatenate([np.unwrap(q[ok], axis=0), values[ok, 4:]], axis=1), axis=0)
    v = spline(t_s)
    rebuilt = np.zeros((len(t_s), 5, 2))
    rebuilt[:, 3], rebuilt[:, 4] = v[:, 4:6], v[:, 6:8]
    lengths = [model.foot_geometry.toe_ankle_m, model.shank.length_m, model.thigh.length_m]
    for j in (2, 1, 0):  # knee, ankle, toe down from the hip
        rebuilt[:, j] = rebuilt[:, j + 1] - lengths[j] * np.stack([np.cos(v[:, j]), np.sin(v[:, j])], axis=1)
    six = markers_from_points(rebuilt, model)
    six[..., 1] = np.nanmedian(markers.positions_m[..., 1], axis=0)
    return six


def rigid_bilateral(raw: BilateralRecording) -> BilateralRecording:
    """The real trial on rigid-link legs, markers and plates at 1 kHz (why: see test_marker_segment_lengths_vary).

    OpenSim's model, like any multibody model, keeps the ankle and knee at fixed
    distances from the hip and needs the coordinates' second derivatives; the
    skin markers keep no fixed distances (up to 2.9 cm off their medians on this
    contact) and at the data's 100 Hz the acceleration of a segment's centre of
    mass depends on whether one interpolates the centre's path (our kinematics)
    or the angles (a multibody tool): up to 10 % of the hip's peak moment in the
    landing impact. Both are properties of the data, not of the inverse dynamics.
    So the motion is moved onto rigid legs (each leg its own fixed lengths, its
    own angles, hip and head paths) and, like the plates (linear
    interpolation), resampled to 1 kHz, where both readings of the motion agree.
    """
    start = raw.recording.start_ns
    models = {side: analyze_leg(raw, side).model for side in SIDES}
    mk = raw.recording.markers
    t_end = min((mk.stamp_ns[-1] - start) * 1e-9, (raw.recording.force.stamp_ns[-1] - start) * 1e-9)
    t = np.arange(0.0, t_end, 1.0 / RATE_HZ)
    stamps = start + np.round(t * 1e9).astype(np.int64)
    ft = (raw.recording.force.stamp_ns - start) * 1e-9

    def plate(p: ForcePlateSeries) -> ForcePlateSeries:
        def col(a):
            return np.column_stack([np.interp(t, ft, a[:, j]) for j in range(3)])
        return ForcePlateSeries(stamps, col(p.force_n), col(p.torque_nm))

    plates = {side: plate(raw.plates[side]) for side in SIDES}
    legs = {side: MarkerSeries(stamps, MARKER_NAMES, _rigid_leg(raw.markers(side), models[side], t)) for side in SIDES}
    v1 = raw.recording
    right = Recording(plate(v1.force), legs["right"], v1.subject, v1.source, list(v1.warnings))
    return BilateralRecording(right, plates, legs["left"])


@pytest.fixture(scope="module")
def legs():
    bilateral = rigid_bilateral(import_opensim_bilateral(TRC, MOT, mass_kg=60.0))
    return bilateral, analyze_legs(bilateral, AnalysisOptions(marker_cutoff_hz=CUTOFF_HZ, force_cutoff_hz=CUTOFF_HZ))


def test_marker_segment_lengths_vary():
    """Why the comparison runs on a rigid leg: the raw markers' segment lengths over the contact (see rigid_markers)."""
    raw = import_opensim_bilateral(TRC, MOT, mass_kg=60.0)
    t = (raw.recording.markers.stamp_ns - raw.recording.start_ns) * 1e-9
    contact = (t >= 1.42) & (t <= 2.16)  # SOURCE.txt: first contact 1.42-2.17 s
    spread = []
    for side in ("left", "right"):
        p = raw.markers(side).positions_m[contact][..., [0, 2]][:, _POINT_IDX]
        lengths = np.linalg.norm(np.diff(p[:, :4], axis=1), axis=2)  # toe-ankle, ankle-knee, knee-hip
        spread.append(np.max(np.abs(lengths - np.median(lengths, axis=0)), axis=0))
    spread = np.max(spread, axis=0)
    print(f"max |segment length - median| over the contact (toe-ankle, ankle-knee, knee-hip): {np.round(100 * spread, 2)} cm")
    assert np.all(spread > 0.005)  # several millimetres to centimetres: skin markers, not a rigid leg


def _analysis_inputs(rec, analysis):
    """The zeroed, low-passed wrench and the kinematics the analysis computed (same functions, same options)."""
    data = recording_span(rec)
    t, opts = data.force_t_s, analysis.options
    flights = flight_intervals([(s.touchdown_s, s.takeoff_s) for s in analysis.stances], float(t[0]), float(t[-1]))
    centres, offsets = flight_offsets(t, data.wrench, flights, opts.flight_margin_s)
    smooth = lowpass(subtract_offsets(t, data.wrench, centres, offsets), sampling_rate_hz(t), opts.force_cutoff_hz)
    kin, _ = compute_kinematics(data.marker_t_s, data.markers_xz, t, analysis.model, opts.marker_cutoff_hz, opts.max_gap_s)
    return t, smooth, kin


def _compare_with_opensim(bilateral, analysis, side, tmp_path) -> np.ndarray:
    """max |ours - OpenSim| / peak per joint over the leg's accepted contact."""
    accepted = [s for s in analysis.stances if s.joints is not None]
    assert len(accepted) == 1  # the landing + rebound contact; the second landing is cut by the file's end
    stance = accepted[0]
    t, wrench, kin = _analysis_inputs(bilateral.leg(side), analysis)
    sel = (t >= stance.touchdown_s) & (t <= stance.takeoff_s)
    assert np.count_nonzero(sel) == len(stance.joints.time_s)
    # OpenSim gets 0.1 s more on each side so that the ends of its spline of the coordinates fall in flight
    wide = (t >= stance.touchdown_s - 0.1) & (t <= stance.takeoff_s + 0.1)
    out = run_inverse_dynamics(analysis.model, t[wide], kin.q[wide], kin.points_xz[wide, 3], wrench[wide], tmp_path)
    theirs = np.column_stack([out[n] for n in ("ankle", "knee", "hip")])[sel[wide]] * EXTENSOR_SIGN
    mine = stance.joints.moment_nm
    peak = np.max(np.abs(mine), axis=0)
    assert np.all(peak > 50)  # N m: a real one-leg landing, not an empty plate
    rel = np.max(np.abs(mine - theirs), axis=0) / peak
    print(f"{side}: peak {np.round(peak, 1)} N m, max |ours - OpenSim| / peak {np.round(100 * rel, 3)} %")
    return rel


@pytest.mark.parametrize("side", ["left", "right"])
def test_leg_moments_agree_with_opensim_within_2_percent(legs, side, tmp_path):
    """Measured: left 0.06 / 1.09 / 0.87 %, right 0.09 / 0.61 / 1.05 % (ankle / knee / hip) of peak."""
    bilateral, analyses = legs
    analysis = analyses[side]
    # per-leg body: half the lumped leg segments (de Leva one side: 1.29 % foot, 4.81 % shank, 14.78 % thigh of 60 kg)
    np.testing.assert_allclose([analysis.model.foot.mass_kg, analysis.model.shank.mass_kg, analysis.model.thigh.mass_kg],
                               [0.0129 * 60, 0.0481 * 60, 0.1478 * 60], rtol=1e-12)
    rel = _compare_with_opensim(bilateral, analysis, side, tmp_path)
    assert np.all(rel < 0.02), rel


def test_raw_skin_markers_at_12_hz_are_not_a_rigid_problem(tmp_path):
    """The limit that the rigid-leg construction removes, measured on the raw 100 Hz skin markers with the default
    12 Hz: OpenSim's rigid leg and our frame-by-frame joint points differ by tens of percent of peak (see the
    figures printed; skin markers change segment lengths by up to 2.9 cm, and per-marker filtering bends a rigid
    leg in the landing impact). Not a defect of either inverse dynamics: they solve different problems."""
    raw = import_opensim_bilateral(TRC, MOT, mass_kg=60.0)
    analyses = analyze_legs(raw)
    for side in SIDES:
        (tmp_path / side).mkdir()
        rel = _compare_with_opensim(raw, analyses[side], side, tmp_path / side)
        assert np.max(rel) > 0.05
