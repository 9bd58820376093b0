"""One leg at a time (issue 21): each leg's stances, inverse dynamics and impedance fits on its own plate.

The lumped analysis (:func:`~hop_impedance.biomech.analysis.analyze_recording`
on the summed plate with both legs as one) stays the default. Here each leg of
a contract v2 recording (:class:`~hop_impedance.bilateral.BilateralRecording`)
is analysed by the *same* code on a v1 view of that leg
(:meth:`BilateralRecording.leg`): its stances found by the project's one
detector on its own plate's vertical force, its 2D sagittal Newton-Euler
bottom-up from its own foot's wrench (force and centre of pressure) to its own
hip with its own markers, its impedance fitted by the existing fit.

Body-segment parameters per leg (:func:`leg_model`): foot, shank and thigh are
half the lumped (two-leg) segments, i.e. de Leva's one-side rows; lengths come
from that leg's markers. The HAT is not part of a leg: it is kept in the model
only because the v1 model has four segments, and the top-down HAT residual
(``hip_residual_rms_nm``) is meaningless for one leg, so it is set to NaN.

Single-leg hopping: the plate of the leg in the air never passes the touchdown
level, so that leg has no stance and the other is analysed alone. The
detector's levels scale with the *whole* body weight (6 % to touch down),
which one foot carrying half of it passes just as well.

Rigid-segment fit (the per-leg default, ``rigid=True``)
-------------------------------------------------------
Skin markers do not keep a leg's segment lengths: on the real OpenCap drop
jump the ankle-knee and knee-hip distances change by up to 2.9 cm during the
contact. The v1 (lumped) kinematics use the measured joint points frame by
frame, so the moment arms of one foot's ~1000 N change with the skin; a rigid
multibody model (OpenSim's) cannot follow that and disagreed by 17-33 % of
peak. Per leg we therefore do what a biomechanist does before inverse
dynamics (OpenSim's IK, then its coordinate filter):

1. Segment lengths and the foot triangle are fixed from the calibration frames
   (the same :func:`body_model_from_markers` model the analysis uses).
2. Per marker frame, the leg's pose - hip ``x, z`` and the foot, shank and
   thigh angles q1..q3 - is fitted to that leg's toe, heel, ankle, knee and
   hip markers by unweighted least squares (Gauss-Newton,
   :func:`fit_leg_pose`). The HAT is not part of the leg: the head marker
   does not pull the leg's pose; q4 is the direction hip -> head.
3. The coordinates are interpolated by cubic spline onto a
   :data:`RIGID_RATE_HZ` grid and low-passed there at
   ``options.marker_cutoff_hz`` (the same zero-lag Butterworth as the markers
   would be; :func:`smooth_pose`), and the six markers rebuilt on the rigid
   leg (:func:`rigid_leg_markers`).
4. The v1 analysis runs on these markers with its marker filter at
   :data:`PASS_THROUGH_HZ` (it leaves a 12 Hz signal unchanged: the filtering
   was done on the coordinates, where it keeps the leg rigid).
   Against OpenSim's InverseDynamicsTool driven by the analysis' own angles
   and hip path (hip, % of its peak, left / right;
   ``bench/per_leg_kinematics.py``): rigid markers filtered one by one (the v1
   way) 8.1 / 9.7, as that bends the leg in the impact; the pose low-passed
   at the markers' 100 Hz and the markers filtered again 4.8 / 5.1; the
   low-passed 100 Hz pose spline-interpolated to 1 kHz 1.3 / 1.6, the spline's
   knots being in the second derivatives; spline first, then low-pass at
   1 kHz (this step) 0.02 / 0.04. The v1 kinematics differentiate the spline
   of each segment's centre-of-mass path, a multibody tool the coordinates:
   on band-limited 1 kHz coordinates both read the same accelerations.
   ``analysis.options`` are the caller's (the data's bandwidth is the
   coordinates' cut-off, which is what the impedance fit needs).

``rigid=False`` gives the previous behaviour (the v1 kinematics on the leg's
markers as measured), used to check that left + right add up to the lumped
analysis when the kinematics are the same.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.interpolate import CubicSpline

from hop_impedance.bilateral import SIDES, BilateralRecording
from hop_impedance.biomech.analysis import AnalysisOptions, RecordingAnalysis, analyze_recording, calibration_markers
from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.biomech.filtering import fill_gaps, lowpass, sampling_rate_hz, uniform_times
from hop_impedance.biomech.kinematics import _POINT_IDX, body_model_from_markers, sagittal_markers, segment_angles_from_points
from hop_impedance.recording import MARKER_NAMES, MarkerSeries, Recording, Subject

if TYPE_CHECKING:  # impedance/ is imported when fitting only
    from hop_impedance.impedance.stance_fit import FitOptions, JointImpedanceFit

#: The segments of one leg (the HAT belongs to neither).
LEG_SEGMENTS = ("foot", "shank", "thigh")

#: Rate (Hz) of the rebuilt rigid-leg markers (see the module docstring, step 4).
RIGID_RATE_HZ = 1000.0
#: The analysis' marker cut-off on the rebuilt markers (Hz): a pass-through for coordinates low-passed at
#: 12 Hz (gain 1 - 1e-5 there; 0.998 at the 40 Hz of the noise-free recovery bench).
PASS_THROUGH_HZ = 200.0
#: Pose coordinates of :func:`fit_leg_pose`, in column order.
POSE_COORDINATES = ("hip_x", "hip_z", "q1_foot", "q2_shank", "q3_thigh", "q4_hat")
_LEG_MARKERS = [MARKER_NAMES.index(n) for n in ("toe", "heel", "ankle", "knee", "hip")]
_HEAD, _HIP = MARKER_NAMES.index("head"), MARKER_NAMES.index("hip")


def _unit(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segment axis (cos q, sin q) and its normal (-sin q, cos q), each (..., 2)."""
    c, s = np.cos(q), np.sin(q)
    return np.stack([c, s], axis=-1), np.stack([-s, c], axis=-1)


