"""Batch analysis of a recording: stances, kinematics, inverse dynamics, per-stance metrics.

``analyze_recording`` runs every stage over the whole record at once. The
streaming stage (:mod:`hop_impedance.biomech.stages`) runs the *same*
:func:`analyze_span` on a window around each stance as the data arrive; see
there for the agreement between the two.

Pipeline (all times in seconds since the recording's first message)
-------------------------------------------------------------------
1. Stance detection on the raw vertical force (:class:`StanceDetector`,
   which estimates the flight baseline from the data and scales its
   thresholds with the subject's body weight).
2. Plate zeroing: offsets measured in each flight, interpolated between
   flight centres (:mod:`force_plate`).
3. The wrench through the markers' own sampling, zero-lag low-pass (at
   ``force_cutoff_hz``, default = the marker cut-off, 12 Hz; see
   :mod:`filtering`) and spline (:func:`kinematics.wrench_through_marker_chain`:
   a touchdown or take-off step is spread as the kinematics spread it).
4. Kinematics from markers, filtered at ``marker_cutoff_hz`` and resampled
   onto force-plate time (:mod:`kinematics`).
5. Inverse dynamics on every force frame (:mod:`inverse_dynamics`).
6. Per stance: timing, peak force (zeroed, *unfiltered* Fz: filtering would
   lower the impact peak), joint series, work, stiffness
   (:mod:`stance_metrics`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.biomech.filtering import DEFAULT_CUTOFF_HZ, DEFAULT_MAX_GAP_S, Gap, sampling_rate_hz
from hop_impedance.biomech.force_plate import (
    DEFAULT_FLIGHT_MARGIN_S,
    flight_intervals,
    flight_offsets,
    sagittal_wrench,
    subtract_offsets,
)
from hop_impedance.biomech.inverse_dynamics import JointLoads, inverse_dynamics_2d, joint_power
from hop_impedance.biomech.joint_angles import JOINT_NAMES as JOINT_NAMES  # re-exported: batch/task.py reads it here
from hop_impedance.biomech.kinematics import (
    Kinematics,
    body_model_from_markers,
    compute_kinematics,
    measured_marker_times,
    sagittal_markers,
    wrench_through_marker_chain,
)
from hop_impedance.biomech.stance_detection import DetectorOptions, Stance, StanceDetector
from hop_impedance.biomech.stance_metrics import (
    com_displacement_from_grf,
    hip_excursion,
    joint_work,
    leg_stiffness,
    overall_joint_stiffness,
)
from hop_impedance.recording import (
    FORCE_TOPIC,
    GRAVITY_M_S2,
    MARKER_NAMES,
    MARKER_TOPIC,
    SUBJECT_TOPIC,
    MarkerSeries,
    Recording,
    Subject,
)


@dataclass(frozen=True)
class AnalysisOptions:
    """Parameters of the analysis (defaults documented in the modules named).

    Attributes
    ----------
    marker_cutoff_hz, force_cutoff_hz : float
        Low-pass cut-offs (Hz), :mod:`filtering`; equal by default.
    max_gap_s : float
        Longest marker gap filled by interpolation (s).
    detector : DetectorOptions
        Stance detection thresholds.
    flight_margin_s : float
        Margin at flight ends ignored by the plate zeroing (s).
    pad_s : float
        Data kept on each side of a stance by the streaming stage (s).
    body_model : BodyModel or None
        Use this model instead of scaling one from the markers.
    overrides : dict or None
        Per-segment overrides applied to the scaled model.
    calibration_s : float or None
        The body model is scaled from the complete marker frames stamped
        within this many seconds of the first complete frame and before the
        first take-off (:func:`calibration_markers`, the rule the live stage
        uses, so live and offline share one model); None = no time limit.
    marker_measured_rate_hz : float or None
        The markers given were resampled from markers measured at this rate
        (the per-leg rigid-fit markers, :mod:`per_leg`): the wrench is
        sampled as that measurement was (:func:`kinematics.measured_marker_times`,
        :func:`kinematics.wrench_through_marker_chain`). None: the markers' own stamps.
    post_takeoff_s : float or None
        Short windows (issue 15, "low latency by default"): each stance is
        analysed on its own window from ``min(touchdown - pad_s, previous
        take-off)`` to ``take-off + post_takeoff_s`` with the end-of-stance
        treatment of :func:`extend_past_window` (force known up to the window
        end, markers up to the last frame stamped at or before it), the
        function the live stage runs. None = the whole record at once.
    """

    marker_cutoff_hz: float = DEFAULT_CUTOFF_HZ
    force_cutoff_hz: float = DEFAULT_CUTOFF_HZ
    max_gap_s: float = DEFAULT_MAX_GAP_S
    detector: DetectorOptions = field(default_factory=DetectorOptions)
    flight_margin_s: float = DEFAULT_FLIGHT_MARGIN_S
    pad_s: float = 0.3
    body_model: BodyModel | None = None
    overrides: dict[str, dict[str, float]] | None = None
    calibration_s: float | None = 1.0
    marker_measured_rate_hz: float | None = None
    post_takeoff_s: float | None = None

    def __post_init__(self) -> None:
        if self.post_takeoff_s is not None and not self.post_takeoff_s > 0:
            raise ValueError(f"post_takeoff_s must be > 0 s (or None for the whole record), got {self.post_takeoff_s}")


@dataclass
class JointSeries:
    """Per-stance joint data, sampled at the force-plate rate from touchdown to take-off.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Time since touchdown (s).
    angle_rad, angular_velocity_rad_s, moment_nm, power_w : ndarray, shape (n, 3)
        rho (rad, increases with flexion), d(rho)/dt (rad/s), net moment of
        both legs (N m, extensor positive), power (W); columns ankle, knee, hip.
    """

    time_s: np.ndarray
    angle_rad: np.ndarray
    angular_velocity_rad_s: np.ndarray
    moment_nm: np.ndarray
    power_w: np.ndarray

    def joint(self, name: str) -> dict[str, np.ndarray]:
        """Arrays of one joint (``ankle``, ``knee`` or ``hip``), each shape (n,)."""
        j = JOINT_NAMES.index(name)
        return {
            "time_s": self.time_s,
            "angle_rad": self.angle_rad[:, j],
            "angular_velocity_rad_s": self.angular_velocity_rad_s[:, j],
            "moment_nm": self.moment_nm[:, j],
            "power_w": self.power_w[:, j],
        }


@dataclass
class StanceResult:
    """Everything computed for one stance; NaN/None where not available.

    ``rejection_reason`` is None for a stance whose joint data may be fitted.
    """

    index: int
    touchdown_s: float
    takeoff_s: float
    complete: bool
    rejection_reason: str | None
    contact_time_s: float
    peak_grf_n: float
    peak_grf_bw: float
    flight_before_s: float | None
    flight_after_s: float | None
    hop_frequency_hz: float | None
    leg_stiffness_n_per_m: float = float("nan")
    leg_stiffness_kinematic_n_per_m: float = float("nan")
    com_drop_grf_m: float = float("nan")
    com_drop_kinematic_m: float = float("nan")
    hip_excursion_m: float = float("nan")
    joints: JointSeries | None = None
    brake_work_j: np.ndarray | None = None
    push_work_j: np.ndarray | None = None
    overall_stiffness_nm_per_rad: np.ndarray | None = None
    hip_residual_rms_nm: float = float("nan")
    #: How far past the take-off the data of this stance's analysis reached (s): ``post_takeoff_s`` of a
    #: short window (:func:`analyze_short_window`, the low-latency stage), None for the whole record.
    #: The fit leaves samples out near take-off when it is short (``recording_fits.takeoff_exclusion_s``).
    data_after_takeoff_s: float | None = None


@dataclass
class RecordingAnalysis:
    """Result of :func:`analyze_recording`.

    ``options`` are the settings the analysis ran with (hook for the impedance
    fit, :mod:`hop_impedance.impedance.recording_fits`, which needs the
    low-pass cut-off as the noise bandwidth); None when built elsewhere.
    """

    subject: Subject
    model: BodyModel | None
    start_ns: int
    recording: dict[str, Any]
    stances: list[StanceResult]
    warnings: list[str] = field(default_factory=list)
    options: AnalysisOptions | None = None


@dataclass
class SpanData:
    """Raw data of a time span, on one clock (s since the recording's start).

    Attributes
    ----------
    force_t_s : ndarray, shape (N,)
    wrench : ndarray, shape (N, 3)
        Raw sagittal wrench ``[Fx, Fz, Mo]`` (:func:`force_plate.sagittal_wrench`).
    marker_t_s : ndarray, shape (M,) or None
    markers_xz : ndarray, shape (M, 6, 2) or None
    """

    force_t_s: np.ndarray
    wrench: np.ndarray
    marker_t_s: np.ndarray | None = None
    markers_xz: np.ndarray | None = None


def stance_timing(stances: list[Stance], k: int) -> tuple[float | None, float | None, float | None]:
    """Flight before, flight after (s) and hop frequency (Hz) of stance ``k``.

    Flights are measured between neighbouring stances' events. Hop frequency
    is 1 / (next touchdown - this touchdown), or 1 / (this - previous
    touchdown) for the last stance; None where no real touchdown pair exists
    (a touchdown cut by the start is not an event).
    """
    s = stances[k]
    before = s.touchdown_s - stances[k - 1].takeoff_s if k > 0 else None
    after = stances[k + 1].touchdown_s - s.takeoff_s if k + 1 < len(stances) else None
    freq = None
    if k + 1 < len(stances) and not s.cut_start:
        freq = 1.0 / (stances[k + 1].touchdown_s - s.touchdown_s)
    elif k > 0 and not s.cut_start and not stances[k - 1].cut_start:
        freq = 1.0 / (s.touchdown_s - stances[k - 1].touchdown_s)
    return before, after, freq


def _gap_reason(gaps: list[Gap], t0: float, t1: float, max_gap_s: float) -> str | None:
    for g in gaps:
        if not g.filled and g.end_s >= t0 and g.start_s <= t1:
            name = MARKER_NAMES[g.column]
            if not np.isfinite(g.duration_s):
                return f"marker {name} missing at the edge of the marker data"
            return f"marker gap of {g.duration_s:.2f} s in {name} exceeds {max_gap_s:.2f} s"
    return None


def analyze_span(
    data: SpanData,
    stances: list[Stance],
    targets: list[int],
    model: BodyModel | None,
    body_mass_kg: float,
    options: AnalysisOptions,
) -> list[StanceResult]:
    """Zeroing, filtering, kinematics, inverse dynamics and metrics of the stances ``targets``.

    Parameters
    ----------
    data : SpanData
        Must cover the target stances plus their neighbouring flights.
    stances : list of Stance
        All stances known (used for flights and timing).
    targets : list of int
        Indices into ``stances`` to compute.
    model : BodyModel or None
        None when there are no markers (only force-based figures are filled).
    body_mass_kg : float
    options : AnalysisOptions

    Returns
    -------
    list of StanceResult, one per target.
    """
    t = data.force_t_s
    times = [(s.touchdown_s, s.takeoff_s) for s in stances]
    flights = flight_intervals(times, float(t[0]), float(t[-1]))
    centres, offsets = flight_offsets(t, data.wrench, flights, options.flight_margin_s)
    zeroed = subtract_offsets(t, data.wrench, centres, offsets)
    kin = loads = None
    gaps: list[Gap] = []
    span_reason = None
    if model is None or data.marker_t_s is None or len(data.marker_t_s) < 8:
        span_reason = "no marker data"
    else:
        span_reason = _too_sparse_reason(t, data.marker_t_s, options)
    if span_reason is None:
        assert model is not None and data.marker_t_s is not None and data.markers_xz is not None  # checked above
        measured = measured_marker_times(data.marker_t_s, options.marker_measured_rate_hz)
        smooth = wrench_through_marker_chain(t, zeroed, measured, data.marker_t_s, options.force_cutoff_hz)
        kin, gaps = compute_kinematics(
            data.marker_t_s, data.markers_xz, t, model, options.marker_cutoff_hz, options.max_gap_s
        )
        loads = inverse_dynamics_2d(kin.points_xz, kin.com_xz, kin.com_acc, kin.qdd, smooth, model)
    weight = body_mass_kg * GRAVITY_M_S2
    return [_stance_result(k, stances, t, zeroed, kin, loads, gaps, span_reason, model, body_mass_kg, weight, options)
            for k in targets]


def _too_sparse_reason(force_t_s: np.ndarray, marker_t_s: np.ndarray, options: AnalysisOptions) -> str | None:
    """Why a window cannot be filtered: a median sampling rate at or below twice the cut-off.

    Happens when most messages of a window were lost (a live stream under
    overload); the stance is then rejected instead of the filter raising.
    """
    for name, t_s, cutoff in (("force", force_t_s, options.force_cutoff_hz), ("marker", marker_t_s, options.marker_cutoff_hz)):
        fs = sampling_rate_hz(t_s)
        if not fs > 2.0 * cutoff:
            return (
                f"{name} samples too sparse in this window (median rate {fs:.1f} Hz, the {cutoff:g} Hz "
                f"low-pass needs more than {2 * cutoff:g} Hz): message loss"
            )
    return None


def _stance_result(
    k: int,
    stances: list[Stance],
    t: np.ndarray,
    zeroed: np.ndarray,
    kin: Kinematics | None,
    loads: JointLoads | None,
    gaps: list[Gap],
    span_reason: str | None,
    model: BodyModel | None,
    mass: float,
    weight: float,
    options: AnalysisOptions,
) -> StanceResult:
    s = stances[k]
    sel = (t >= s.touchdown_s) & (t <= s.takeoff_s)
    fz = zeroed[sel, 1]
    peak = float(np.max(fz)) if fz.size else float("nan")
    before, after, freq = stance_timing(stances, k)
    res = StanceResult(
        k, s.touchdown_s, s.takeoff_s, s.complete, s.rejection_reason, s.contact_time_s,
        peak, peak / weight, before, after, freq,
    )
    if res.rejection_reason is None and np.count_nonzero(sel) < 10:
        res.rejection_reason = f"too few force samples in stance: {np.count_nonzero(sel)} < 10"
    if res.rejection_reason is not None:
        return res
    ts = t[sel]
    disp = com_displacement_from_grf(ts, fz, mass)
    res.com_drop_grf_m = -float(np.min(disp))
    res.leg_stiffness_n_per_m = leg_stiffness(peak, disp)
    reason = span_reason or _gap_reason(gaps, s.touchdown_s, s.takeoff_s, options.max_gap_s)
    if reason is not None:
        res.rejection_reason = reason
        return res
    assert kin is not None and loads is not None and model is not None  # span_reason None: analyze_span ran them
    if not np.all(kin.reliable[sel]):
        res.rejection_reason = "markers do not cover the whole stance"
        return res
    rho, rhod, moment = kin.rho[sel], kin.rhod[sel], loads.moment_nm[sel]
    power = joint_power(moment, rhod)
    res.joints = JointSeries(ts - s.touchdown_s, rho, rhod, moment, power)
    res.brake_work_j, res.push_work_j = joint_work(ts, power)
    res.overall_stiffness_nm_per_rad = overall_joint_stiffness(rho, moment)
    body_z = kin.body_com_xz(model)[sel, 1]
    res.com_drop_kinematic_m = float(body_z[0] - np.min(body_z))
    res.leg_stiffness_kinematic_n_per_m = leg_stiffness(peak, body_z - body_z[0])
    res.hip_excursion_m = hip_excursion(kin.points_xz[sel, 3, 1])
    res.hip_residual_rms_nm = float(np.sqrt(np.mean(loads.hip_residual_moment_nm[sel] ** 2)))
    return res


#: Span synthesised past a short window's end before filtering (s): the zero-lag filters' edge
#: transient (time constant ~13 ms at 12 Hz) has decayed long before it reaches the stance.
TAIL_S = 0.3
#: Marker frames (the last ones at or before the window end) the extrapolating polynomial is fitted to.
MARKER_FIT_FRAMES = 2
#: Degree of that polynomial (1: each marker goes on at the velocity of its last two frames).
MARKER_FIT_DEGREE = 1


def short_window(stances: list[Stance], k: int, options: AnalysisOptions) -> tuple[float, float]:
    """Window of stance ``k`` when ``options.post_takeoff_s`` is set (s): (start, take-off + post_takeoff_s).

    Starts at ``touchdown - pad_s`` or ``TEMPLATE_LEAD_S`` before the
    previous take-off if earlier, so the previous flight (the plate offset
    used for this stance) is whole and the previous hop's take-off (the
    markers' template, :func:`_templated_markers`) is in the window.
    """
    s = stances[k]
    start = s.touchdown_s - options.pad_s
    if k > 0:
        start = min(start, stances[k - 1].takeoff_s - (TEMPLATE_LEAD_S if MARKER_TEMPLATE else 0.0))
    return start, s.takeoff_s + _post_takeoff_s(options)


def _post_takeoff_s(options: AnalysisOptions) -> float:
    """``options.post_takeoff_s`` where a short window is analysed (short windows are used only when it is set)."""
    assert options.post_takeoff_s is not None, "a short window needs options.post_takeoff_s"
    return options.post_takeoff_s


def window_span(data: SpanData, start_s: float, end_s: float) -> SpanData:
    """What a live stage knows of ``[start_s, end_s]``: force samples inside, marker frames stamped at or before the end.

    The last marker frame before ``start_s`` is kept (the spline then
    interpolates at the window start); none after ``end_s``: a live stage
    cannot wait for a frame beyond the window (up to one marker period
    later). The rule uses the stamps only, so any ``data`` holding the
    window and a frame before it (the whole record offline, the stage's
    buffer live) gives the same span.
    """
    t = data.force_t_s
    sel = (t >= start_s) & (t <= end_s)
    out = SpanData(t[sel], data.wrench[sel])
    if data.marker_t_s is not None:
        tm = data.marker_t_s
        assert data.markers_xz is not None  # set together with marker_t_s
        i0 = max(int(np.searchsorted(tm, start_s, side="left")) - 1, 0)
        i1 = int(np.searchsorted(tm, end_s, side="right"))
        out.marker_t_s, out.markers_xz = tm[i0:i1], data.markers_xz[i0:i1]
    return out


def extend_past_window(span: SpanData, stances: list[Stance], k: int, options: AnalysisOptions) -> SpanData:
    """End-of-stance treatment of a short window: data synthesised for ``TAIL_S`` past its end.

    The zero-lag filters and the marker splines need data after the
    take-off; a window ending a few ms after it makes them bend the end of
    the stance (odd-extension padding mirrors the stance force below zero).
    What the data must be after the window end is known or predictable:

    - force: after a take-off the plate carries no load, so the raw wrench
      is the plate offset. The extension repeats the offset of the flight
      before the stance (its mean wrench, :func:`force_plate.flight_offsets`)
      at the force rate; the following flight's offset estimate is then that
      same baseline (the zeroing sees only synthesised samples in its
      interior) instead of the mean of the few samples the window holds.
      No flight before the stance in the window: zero offset, what the
      zeroing assumes without flights.
    - markers: from the second stance on, each marker repeats what it did
      after the previous hop's take-off, anchored to the last frames
      (:func:`_templated_markers`); for the first stance (no hop before it
      in the window), a marker without a finite template, or a previous
      flight shorter than ``TEMPLATE_MIN_S``, it is extrapolated from the
      last ``MARKER_FIT_FRAMES`` frames at or before the window end by a
      least-squares polynomial of degree ``MARKER_FIT_DEGREE`` in time, at
      the marker rate: by default the straight line through the last two
      frames (constant velocity). A marker whose last frame is missing is
      not extrapolated (its gap runs to the edge, as before).

    Measured by ``bench/low_latency_windows.py`` (36 cells of k0/k1 median
    recovery errors against batch; docs/pipeline.md "Batch vs low-latency"
    has the figures and what else was tried). The force treatment alone is
    exact (the recorded markers after the window end: 0 of 36 cells move);
    the markers are the limit: around a take-off the segment angular
    accelerations change within a few marker frames, the batch filters
    average the following flight's motion into the stance's end, and an
    extrapolation from the frames before the take-off only guesses it.

    Returns a new :class:`SpanData`; ``span`` is not changed.
    """
    t, w = span.force_t_s, span.wrench
    dt = 1.0 / sampling_rate_hz(t)
    t_ext = t[-1] + dt * np.arange(1, int(np.ceil(TAIL_S / dt)) + 1)
    baseline = _offset_of_flight_before(span, stances, k, options)
    out = SpanData(np.concatenate([t, t_ext]), np.vstack([w, np.tile(baseline, (t_ext.size, 1))]))
    if span.marker_t_s is None or len(span.marker_t_s) < 2:
        return out
    tm, xz = span.marker_t_s, span.markers_xz
    assert xz is not None  # set together with marker_t_s
    dtm = 1.0 / sampling_rate_hz(tm)  # marker frames after the last one, at the marker rate, to one frame past the end
    tm_ext = tm[-1] + dtm * np.arange(1, int(np.ceil((t_ext[-1] - tm[-1]) / dtm)) + 2)
    xz_ext = np.full((tm_ext.size,) + xz.shape[1:], np.nan)
    templated = _templated_markers(tm, xz, tm_ext, xz_ext, stances[k - 1], stances[k]) if MARKER_TEMPLATE and k > 0 else []
    _extrapolated_markers(tm, xz, tm_ext, xz_ext, [m for m in range(xz.shape[1]) if m not in templated])
    out.marker_t_s, out.markers_xz = np.concatenate([tm, tm_ext]), np.concatenate([xz, xz_ext])
    return out


def _offset_of_flight_before(span: SpanData, stances: list[Stance], k: int, options: AnalysisOptions) -> np.ndarray:
    """Raw plate wrench of the flight before stance ``k`` in ``span`` (its mean, :func:`force_plate.flight_offsets`).

    Only the stances up to ``k`` bound the flights (a later one is not known
    live). No flight before the stance in the window: zeros, what the
    zeroing assumes without flights.
    """
    t, w = span.force_t_s, span.wrench
    before = [(s.touchdown_s, s.takeoff_s) for s in stances[: k + 1]]
    flights = [f for f in flight_intervals(before, float(t[0]), float(t[-1])) if f[1] <= stances[k].touchdown_s]
    _, offsets = flight_offsets(t, w, flights, options.flight_margin_s)
    return offsets[-1] if len(offsets) else np.zeros(w.shape[1])


def _extrapolated_markers(tm: np.ndarray, xz: np.ndarray, tm_ext: np.ndarray, xz_ext: np.ndarray,
                          markers: list[int]) -> None:
    """Write ``markers``' frames at ``tm_ext`` (s, after the last frame) into ``xz_ext`` (m, shaped like ``xz``).

    Each marker goes on by the least-squares polynomial of degree
    ``MARKER_FIT_DEGREE`` in time through its last ``MARKER_FIT_FRAMES``
    frames (fewer, and a lower degree, when its last visible run is
    shorter); a marker whose last frame is missing is left as it is in
    ``xz_ext`` (NaN: its gap runs to the edge).
    """
    for m in markers:
        finite = np.all(np.isfinite(xz[:, m]), axis=1)
        if not finite[-1]:
            continue
        run = finite.size - (np.argmin(finite[::-1]) if not finite.all() else finite.size)
        last = np.arange(max(run, finite.size - MARKER_FIT_FRAMES), finite.size)
        deg = min(MARKER_FIT_DEGREE, last.size - 1)
        coef = np.polynomial.polynomial.polyfit(tm[last] - tm[-1], xz[last, m], deg)
        xz_ext[:, m] = np.polynomial.polynomial.polyval(tm_ext - tm[-1], coef).T


#: Continue the markers past a short window's end by the previous hop's motion after its take-off
#: (:func:`_templated_markers`); False: the straight line of :func:`_extrapolated_markers` only.
MARKER_TEMPLATE = True
#: Frames at the window end the template is anchored to: its offset and drift (velocity) are fitted to them.
MARKER_TEMPLATE_FRAMES = 2
#: The template stops this long before the previous flight's end (s): the landing is not part of it.
TEMPLATE_MARGIN_S = 0.01
#: Shortest previous flight (s, after the margin) worth a template; shorter: the straight line.
TEMPLATE_MIN_S = 0.02
#: The window starts this long before the previous take-off (s), so the template covers the anchor frames
#: (30 ms: two frames at 100 Hz and one spare; 80 ms gave the same 36 recovery cells and cost 0.2 ms more per stance).
TEMPLATE_LEAD_S = 0.03


def _templated_markers(tm: np.ndarray, xz: np.ndarray, tm_ext: np.ndarray, xz_ext: np.ndarray,
                       prev: Stance, cur: Stance) -> list[int]:
    """Markers past the window end continued by the previous hop's motion after its take-off.

    Writes the frames at ``tm_ext`` (s) into ``xz_ext`` (m) for the markers
    it can continue and returns their indices; the others are left to the
    straight line (:func:`_extrapolated_markers`).

    Hopping repeats itself: what each marker did after the previous
    take-off is the best guess of what it does after this one. The
    previous hop's frames (in the window: it starts ``TEMPLATE_LEAD_S``
    before the previous take-off) are splined (cubic) against the time
    from that take-off, evaluated at the same times from this take-off
    (up to the previous flight's end less ``TEMPLATE_MARGIN_S``, then on
    at the template's last velocity), and anchored to this stance's last
    ``MARKER_TEMPLATE_FRAMES`` frames by a fitted offset and drift (with 2
    frames: the last frame's position and the last two frames' velocity).
    This carries the take-off's segment accelerations, which the straight
    line (for markers without a finite template or anchor) sets to zero.
    Uses only frames at or before the window end.

    Measured (bench/low_latency_windows.py, 36 recovery cells against batch, PAD 5 ms):
    see :func:`extend_past_window`.
    """
    from scipy.interpolate import CubicSpline

    length = min(TAIL_S, cur.touchdown_s - prev.takeoff_s - TEMPLATE_MARGIN_S)
    sel = (tm >= prev.takeoff_s - TEMPLATE_LEAD_S) & (tm <= prev.takeoff_s + length + 0.03)
    n_fit = min(MARKER_TEMPLATE_FRAMES, tm.size)
    r_fit = tm[-n_fit:] - cur.takeoff_s
    if length < TEMPLATE_MIN_S or sel.sum() < 6 or r_fit[0] < tm[sel][0] - prev.takeoff_s:
        return []
    r = np.minimum(tm_ext - cur.takeoff_s, length)
    beyond = np.maximum(tm_ext - cur.takeoff_s - length, 0.0)
    anchor = np.column_stack([np.ones(n_fit), tm[-n_fit:] - tm[-1]])[:, : min(n_fit, 2)]
    ahead = np.column_stack([np.ones(tm_ext.size), tm_ext - tm[-1]])[:, : anchor.shape[1]]
    usable = [m for m in range(xz.shape[1]) if np.isfinite(xz[sel, m]).all() and np.isfinite(xz[-n_fit:, m]).all()]
    if not usable:
        return []
    spline = CubicSpline(tm[sel] - prev.takeoff_s, xz[sel][:, usable], axis=0)
    residual = xz[-n_fit:][:, usable] - spline(r_fit)  # (n_fit, markers, 2)
    coef, *_ = np.linalg.lstsq(anchor, residual.reshape(n_fit, -1), rcond=None)
    xz_ext[:, usable] = (spline(r) + beyond[:, None, None] * spline(length, 1)[None]
                         + (ahead @ coef).reshape((tm_ext.size,) + residual.shape[1:]))
    return usable


def analyze_short_window(
    data: SpanData, stances: list[Stance], k: int, model: BodyModel | None, body_mass_kg: float, options: AnalysisOptions
) -> tuple[StanceResult, SpanData]:
    """Stance ``k`` analysed on its short window (``options.post_takeoff_s``): one function live and offline.

    ``data`` may hold more than the window (the whole record offline, the
    stage's buffer live): the window is cut here (:func:`short_window`,
    :func:`window_span`), treated (:func:`extend_past_window`) and analysed
    with only the stances up to ``k`` (a later one is not known live); the
    timing fields (flight after, hop frequency) come from ``stances``.

    Returns the result and the window's data (for the message-loss check).
    """
    start, end = short_window(stances, k, options)
    span = window_span(data, start, end)
    extended = extend_past_window(span, stances, k, options)
    result = analyze_span(extended, stances[: k + 1], [k], model, body_mass_kg, options)[0]
    result.flight_before_s, result.flight_after_s, result.hop_frequency_hz = stance_timing(stances, k)
    result.data_after_takeoff_s = _post_takeoff_s(options)
    return result, span


def recording_span(rec: Recording) -> SpanData:
    """The whole recording as :class:`SpanData` (times relative to ``rec.start_ns``)."""
    if len(rec.force) < 2:
        raise ValueError(f"{rec.source or 'recording'}: needs force-plate samples on {FORCE_TOPIC}, found {len(rec.force)}")
    t0 = rec.start_ns
    data = SpanData((rec.force.stamp_ns - t0) * 1e-9, sagittal_wrench(rec.force))
    if rec.markers is not None and len(rec.markers):
        data.marker_t_s = (rec.markers.stamp_ns - t0) * 1e-9
        data.markers_xz = sagittal_markers(rec.markers)
    return data


def analyze_recording(rec: Recording, options: AnalysisOptions | None = None) -> RecordingAnalysis:
    """Stances and per-stance inverse dynamics of a whole recording.

    Parameters
    ----------
    rec : Recording
        Needs a subject (mass, height) and force-plate data; without markers
        only force-based figures are computed and the stances are rejected
        for the joint analysis with reason "no marker data".
    options : AnalysisOptions, optional

    Returns
    -------
    RecordingAnalysis
    """
    options = options or AnalysisOptions()
    if rec.subject is None:
        raise ValueError(f"{rec.source or 'recording'}: no {SUBJECT_TOPIC} message; give the subject's mass and height")
    data = recording_span(rec)
    detector = StanceDetector(options.detector, rec.subject.body_mass_kg * GRAVITY_M_S2)
    detector.push(data.force_t_s, data.wrench[:, 1])
    detector.flush()
    stances = detector.stances
    model = options.body_model
    if model is None and data.markers_xz is not None:
        assert rec.markers is not None  # data.markers_xz comes from them (recording_span)
        until = rec.start_ns + round(detector.first_takeoff_s * 1e9) if np.isfinite(detector.first_takeoff_s) else None
        calibration = calibration_markers(rec.markers, options.calibration_s, until)
        model = body_model_from_markers(rec.subject, calibration, options.overrides)
    if options.post_takeoff_s is None:
        results = analyze_span(data, stances, list(range(len(stances))), model, rec.subject.body_mass_kg, options)
        _reject_holes(results, data, options)
    else:
        windows = [analyze_short_window(data, stances, k, model, rec.subject.body_mass_kg, options) for k in range(len(stances))]
        results = [r for r, _ in windows]
        _reject_holes(results, data, options, [span for _, span in windows])
    warnings = list(rec.warnings) + detector.warnings
    return RecordingAnalysis(rec.subject, model, rec.start_ns, recording_info(rec), results, warnings, options)


#: Stamp tolerance of the calibration window's bounds (ns): the live stage works on float seconds, so a
#: frame exactly ``calibration_s`` after the first must not fall out through round-off.
CALIBRATION_TOLERANCE_NS = 1000


def calibration_markers(markers: MarkerSeries, calibration_s: float | None, until_ns: int | None = None) -> MarkerSeries:
    """The marker frames the body model is scaled from: one rule for ``analyze`` and the live stage.

    The complete frames (every contract marker visible) whose stamp lies
    within ``calibration_s`` of the first complete frame's stamp (integer
    nanoseconds, bounds included) and not after ``until_ns``, the first
    take-off the detector announced (:attr:`StanceDetector.first_takeoff_s`):
    so the model is ready when the first stance ends and the first profile is
    not held back by the calibration (issue 15: it waited ~0.4 s for the 1 s
    window). The rule depends on stamps only, so the live stage, which scales
    the model once its marker stream has passed the window, gets the same
    frames whatever the message batching (it used to take every frame that
    had arrived when it started: 115 frames in one run, 140 in another, and
    a hip k1 0.45 % away from offline). ``calibration_s`` None: no time limit.
    If the first take-off comes before the first complete frame, the window
    ignores it. No complete frame: the series unchanged (the model scaling
    then names what is missing).
    """
    complete = np.all(np.isfinite(sagittal_markers(markers)), axis=(1, 2))
    if not complete.any():
        return markers
    first = int(markers.stamp_ns[complete][0])
    keep = complete & (markers.stamp_ns >= first)
    if calibration_s is not None:
        keep &= markers.stamp_ns - first <= round(calibration_s * 1e9) + CALIBRATION_TOLERANCE_NS
    if until_ns is not None and (keep & (markers.stamp_ns <= until_ns)).any():
        keep &= markers.stamp_ns <= until_ns
    return MarkerSeries(markers.stamp_ns[keep], markers.names, markers.positions_m[keep])


def _reject_holes(results: list[StanceResult], data: SpanData, options: AnalysisOptions,
                  windows: list[SpanData] | None = None) -> None:
    """Reject stances with missing samples inside (a force gap the detector bridged), as the live stage does.

    Same rule and nominal periods (first 50 steps) as
    ``stages.StanceAnalysisStage._reject_on_loss``, so a 0.3 s force gap inside a
    stance is a rejection offline too, not a longer stance with a lower peak.
    ``windows``: each stance's short window (:func:`analyze_short_window`),
    checked instead of ``data`` as the live stage checks it.
    """
    from hop_impedance.biomech.stages import NominalPeriod, missing_samples_reason  # stages imports this module

    force_period, marker_period = NominalPeriod(), NominalPeriod()
    force_period.update(data.force_t_s)
    if data.marker_t_s is not None:
        marker_period.update(data.marker_t_s)
    for k, res in enumerate(results):
        if not res.complete:
            continue  # cut by the recording's start or end: already rejected for that
        span, end = (data, None) if windows is None else (windows[k], res.takeoff_s + _post_takeoff_s(options))
        reason = missing_samples_reason(span, res.touchdown_s, res.takeoff_s, options.max_gap_s,
                                        force_period_s=force_period.value, marker_period_s=marker_period.value,
                                        data_end_s=end)
        if reason is not None:
            res.rejection_reason = reason if res.rejection_reason is None else f"{reason}; {res.rejection_reason}"
            res.joints = None


def recording_info(rec: Recording) -> dict[str, Any]:
    """Topics, sampling rates and time span of a recording (for the JSON)."""
    t0 = rec.start_ns
    ends = [int(rec.force.stamp_ns[-1])]
    topics = {FORCE_TOPIC: {"messages": len(rec.force), "rate_hz": sampling_rate_hz((rec.force.stamp_ns - t0) * 1e-9)}}
    if rec.markers is not None and len(rec.markers) >= 2:
        topics[MARKER_TOPIC] = {"messages": len(rec.markers), "rate_hz": sampling_rate_hz((rec.markers.stamp_ns - t0) * 1e-9)}
        ends.append(int(rec.markers.stamp_ns[-1]))
    if rec.subject is not None:
        topics[SUBJECT_TOPIC] = {"messages": 1}
    end = max(ends)
    return {"source": rec.source, "topics": topics, "start_ns": int(t0), "end_ns": end, "duration_s": (end - t0) * 1e-9}
