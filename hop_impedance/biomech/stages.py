"""Streaming stages: the same science as :func:`analysis.analyze_recording`, fed chunk by chunk.

Every stage has ``push(...) -> list[outputs]`` and ``flush() -> list[outputs]``.
Times are seconds on the recording's clock (``(stamp_ns - start_ns) * 1e-9``).

Agreement with the batch analysis
---------------------------------
- Events and stances are *identical*: the detector is the same
  sample-by-sample state machine in both cases.
- Per-stance results come from :func:`analysis.analyze_span` run on a window
  from ``min(touchdown - pad_s, previous take-off)`` to
  ``max(take-off + pad_s, next touchdown)``, i.e. the stance, both
  neighbouring flights (so the plate offsets are the same as in batch), and
  at least ``pad_s`` (default 0.3 s) of data on each side. The batch run
  filters the whole record; the zero-lag filters' edge transients decay with
  a time constant of about 1 / (2 pi f_c) = 13 ms at 12 Hz, so after 0.3 s
  they are below 1e-6 of the signal step at the window edge. The remaining
  difference comes from the cubic splines (whose end effects decay by a
  factor ~0.27 per marker sample) and is far below 1e-6 of the peak moment;
  the tests assert 1e-4 of the peak moment per joint.
- A stance is emitted once the window's data have arrived (and the next
  touchdown is known); so the latency is one flight plus ``pad_s``. The last
  stance is emitted by :meth:`StanceAnalysisStage.flush`, with a window
  reaching the end of the data (so its trailing flight's offset is the
  batch one).

Low-latency mode (``post_pad_s`` given)
---------------------------------------
The window ends ``post_pad_s`` after take-off instead of at the next
touchdown, so a stance is emitted as soon as the take-off is *announced*
(the detector's provisional take-off, ``provisional_s`` = 5 ms below the
level) and the data reach ``takeoff + post_pad_s``: the force samples, and
the marker stream up to its last frame stamped at or before the window's end
(known complete once the next frame, one nominal period on, would lie
beyond the end; no frame past the end is waited for or used). If the
detector withdraws the take-off (the force came back within
``min_flight_s``), the stage emits a :data:`WITHDRAWN` result for that
stance (no joint data) and analyses it again at its real take-off. Each
stance is analysed by :func:`analysis.analyze_short_window`, the function
``analyze`` runs with ``AnalysisOptions.post_takeoff_s`` set (same window,
same end-of-stance treatment: force continued with the flight baseline,
markers extrapolated), so live and offline results are equal
(test/biomech/test_short_windows.py). Differences from batch are at the end
of the stance, where the zero-lag filters and splines need the motion after
the window's end (figures in docs/pipeline.md, "Batch vs low-latency").

Message loss
------------
A stance whose window has a hole in the force samples (a step longer than
1.5 force periods, i.e. at least one sample lost) or in the marker frames
(a step longer than ``max_gap_s`` + one frame) is still emitted with its
force-based figures, but its joint data are dropped and the rejection
reason names the number of missing samples; it is never silently analysed
on incomplete data. Periods are the streams' nominal ones, from their first
50 time steps (:class:`NominalPeriod`), not the window's median step, which
loss spread over the whole window turns into a gap.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hop_impedance.biomech.analysis import (
    AnalysisOptions,
    SpanData,
    StanceResult,
    analyze_short_window,
    analyze_span,
    calibration_markers,
    short_window,
)
from hop_impedance.biomech.body_model import BodyModel, body_model_from_stature
from hop_impedance.biomech.kinematics import body_model_from_markers
from hop_impedance.biomech.stance_detection import ContactEvent, DetectorOptions, Stance, StanceDetector
from hop_impedance.recording import GRAVITY_M_S2, MARKER_NAMES, MarkerSeries, Subject

#: Rejection reason of a stance whose provisional take-off was withdrawn (its earlier result is void).
WITHDRAWN = "take-off withdrawn"


class StanceDetectorStage:
    """Contact events from chunks of vertical force (what the ``stance_detector`` node wraps).

    ``push((t_s, fz_n))`` returns the :class:`ContactEvent` s completed by the
    chunk; finished :class:`Stance` objects accumulate in :attr:`stances`.
    """

    def __init__(self, options: DetectorOptions | None = None, body_weight_n: float | None = None) -> None:
        self.detector = StanceDetector(options, body_weight_n)

    @property
    def stances(self) -> list[Stance]:
        """Stances finished so far (each appended once the following flight is known)."""
        return self.detector.stances

    def push(self, samples: tuple[np.ndarray, np.ndarray]) -> list[ContactEvent]:
        """Feed ``(t_s, fz_n)``, two arrays of shape (n,)."""
        t_s, fz_n = samples
        return self.detector.push(t_s, fz_n)

    def flush(self) -> list[ContactEvent]:
        """End of stream."""
        return self.detector.flush()


class StanceAnalysisStage:
    """Per-stance kinematics, inverse dynamics and metrics from streamed force and markers.

    Parameters
    ----------
    model : BodyModel or None
        Body model (from a calibration or from :func:`kinematics.body_model_from_markers`);
        None for force-only streams.
    body_mass_kg : float
    options : AnalysisOptions, optional
    post_pad_s : float or None
        None (default): ``options.post_takeoff_s``, None there too gives
        batch-identical results (window up to the next touchdown); a value
        selects the low-latency mode (module docstring) and is the options'
        ``post_takeoff_s`` from then on.
    subject : Subject, optional
        With ``model`` None: scale the body model from the streamed markers by
        the rule ``analyze`` uses (:func:`analysis.calibration_markers`: the
        complete frames within ``calibration_s`` of the first and not after
        the first announced take-off), as soon as the marker stream has passed
        that window; stances wait for it. Without any marker frame after
        ``2 calibration_s`` of force (or at the end), the stream is force-only
        (stances without joint data, as offline). :attr:`notes` says what
        happened, one line each (for a log).
    """

    def __init__(
        self,
        model: BodyModel | None,
        body_mass_kg: float,
        options: AnalysisOptions | None = None,
        post_pad_s: float | None = None,
        subject: Subject | None = None,
    ) -> None:
        if post_pad_s is not None and not post_pad_s > 0:
            raise ValueError(f"post_pad_s must be > 0 s (or None for batch mode), got {post_pad_s}")
        self.options = options or AnalysisOptions()
        if post_pad_s is None:
            post_pad_s = self.options.post_takeoff_s
        else:  # one pad for the windows and analyze's short-window treatment
            self.options = replace(self.options, post_takeoff_s=post_pad_s)
        self.post_pad_s = post_pad_s
        self.model = model
        self.body_mass_kg = float(body_mass_kg)
        self.detector = StanceDetector(self.options.detector, self.body_mass_kg * GRAVITY_M_S2)
        self._force_t: list[np.ndarray] = []
        self._wrench: list[np.ndarray] = []
        self._marker_t: list[np.ndarray] = []
        self._markers: list[np.ndarray] = []
        self._last_touchdown_s = np.nan
        self._next = 0  # index of the next stance to emit
        self._force_period = NominalPeriod()
        self._marker_period = NominalPeriod()
        self.subject = subject
        self.calibrating = model is None and subject is not None
        self.notes: list[str] = []
        self._provisional_out: Stance | None = None  # an emitted stance whose take-off is provisional
        self._warmed = False  # the short-window analysis has run once (:meth:`_warm_up`)

    def push(
        self,
        force: tuple[np.ndarray, np.ndarray] | None = None,
        markers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> list[StanceResult]:
        """Feed a chunk and return the stances it completes.

        Parameters
        ----------
        force : (t_s, wrench), optional
            Times (n,) (s) and raw sagittal wrench (n, 3) ``[Fx, Fz, Mo]``.
        markers : (t_s, xz), optional
            Times (m,) (s) and sagittal markers (m, 6, 2) in contract order.
        """
        if markers is not None and len(markers[0]):
            self._marker_t.append(np.asarray(markers[0], float))
            self._markers.append(np.asarray(markers[1], float))
            self._marker_period.update(self._marker_t[-1])
        if force is not None and len(force[0]):
            t, w = np.asarray(force[0], float), np.asarray(force[1], float)
            self._force_t.append(t)
            self._force_period.update(t)
            self._wrench.append(w)
            for ev in self.detector.push(t, w[:, 1]):
                if ev.kind == "touchdown":
                    self._last_touchdown_s = ev.time_s
        if self.calibrating:
            self._calibrate(final=False)
        if not self._warmed and np.isfinite(self._last_touchdown_s):
            self._warm_up()
        return self._withdrawn() + self._emit_ready(final=False)

    def _warm_up(self) -> None:
        """Run the short-window analysis once, thrown away, at the first touchdown (low-latency mode only).

        The first call of the filters, splines and inverse dynamics in a process costs ~10 ms
        more than the later ones (first use of scipy's and numpy's code paths); done here, in
        the first stance (150-450 ms before its take-off), it is off the path from that take-off
        to the controller. Two made-up stances laid over the data before the touchdown (a flight
        or quiet standing: any data run the same code) and the stature's de Leva model when the
        markers' one is not scaled yet; nothing of it is kept.
        """
        self._warmed = True
        if self.post_pad_s is None or not self._marker_t or self.subject is None:
            return
        data = self._span(-np.inf, self._last_touchdown_s)
        if data.marker_t_s is None or data.force_t_s.size < 2:
            return
        a, length = float(data.force_t_s[0]), float(data.force_t_s[-1] - data.force_t_s[0])
        if length < WARM_UP_MIN_S:
            return
        fake = [Stance(a + 0.1 * length, a + 0.35 * length, True), Stance(a + 0.5 * length, a + 0.85 * length, True)]
        model = self.model or body_model_from_stature(self.subject)
        try:
            analyze_short_window(data, fake, 1, model, self.body_mass_kg, self.options)
        except (ValueError, ArithmeticError, IndexError, np.linalg.LinAlgError) as exc:  # a warm-up never stops the stream
            self.notes.append(f"warm-up analysis skipped: {exc}")

    def flush(self) -> list[StanceResult]:
        """End of stream: emit every remaining stance with the data available."""
        self.detector.flush()
        if self.calibrating:
            self._calibrate(final=True)
        return self._withdrawn() + self._emit_ready(final=True)

    # -- body model ------------------------------------------------------------

    def _calibrate(self, final: bool) -> None:
        """Scale the body model once the markers of the calibration window are all in (see ``subject``)."""
        cal_s = self.options.calibration_s
        if not self._marker_t:
            span = float(self._force_t[-1][-1] - self._force_t[0][0]) if self._force_t else 0.0
            if final or span >= 2 * (cal_s or 1.0):
                self.calibrating = False
                self.notes.append("no marker data: force-only, stances without joint data")
            return
        t = np.concatenate(self._marker_t)
        xz = np.concatenate(self._markers)
        complete = np.all(np.isfinite(xz), axis=(1, 2))
        if not final:
            if not complete.any():
                return
            first = float(t[complete][0])
            end = first + cal_s if cal_s is not None else np.inf
            takeoff = self.detector.first_takeoff_s
            if np.isfinite(takeoff) and takeoff >= first:
                end = min(end, takeoff)
            if not self._markers_complete_to(end):
                return
        self.calibrating = False
        positions = np.zeros(xz.shape[:2] + (3,))
        positions[:, :, 0], positions[:, :, 2] = xz[:, :, 0], xz[:, :, 1]
        takeoff = self.detector.first_takeoff_s
        until = round(takeoff * 1e9) if np.isfinite(takeoff) else None
        frames = calibration_markers(MarkerSeries(np.round(t * 1e9).astype(np.int64), MARKER_NAMES, positions), cal_s, until)
        assert self.subject is not None  # calibrating is set only with a subject (__init__)
        try:
            self.model = body_model_from_markers(self.subject, frames, self.options.overrides)
        except ValueError as exc:
            self.notes.append(f"body model: {exc}")
            return
        span_s = (frames.stamp_ns[-1] - frames.stamp_ns[0]) * 1e-9
        self.notes.append(f"body model scaled from {len(frames)} marker frames ({span_s:.2f} s)")

    def _markers_complete_to(self, end_s: float) -> bool:
        """Every marker frame stamped at or before ``end_s`` is in (the stream is stamp-sorted).

        True once a frame beyond ``end_s`` arrived, or, with the stream's
        nominal period known, once the next frame would be stamped beyond it.
        """
        last = float(self._marker_t[-1][-1])
        period = self._marker_period.value
        return last > end_s or (period is not None and last + period > end_s + 0.25 * period)

    # -- withdrawals -----------------------------------------------------------

    def _withdrawn(self) -> list[StanceResult]:
        """A :data:`WITHDRAWN` result for an emitted stance whose provisional take-off the detector withdrew."""
        out = self._provisional_out
        if out is None:
            return []
        k = self._next - 1
        confirmed = self._final_stances(provisional=False)
        if len(confirmed) > k and confirmed[k].takeoff_s == out.takeoff_s:
            self._provisional_out = None  # confirmed: the emitted result stands
            return []
        now = self.detector.provisional_stance
        if now is not None and now.takeoff_s == out.takeoff_s:
            return []  # still provisional
        self._provisional_out = None
        self._next = k
        return [StanceResult(k, out.touchdown_s, out.takeoff_s, out.complete,
                             f"{WITHDRAWN}: the force came back within min_flight_s "
                             f"({self.options.detector.min_flight_s:g} s) of the announced take-off, the stance goes on",
                             out.contact_time_s, float("nan"), float("nan"), None, None, None)]

    # -- internals -------------------------------------------------------------

    def _final_stances(self, provisional: bool = True) -> list[Stance]:
        """Stances whose take-off is known.

        The detector appends a stance to ``stances`` only at the next
        touchdown (its trailing flight baseline is then known); in
        low-latency mode the stance waiting for that (``pending_stance``)
        counts as final from its confirmed take-off on, and (``provisional``)
        one whose take-off is only announced from the announcement on.
        """
        stances = list(self.detector.stances)
        if self.post_pad_s is None:
            return stances
        pending = pending_stance(self.detector)
        if pending is not None:
            stances.append(pending)
        elif provisional and self.detector.provisional_stance is not None:
            stances.append(self.detector.provisional_stance)
        return stances

    def _known_stances(self) -> list[Stance]:
        """Final stances plus, if in stance now, a provisional one (for neighbours' timing)."""
        stances = self._final_stances()
        if np.isfinite(self._last_touchdown_s) and (not stances or self._last_touchdown_s > stances[-1].takeoff_s):
            t_end = float(self._force_t[-1][-1]) if self._force_t else self._last_touchdown_s
            stances.append(Stance(self._last_touchdown_s, max(t_end, self._last_touchdown_s), False))
        return stances

    def _window(self, stances: list[Stance], k: int) -> tuple[float, float]:
        if self.post_pad_s is not None:
            return short_window(stances, k, self.options)
        s, pad = stances[k], self.options.pad_s
        start = s.touchdown_s - pad
        if k > 0:
            start = min(start, stances[k - 1].takeoff_s)
        end = s.takeoff_s + pad
        if k + 1 < len(stances):
            end = max(end, stances[k + 1].touchdown_s)
        return start, end

    def _emit_ready(self, final: bool) -> list[StanceResult]:
        out: list[StanceResult] = []
        if not self._force_t or self.calibrating:
            return out
        stances = self._known_stances()
        n_final = len(self._final_stances())
        while self._next < n_final:
            k = self._next
            start, end = self._window(stances, k)
            if not final and not self._data_reach(end):
                break
            if final and k + 1 >= len(stances) and self.post_pad_s is None:
                end = np.inf  # the last flight runs to the end of the data, as in batch
            if self.post_pad_s is not None:  # the function analyze runs; it cuts the same window from the buffer
                result, data = analyze_short_window(self._span(start - 0.1, end), stances, k, self.model,
                                                    self.body_mass_kg, self.options)
            else:
                data = self._span(start, end)
                result = analyze_span(data, stances, [k], self.model, self.body_mass_kg, self.options)[0]
            out.append(self._reject_on_loss(result, data, end))
            self._next += 1
            provisional = self.detector.provisional_stance
            if provisional is not None and stances[k] is provisional:
                self._provisional_out = provisional
        self._trim(stances)
        return out

    def _reject_on_loss(self, result: StanceResult, data: SpanData, end_s: float) -> StanceResult:
        """Drop the joint data of a stance whose samples have holes (see Message loss).

        Loss is named first even when the analysis already rejected the stance
        for a reason the loss caused (e.g. too few force samples left in it).
        """
        reason = missing_samples_reason(
            data, result.touchdown_s, result.takeoff_s, self.options.max_gap_s,
            force_period_s=self._force_period.value, marker_period_s=self._marker_period.value,
            data_end_s=end_s if self.post_pad_s is not None else None,
        )
        if reason is not None:
            earlier = result.rejection_reason
            result.rejection_reason = reason if earlier is None else f"{reason}; {earlier}"
            result.joints = None
        return result

    def _data_reach(self, end_s: float) -> bool:
        force_ok = self._force_t[-1][-1] >= end_s
        if self.model is None or not self._marker_t:
            return bool(force_ok)
        if self.post_pad_s is not None:  # markers up to the window's end, none beyond (module docstring)
            return bool(force_ok and self._markers_complete_to(end_s))
        # One marker frame beyond the window so the spline is interpolating, not extrapolating.
        return bool(force_ok and self._marker_t[-1][-1] > end_s)

    def _span(self, start_s: float, end_s: float) -> SpanData:
        t = np.concatenate(self._force_t)
        w = np.concatenate(self._wrench)
        sel = (t >= start_s) & (t <= end_s)
        data = SpanData(t[sel], w[sel])
        if self._marker_t:
            tm = np.concatenate(self._marker_t)
            xz = np.concatenate(self._markers)
            dt = float(np.median(np.diff(tm))) if tm.size > 1 else 0.0
            # low-latency: no frame after the window's end (it may or may not have arrived yet)
            msel = (tm >= start_s - dt) & (tm <= end_s + (dt if self.post_pad_s is None else 0.0))
            data.marker_t_s, data.markers_xz = tm[msel], xz[msel]
        return data

    def _trim(self, stances: list[Stance]) -> None:
        """Drop data no future window can need."""
        if self._next < len(stances):
            keep_from = self._window(stances, self._next)[0] - 0.1
        elif stances:
            keep_from = stances[-1].takeoff_s - self.options.pad_s - 0.1
        else:
            keep_from = float(self._force_t[-1][-1]) - 10.0
        if self._provisional_out is not None and self._next - 1 < len(stances):  # may be withdrawn and redone
            keep_from = min(keep_from, self._window(stances, self._next - 1)[0] - 0.1)
        if self.calibrating:
            return  # every marker frame may still be in the calibration window
        for ts, vs in ((self._force_t, self._wrench), (self._marker_t, self._markers)):
            if ts:
                t = np.concatenate(ts)
                v = np.concatenate(vs)
                sel = t >= keep_from
                ts[:] = [t[sel]]
                vs[:] = [v[sel]]


#: Least data before the first touchdown (s) that :meth:`StanceAnalysisStage._warm_up` lays its two stances over.
WARM_UP_MIN_S = 0.2


def pending_stance(detector: StanceDetector) -> Stance | None:
    """The stance whose take-off is confirmed but not yet in ``detector.stances``, or None.

    :class:`StanceDetector` keeps it aside until the next touchdown (to fill
    ``baseline_after_n``); this is :attr:`StanceDetector.pending_stance`.
    """
    return detector.pending_stance


#: Time steps at the start of a stream that set its nominal sampling period.
NOMINAL_PERIOD_STEPS = 50


class NominalPeriod:
    """Sampling period of a stream, from its first :data:`NOMINAL_PERIOD_STEPS` time steps (s).

    A window's own median step is no estimate once most of its messages are
    lost (at 500x replay 195 of ~200 force samples of a stance went missing,
    the window's median step was then a gap and the holes went unseen). The
    stream's start, before any overload, gives the nominal period, as the
    node's input tracker does (nodes/common.py).
    """

    def __init__(self) -> None:
        self._steps: list[float] = []
        self._last_t: float | np.integer | None = None
        #: The nominal period (s), or None until enough steps were seen.
        self.value: float | None = None

    def update(self, t_s: np.ndarray) -> None:
        """Take the steps of a chunk of increasing times ``t_s`` (s) until the period is known.

        Any unit works: integer nanosecond stamps stay integers (the node's
        reorder buffer, :class:`hop_impedance.nodes.common.ReorderBuffer`, passes
        them; a float64 of an epoch stamp in ns would lose ~100 ns).
        """
        if self.value is not None or len(t_s) == 0:
            return
        t = np.asarray(t_s) if self._last_t is None else np.concatenate([[self._last_t], t_s])
        if t.dtype.kind not in "iu":
            t = t.astype(float)
        self._steps.extend(float(v) for v in np.diff(t) if v > 0)
        self._last_t = t[-1]
        if len(self._steps) >= NOMINAL_PERIOD_STEPS:
            self.value = float(np.median(self._steps[:NOMINAL_PERIOD_STEPS]))
            self._steps = []


def missing_samples_reason(
    data: SpanData,
    touchdown_s: float,
    takeoff_s: float,
    max_gap_s: float,
    force_period_s: float | None = None,
    marker_period_s: float | None = None,
    data_end_s: float | None = None,
) -> str | None:
    """Why a stance's data have holes from lost messages, or None.

    Parameters
    ----------
    data : SpanData
        The stance's window (force times (N,) s; marker times (M,) s or None).
    touchdown_s, takeoff_s : float
        Stance events (s, same clock).
    max_gap_s : float
        Longest marker-frame gap the kinematics bridges (s).
    force_period_s, marker_period_s : float, optional
        Nominal sampling periods (s) of the streams (:class:`NominalPeriod`);
        default: the median step of the window, which heavy loss inflates.
    data_end_s : float, optional
        End of a short window (s): marker frames are expected only up to it
        (the last one may be up to one frame period before it).

    Returns
    -------
    str or None
        Names the stream and the number of missing samples, e.g.
        ``"3 force samples lost in stance (message loss)"``.

    Notes
    -----
    Force: steps longer than 1.5 x the median sampling period inside
    ``[touchdown, take-off]``; each counts ``round(step / period) - 1``
    samples. Markers: steps longer than ``max_gap_s`` + one frame period in
    the same interval extended by one frame on each side.
    """
    reason = _hole_reason(data.force_t_s, touchdown_s, takeoff_s, 1.5, 0.0, "force", force_period_s)
    if reason is None and data.marker_t_s is not None and len(data.marker_t_s) > 2:
        dt = marker_period_s or float(np.median(np.diff(data.marker_t_s)))
        end = takeoff_s + dt if data_end_s is None else min(takeoff_s + dt, data_end_s)
        reason = _hole_reason(data.marker_t_s, touchdown_s - dt, end, 1.0, max_gap_s, "marker", marker_period_s)
    return reason


def _hole_reason(
    t: np.ndarray, t0: float, t1: float, factor: float, extra_s: float, name: str, period_s: float | None
) -> str | None:
    if t.size < 3:
        return None
    period = period_s or float(np.median(np.diff(t)))
    inside = t[(t >= t0 - period) & (t <= t1 + period)]
    steps = np.diff(inside)
    holes = steps[steps > factor * period + extra_s]
    if inside.size == 0 or inside[0] > t0 + period or inside[-1] < t1 - period:
        return f"{name} samples missing at the stance edge (message loss)"
    if holes.size == 0:
        return None
    lost = int(np.sum(np.round(holes / period) - 1))
    return f"{max(lost, 1)} {name} samples lost in stance (message loss)"


def equivalent_linear_impedance(
    angle_rad: np.ndarray, angular_velocity_rad_s: np.ndarray, moment_nm: np.ndarray
) -> tuple[float, float, float]:
    """Linear impedance ``tau = k (rho - theta_eq) + b omega`` fitted to one joint's stance.

    The law finite-state impedance controllers of prostheses use (one
    stiffness, damping and equilibrium angle per phase).

    Parameters
    ----------
    angle_rad : ndarray, shape (n,)
        Joint angle rho (rad, increases with flexion).
    angular_velocity_rad_s : ndarray, shape (n,)
        d(rho)/dt (rad/s).
    moment_nm : ndarray, shape (n,)
        Net joint moment (N m, extensor positive, both legs lumped).

    Returns
    -------
    stiffness_nm_per_rad, damping_nms_per_rad, equilibrium_angle_rad : float
        Ordinary least squares (``scipy.linalg.lstsq``) of ``tau`` on
        ``[rho, omega, 1]``; ``theta_eq = -intercept / k``. NaN when fewer
        than 3 finite samples or a singular design (flat angle).
    """
    from scipy.linalg import lstsq

    rho, omega, tau = (np.asarray(a, float) for a in (angle_rad, angular_velocity_rad_s, moment_nm))
    ok = np.isfinite(rho) & np.isfinite(omega) & np.isfinite(tau)
    nan3 = (float("nan"),) * 3
    if np.count_nonzero(ok) < 3 or np.ptp(rho[ok]) <= 0:
        return nan3
    design = np.column_stack([rho[ok], omega[ok], np.ones(np.count_nonzero(ok))])
    coef, _, rank, _ = lstsq(design, tau[ok])
    if rank < 3 or coef[0] == 0:
        return nan3
    k, b, c = (float(v) for v in coef)
    return k, b, -c / k