def leg_pose_markers(pose: np.ndarray, model: BodyModel) -> np.ndarray:
    """The six contract markers ``[x, z]`` (N, 6, 2) of the rigid leg in pose ``pose`` (N, 6), :data:`POSE_COORDINATES`.

    Down from the hip at the model's fixed lengths: knee, ankle, toe; the heel
    on the model's foot triangle; the head at the HAT's length along q4.
    """
    g = model.foot_geometry
    hip = pose[:, :2]
    (e1, n1), (e2, _), (e3, _), (e4, _) = (_unit(pose[:, 2 + k]) for k in range(4))
    knee = hip - model.thigh.length_m * e3
    ankle = knee - model.shank.length_m * e2
    toe = ankle - g.toe_ankle_m * e1
    heel = toe + g.heel_along_m * e1 + g.heel_perp_m * n1
    head = hip + model.hat.length_m * e4
    return np.stack([toe, heel, ankle, knee, hip, head], axis=1)


def fit_leg_pose(markers_xz: np.ndarray, model: BodyModel, iterations: int = 50) -> np.ndarray:
    """Least-squares rigid-leg pose per frame (step 2 of the module docstring), shape (M, 6), :data:`POSE_COORDINATES`.

    ``markers_xz`` (M, 6, 2) in :data:`MARKER_NAMES` order, finite. Minimises
    the summed squared distances of the toe, heel, ankle, knee and hip markers
    to the model's (5 unknowns, 10 equations per frame) by Gauss-Newton from
    the segment angles of the markers themselves, all frames at once; q4 is
    the angle of hip (fitted) -> head (marker).
    """
    x = np.asarray(markers_xz, float)[:, _LEG_MARKERS]  # (M, 5, 2) toe heel ankle knee hip
    g = model.foot_geometry
    pose = np.zeros((len(x), 6))
    pose[:, :2] = x[:, 4]
    pose[:, 2:5] = segment_angles_from_points(np.asarray(markers_xz, float)[:, _POINT_IDX])[:, :3]
    for _ in range(iterations):
        residual = (leg_pose_markers(pose, model)[:, :5] - x).reshape(len(x), 10)
        (e1, n1), (e2, n2), (e3, n3) = (_unit(pose[:, 2 + k]) for k in range(3))
        jac: np.ndarray = np.zeros((len(x), 5, 2, 5))  # d marker / d (hip_x, hip_z, q1, q2, q3); d e/dq = n, d n/dq = -e
        jac[:, :, 0, 0] = jac[:, :, 1, 1] = 1.0
        jac[:, :4, :, 4] = (-model.thigh.length_m * n3)[:, None]
        jac[:, :3, :, 3] = (-model.shank.length_m * n2)[:, None]
        jac[:, 0, :, 2] = -g.toe_ankle_m * n1
        jac[:, 1, :, 2] = (g.heel_along_m - g.toe_ankle_m) * n1 - g.heel_perp_m * e1
        jac = jac.reshape(len(x), 10, 5)
        jt = np.swapaxes(jac, 1, 2)
        step = np.linalg.solve(jt @ jac, -(jt @ residual[..., None]))[..., 0]
        pose[:, :5] += step
        if np.max(np.abs(step), initial=0.0) < 1e-12:
            break
    head = np.asarray(markers_xz, float)[:, _HEAD] - pose[:, :2]
    pose[:, 5] = np.unwrap(np.arctan2(head[:, 1], head[:, 0]))
    return pose


def smooth_pose(t_s: np.ndarray, pose: np.ndarray, cutoff_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Pose coordinates (M, k) at marker times ``t_s`` onto a :data:`RIGID_RATE_HZ` grid, then low-passed there.

    Cubic spline through the fitted (unfiltered) coordinates, evaluated every
    1 / RIGID_RATE_HZ s from ``t_s[0]``, then the project's zero-lag
    Butterworth at ``cutoff_hz`` at that rate: the result has no content near
    the marker rate, so any later interpolation of it (our spline of each
    segment's centre of mass, OpenSim's spline of the coordinates) differentiates
    the same curve. Filtering at the marker rate and then interpolating left the
    spline's knots in the second derivatives: up to 1.6 % of the hip's peak
    between us and OpenSim on the drop jump, instead of 0.04 %
    (``bench/per_leg_kinematics.py``).

    Returns ``(grid_s, pose_on_grid)``.
    """
    grid = uniform_times(t_s[0], t_s[-1], RIGID_RATE_HZ)
    return grid, lowpass(CubicSpline(t_s, pose, axis=0)(grid), RIGID_RATE_HZ, cutoff_hz)


def rigid_leg_markers(markers: MarkerSeries, model: BodyModel, cutoff_hz: float,
                      max_gap_s: float) -> tuple[MarkerSeries, np.ndarray, np.ndarray]:
    """One leg's markers moved onto the rigid leg (steps 2-3 of the module docstring).

    Gaps are filled first as the v1 kinematics fill them
    (:func:`~hop_impedance.biomech.filtering.fill_gaps`); rebuilt samples that
    fall where a marker was in an unfilled gap are NaN again, so the analysis
    rejects a stance there for the same reason as on the measured markers.

    Returns
    -------
    MarkerSeries
        The six markers on the :data:`RIGID_RATE_HZ` grid of :func:`smooth_pose`
        (y: each marker's median y).
    ndarray, shape (G, 6)
        The low-passed pose (:data:`POSE_COORDINATES`) on that grid.
    ndarray, shape (M,)
        Per marker frame, the RMS distance (m) of the five leg markers to the fitted leg.
    """
    t = (markers.stamp_ns - markers.stamp_ns[0]) * 1e-9
    filled, reliable, _ = fill_gaps(t, sagittal_markers(markers), max_gap_s)
    if not np.all(np.isfinite(filled)):
        bad = [MARKER_NAMES[c] for c in range(filled.shape[1]) if not np.isfinite(filled[:, c]).all()]
        raise ValueError(f"marker(s) {bad} never visible: cannot fit the rigid leg")
    pose = fit_leg_pose(filled, model)
    fit_rms = np.sqrt(np.mean(np.sum((leg_pose_markers(pose, model) - filled)[:, _LEG_MARKERS] ** 2, axis=2), axis=1))
    grid, smooth = smooth_pose(t, pose, cutoff_hz)
    # per marker: a rebuilt marker is missing where that marker was in an unfilled gap, so the analysis names it
    ok = np.column_stack([np.interp(grid, t, reliable[:, c].astype(float)) >= 1.0 for c in range(reliable.shape[1])])
    xz = leg_pose_markers(smooth, model)
    positions = np.empty(xz.shape[:2] + (3,))
    positions[..., 0], positions[..., 2] = xz[..., 0], xz[..., 1]
    positions[..., 1] = np.nanmedian(markers.positions_m[:, [markers.names.index(n) for n in MARKER_NAMES], 1], axis=0)
    positions[~ok] = np.nan
    stamps = markers.stamp_ns[0] + np.round(grid * 1e9).astype(np.int64)
    return MarkerSeries(stamps, MARKER_NAMES, positions), smooth, fit_rms


def leg_model(lumped: BodyModel) -> BodyModel:
    """One leg's model from a lumped (two-leg) one: foot, shank and thigh mass and inertia halved.

    Lengths, centre-of-mass positions and the foot's shape are unchanged (they
    are per leg already: the lumped model is two identical legs on top of each
    other). The HAT is left as it is; it is not part of a leg's inverse dynamics.
    """
    halves = {name: replace(getattr(lumped, name), mass_kg=getattr(lumped, name).mass_kg / 2,
                            inertia_kgm2=getattr(lumped, name).inertia_kgm2 / 2) for name in LEG_SEGMENTS}
    return replace(lumped, **halves)


def leg_subject(subject: Subject) -> Subject:
    """The subject as one leg's segment tables see it: half the body mass.

    de Leva's segment masses and inertias are proportional to the body mass, so
    a model scaled for this subject from one leg's markers has exactly
    :func:`leg_model`'s foot, shank and thigh (tested); its HAT is halved too,
    which no leg uses. For the live ``inverse_dynamics`` node with ``side``
    left or right, whose stage scales its model itself; stance detection there
    keeps the whole body weight, as :func:`analyze_leg` does.
    """
    return replace(subject, body_mass_kg=subject.body_mass_kg / 2)


def analyze_leg(bilateral: BilateralRecording, side: str, options: AnalysisOptions | None = None,
                rigid: bool = True) -> RecordingAnalysis:
    """Stances and per-stance inverse dynamics of one leg (see the module docstring).

    ``options.body_model``, when given, is taken as that leg's model as is;
    otherwise the lumped de Leva model is scaled from that leg's markers by
    the lumped analysis' rule (the calibration frames of
    :func:`~hop_impedance.biomech.analysis.calibration_markers`,
    ``options.overrides`` applied) and halved by :func:`leg_model`.
    ``rigid``: kinematics from the rigid-segment fit (default), else from the
    leg's markers as measured (the v1 kinematics).
    """
    options = options or AnalysisOptions()
    rec = bilateral.leg(side)
    if rec.subject is None:
        raise ValueError(f"{rec.source or 'recording'}: no /subject message; give the subject's mass and height")
    model = options.body_model or _leg_body_model(rec, options)
    if rigid and model is not None and rec.markers is not None and len(rec.markers) >= 8:
        rigid_markers, _, fit_rms = rigid_leg_markers(rec.markers, model, options.marker_cutoff_hz, options.max_gap_s)
        note = (f"{side} leg: kinematics of a rigid-segment fit to the markers (median / max RMS marker distance "
                f"{1000 * np.median(fit_rms):.1f} / {1000 * np.max(fit_rms):.1f} mm), coordinates low-passed "
                f"at {options.marker_cutoff_hz:g} Hz")
        analysis = _analyze_fitted(replace(rec, warnings=rec.warnings + [note]), rigid_markers, model, options)
    else:
        analysis = analyze_recording(rec, replace(options, body_model=model))
    for stance in analysis.stances:
        stance.hip_residual_rms_nm = float("nan")  # the HAT is not part of one leg: no top-down check
    return analysis


def _leg_body_model(rec: Recording, options: AnalysisOptions) -> BodyModel | None:
    """One leg's model: the lumped analysis' scaling rule (same calibration frames) on that leg's markers, halved."""
    if rec.markers is None or not len(rec.markers):
        return None
    assert rec.subject is not None  # analyze_leg checks it; sum_against_lumped runs analyze_legs first
    calibration = calibration_markers(rec.markers, options.calibration_s)
    return leg_model(body_model_from_markers(rec.subject, calibration, options.overrides))


def _analyze_fitted(rec: Recording, markers: MarkerSeries, model: BodyModel, options: AnalysisOptions) -> RecordingAnalysis:
    """The v1 analysis on rigid-fit markers (step 4 of the module docstring); ``options`` kept as the caller's."""
    assert rec.markers is not None  # analyze_leg fits the rigid leg only to a leg with markers
    measured_hz = sampling_rate_hz((rec.markers.stamp_ns - rec.markers.stamp_ns[0]) * 1e-9)
    leg_options = replace(options, body_model=model, marker_cutoff_hz=PASS_THROUGH_HZ, marker_measured_rate_hz=measured_hz)
    analysis = analyze_recording(replace(rec, markers=markers), leg_options)
    analysis.options = replace(options, body_model=model)
    return analysis


def analyze_legs(bilateral: BilateralRecording, options: AnalysisOptions | None = None,
                 rigid: bool = True) -> dict[str, RecordingAnalysis]:
    """:func:`analyze_leg` for both sides, ``{"left": ..., "right": ...}``."""
    _require_bilateral(bilateral)
    return {side: analyze_leg(bilateral, side, options, rigid) for side in SIDES}


def _require_bilateral(bilateral: BilateralRecording) -> None:
    """A one-line ValueError unless the recording has both plates, both legs' markers and a subject."""
    source = bilateral.recording.source or "recording"
    if not bilateral.is_bilateral:
        raise ValueError(
            f"{source}: per-leg analysis needs contract v2 "
            "(one wrench topic per plate and both legs' markers); this is a v1 recording: use the lumped analysis"
        )
    if bilateral.recording.markers is None:
        raise ValueError(f"{source}: no markers on /mocap/markers for the right leg")
    if bilateral.recording.subject is None:
        raise ValueError(f"{source}: no /subject message; give the subject's mass and height")


def fit_legs(
    analyses: dict[str, RecordingAnalysis], options: FitOptions | None = None
) -> dict[str, list[dict[str, JointImpedanceFit]]]:
    """Impedance fits per leg, stance and joint with the existing fit
    (:func:`~hop_impedance.impedance.recording_fits.fit_recording`): ``{side: [{joint: JointImpedanceFit}]}``."""
    from hop_impedance.impedance.recording_fits import fit_recording

    return {side: fit_recording(analysis, options) for side, analysis in analyses.items()}


def moments_on_common_time(analyses: dict[str, RecordingAnalysis], t_s: np.ndarray) -> dict[str, np.ndarray]:
    """Each leg's joint moments (N m, ankle/knee/hip) on times ``t_s`` (s since the recording's start).

    Zero where the leg has no accepted stance (a foot in the air carries no
    moment from the ground up apart from its own segments' inertia, which the
    stance-based analysis does not report); used to add the legs and compare
    with the lumped analysis.
    """
    out = {}
    for side, analysis in analyses.items():
        m = np.zeros((len(t_s), 3))
        for s in analysis.stances:
            if s.joints is None:
                continue
            ts = s.joints.time_s + s.touchdown_s
            sel = (t_s >= ts[0] - 1e-9) & (t_s <= ts[-1] + 1e-9)
            for j in range(3):
                m[sel, j] = np.interp(t_s[sel], ts, s.joints.moment_nm[:, j])
        out[side] = m
    return out


def load_share(bilateral: BilateralRecording, t_s: np.ndarray) -> np.ndarray:
    """The left plate's share of the summed vertical force at times ``t_s`` (s since the recording's start); NaN
    where the plates carry less than 20 N together."""
    rec = bilateral.recording
    ft = (rec.force.stamp_ns - rec.start_ns) * 1e-9
    left, right = (np.interp(t_s, ft, bilateral.plates[side].force_n[:, 2]) for side in ("left", "right"))
    total = left + right
    return np.where(total > 20.0, left / np.where(total > 20.0, total, 1.0), np.nan)


def mean_leg_analysis(bilateral: BilateralRecording, options: AnalysisOptions | None = None,
                      rigid: bool = True) -> RecordingAnalysis:
    """The lumped analysis (:func:`analyze_recording`, unchanged) of a bilateral trial on its *mean leg*.

    The seed's lumped model is two identical legs on one plate; a bilateral
    trial's two legs are not identical (on the OpenCap drop jump the left ankle
    lands 2.9 cm ahead of the right), so the lumped analysis of the summed plate
    is given the mean of the two legs' markers (the head is shared) instead of
    the right leg's. ``rigid``: the mean of the two legs' rigid-fit markers
    (:func:`rigid_leg_markers`, with the analysis' marker filter as a
    pass-through as in :func:`analyze_leg`), so that it is compared with the
    rigid per-leg analysis on the same kinematic footing; else the mean of the
    measured markers, for the per-leg analysis with ``rigid=False``. The lumped
    body model is scaled from the mean measured markers by the lumped rule.
    """
    options = options or AnalysisOptions()
    _require_bilateral(bilateral)
    rec = bilateral.recording
    left, right = bilateral.markers("left"), bilateral.markers("right")
    assert left is not None and right is not None  # is_bilateral: both legs' markers
    mean = MarkerSeries(right.stamp_ns, right.names, (left.positions_m + right.positions_m) / 2)
    model = options.body_model
    if model is None:
        assert rec.subject is not None  # _require_bilateral
        model = body_model_from_markers(rec.subject, calibration_markers(mean, options.calibration_s), options.overrides)
    if not rigid:
        return analyze_recording(replace(rec, markers=mean), replace(options, body_model=model))
    fitted = []
    for side in SIDES:
        leg_markers, leg_body = bilateral.markers(side), _leg_body_model(bilateral.leg(side), options)
        assert leg_markers is not None and leg_body is not None  # both legs' markers (as above)
        fitted.append(rigid_leg_markers(leg_markers, leg_body, options.marker_cutoff_hz, options.max_gap_s)[0])
    markers = MarkerSeries(fitted[0].stamp_ns, fitted[0].names, (fitted[0].positions_m + fitted[1].positions_m) / 2)
    return _analyze_fitted(rec, markers, model, options)


def sum_against_lumped(bilateral: BilateralRecording, options: AnalysisOptions | None = None, rigid: bool = True,
                       share: tuple[float, float] = (0.4, 0.6)) -> tuple[np.ndarray, int]:
    """Left + right against the lumped analysis where both feet share the load (issue 21).

    Compared: each joint's moment of :func:`analyze_legs` (left + right, on the
    lumped analysis' force samples) with :func:`mean_leg_analysis` (same
    ``rigid``), over the samples of the lumped analysis' accepted stances where
    both legs are in an accepted stance and the left plate carries between
    ``share[0]`` and ``share[1]`` of the summed vertical force.

    Returns ``(max |left + right - lumped| / lumped peak per joint (ankle, knee,
    hip), number of samples compared)``; the peak is each joint's largest
    |moment| over the lumped stances. Why the band: with forces F_l, F_r and the
    two ankles ``d`` apart along x, the lumped model's ankle moment differs from
    the sum by about ``(F_l - F_r) d / 2`` (Newton-Euler is linear in the wrench
    and the segment masses; only the lever arms differ), which is small only
    when the feet carry about equal loads.
    """
    legs = analyze_legs(bilateral, options, rigid)
    lumped = mean_leg_analysis(bilateral, options, rigid)
    worst, peak, n = np.zeros(3), np.zeros(3), 0
    for stance in lumped.stances:
        if stance.joints is None:
            continue
        t = stance.joints.time_s + stance.touchdown_s
        down = np.ones(t.size, bool)
        for analysis in legs.values():
            down &= np.any([(t >= s.touchdown_s - 1e-9) & (t <= s.takeoff_s + 1e-9)
                            for s in analysis.stances if s.joints is not None]
                           or [np.zeros(t.size, bool)], axis=0)
        left_share = load_share(bilateral, t)
        sel = down & (left_share >= share[0]) & (left_share <= share[1])
        m = moments_on_common_time(legs, t)
        peak = np.maximum(peak, np.max(np.abs(stance.joints.moment_nm), axis=0))
        if sel.any():
            worst = np.maximum(worst, np.max(np.abs(m["left"] + m["right"] - stance.joints.moment_nm)[sel], axis=0))
            n += int(sel.sum())
    return worst / np.where(peak > 0, peak, np.nan), n
