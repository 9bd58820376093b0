"""Streaming stance detection on vertical ground reaction force.

A state machine with hysteresis runs sample by sample, so the same object
serves the live ROS node (chunks of ``(t, fz)`` as they arrive) and the batch
analysis (one call over the whole record): both give identical events.

Rules (defaults in :class:`DetectorOptions`)
---------------------------------------------
- Forces are compared with the *flight baseline*: the running mean of Fz over
  the current flight (from ``settle_s`` after take-off on), or the previous
  flight's mean while the current one is still shorter than ``settle_s``;
  0 N before the first flight. This tracks offset and drift of the plate.
- FLIGHT -> STANCE when Fz - baseline rises above ``touchdown_n`` (40 N).
- STANCE -> FLIGHT when Fz - baseline stays below ``takeoff_n`` (20 N) for
  ``min_flight_s`` (0.05 s); shorter dips are not flights. The take-off event
  is therefore emitted ``min_flight_s`` late.
- Event times are sub-sample: the linear interpolation of the instant at
  which Fz - baseline crosses ``event_level_n`` (default = ``takeoff_n``),
  the level at which "a person looking at the curve" sees the force leave zero.
- A stance shorter than ``min_stance_s`` (0.08 s) is still reported (never
  silently dropped) but carries a rejection reason.
- A recording starting with Fz - baseline above ``event_level_n`` starts in
  stance: that stance is *incomplete* (cut by the start); one still in
  progress at :meth:`StanceDetector.flush` is incomplete (cut by the end).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class DetectorOptions:
    """Thresholds of the stance state machine (N above the flight baseline, s).

    Attributes
    ----------
    touchdown_n : float
        Fz - baseline above which a touchdown is declared (N).
    takeoff_n : float
        Fz - baseline below which a take-off starts (N); lower than
        ``touchdown_n`` (hysteresis).
    event_level_n : float or None
        Level whose crossing gives the event times (N); None = ``takeoff_n``.
    min_stance_s : float
        Shorter stances are rejected ("too short").
    min_flight_s : float
        A dip below ``takeoff_n`` must last this long to count as flight (s).
    settle_s : float
        Flight samples closer than this to the take-off are not used for the
        baseline (s) (plate ringing).
    """

    touchdown_n: float = 40.0
    takeoff_n: float = 20.0
    event_level_n: float | None = None
    min_stance_s: float = 0.08
    min_flight_s: float = 0.05
    settle_s: float = 0.02

    def __post_init__(self) -> None:
        if not self.touchdown_n > self.takeoff_n > 0:
            raise ValueError(
                f"need touchdown_n > takeoff_n > 0 N (hysteresis), got {self.touchdown_n} and {self.takeoff_n}"
            )
        if self.min_flight_s < 0 or self.min_stance_s < 0 or self.settle_s < 0:
            raise ValueError("min_flight_s, min_stance_s and settle_s must be >= 0 s")

    @property
    def level_n(self) -> float:
        """Event level actually used (N)."""
        return self.takeoff_n if self.event_level_n is None else self.event_level_n


@dataclass(frozen=True)
class ContactEvent:
    """A touchdown or take-off.

    Attributes
    ----------
    kind : str
        ``"touchdown"`` or ``"takeoff"``.
    time_s : float
        Sub-sample instant (s, same clock as the input ``t``).
    baseline_n : float
        Flight baseline used for the decision (N).
    cut : bool
        True for the pseudo-events at the data edges: a take-off of a stance
        that began before the data (``kind="takeoff"`` after an implicit
        touchdown at the first sample) is flagged on its touchdown; see
        :class:`Stance`.
    """

    kind: str
    time_s: float
    baseline_n: float
    cut: bool = False


@dataclass(frozen=True)
class Stance:
    """One ground contact found by the detector.

    Attributes
    ----------
    touchdown_s, takeoff_s : float
        Event times (s); for an incomplete stance the cut side is the first or
        last sample time.
    complete : bool
        False when cut by the start or the end of the data.
    rejection_reason : str or None
        Why the stance must not be fitted (incomplete, too short, ...).
    baseline_before_n, baseline_after_n : float
        Flight baselines before and after (N); NaN when unknown.
    cut_start, cut_end : bool
        Which edge of the data cut the stance.
    """

    touchdown_s: float
    takeoff_s: float
    complete: bool
    rejection_reason: str | None = None
    baseline_before_n: float = float("nan")
    baseline_after_n: float = float("nan")
    cut_start: bool = False
    cut_end: bool = False

    @property
    def contact_time_s(self) -> float:
        """Take-off minus touchdown (s)."""
        return self.takeoff_s - self.touchdown_s


@dataclass
class _FlightStats:
    n: int = 0
    total: float = 0.0


class StanceDetector:
    """Sample-by-sample stance state machine (see the module docstring).

    Use :meth:`push` with chunks of samples as they arrive; it returns the
    :class:`ContactEvent` s found so far and collects finished :class:`Stance`
    objects in :attr:`stances`. Call :meth:`flush` at the end of the data.

    Parameters
    ----------
    options : DetectorOptions
    initial_baseline_n : float
        Baseline assumed before the first flight has been seen (N).
    """

    def __init__(self, options: DetectorOptions | None = None, initial_baseline_n: float = 0.0) -> None:
        self.options = options or DetectorOptions()
        self.stances: list[Stance] = []
        self._state: str | None = None  # None until the first sample, then "flight" / "stance"
        self._baseline = float(initial_baseline_n)
        self._prev_flight_baseline = float(initial_baseline_n)
        self._flight = _FlightStats()
        self._flight_start_s = -np.inf
        self._prev = (np.nan, np.nan)  # last sample (t, fz - baseline)
        self._touchdown_s: float | None = None
        self._touchdown_cut = False
        self._baseline_before = float("nan")
        self._dip_start: tuple[float, float] | None = None  # (crossing time, baseline) of a candidate take-off
        self._dip_samples: list[tuple[float, float]] = []
        self._last_t = np.nan
        self._first_t = np.nan
        self._pending_after: Stance | None = None  # stance waiting for the next flight's baseline
        self._rise_s: float | None = None  # last upward crossing of the event level during flight

    @property
    def in_stance(self) -> bool:
        """True while the state machine is in stance."""
        return self._state == "stance"

    @property
    def pending_stance(self) -> Stance | None:
        """The stance whose take-off is confirmed but not yet in :attr:`stances`, or None.

        A stance is appended to :attr:`stances` only at the next touchdown,
        once the following flight's baseline (``baseline_after_n``) is known;
        until then it waits here with ``baseline_after_n`` NaN. Streaming
        consumers that act at take-off (the pipeline's low-latency mode and
        its take-off events) read it from here.
        """
        return self._pending_after

    def push(self, t_s: np.ndarray, fz_n: np.ndarray) -> list[ContactEvent]:
        """Feed samples; return the events they complete.

        Parameters
        ----------
        t_s : ndarray, shape (N,)
            Sample times (s), increasing across calls.
        fz_n : ndarray, shape (N,)
            Vertical ground reaction force (N), raw (the baseline is tracked
            here). NaN samples are skipped.
        """
        t_s = np.atleast_1d(np.asarray(t_s, float))
        fz_n = np.atleast_1d(np.asarray(fz_n, float))
        if t_s.shape != fz_n.shape:
            raise ValueError(f"t_s and fz_n must have the same shape, got {t_s.shape} and {fz_n.shape}")
        events: list[ContactEvent] = []
        for t, f in zip(t_s.tolist(), fz_n.tolist()):
            if not (np.isfinite(t) and np.isfinite(f)):
                continue
            if np.isfinite(self._last_t) and t <= self._last_t:
                raise ValueError(f"time stamps must increase: {t} s after {self._last_t} s")
            self._step(t, f, events)
            self._last_t = t
        return events

    def flush(self) -> list[ContactEvent]:
        """End of data: close a stance in progress as incomplete (cut by the end)."""
        events: list[ContactEvent] = []
        if self._pending_after is not None and self._state == "flight":
            self._finish_pending(self._flight.total / self._flight.n if self._flight.n else float("nan"))
        if self._state == "stance" and self._touchdown_s is not None:
            events.append(ContactEvent("takeoff", self._last_t, self._baseline, cut=True))
            self._record_stance(self._touchdown_s, self._last_t, cut_start=self._touchdown_cut, cut_end=True)
            self._finish_pending()
            self._state = None
        return events

    # -- internals -------------------------------------------------------------

    def _step(self, t: float, f: float, events: list[ContactEvent]) -> None:
        opt = self.options
        if self._state is None:
            self._first_t = t
            if f - self._baseline >= opt.level_n:
                self._state = "stance"
                self._touchdown_s = t
                self._touchdown_cut = True
            else:
                self._enter_flight(t)
            self._prev = (t, f - self._baseline)
            return
        rel = f - self._baseline
        if self._state == "flight":
            if rel >= opt.level_n and (self._prev[1] < opt.level_n or self._rise_s is None):
                self._rise_s = self._crossing_time(t, rel)  # where the rising edge left the zero line
            elif rel < opt.level_n:
                self._rise_s = None
            if rel > opt.touchdown_n:
                td = self._rise_s if self._rise_s is not None else t
                self._rise_s = None
                self._close_flight()
                self._state = "stance"
                self._touchdown_s = td
                self._touchdown_cut = False
                self._baseline_before = self._baseline
                events.append(ContactEvent("touchdown", td, self._baseline))
            elif rel < opt.level_n:  # the rising edge of a touchdown must not bias the baseline
                self._update_flight_baseline(t, f)
                rel = f - self._baseline
        else:  # stance
            if self._dip_start is None:
                if rel < opt.takeoff_n:
                    self._dip_start = (self._crossing_time(t, rel), self._baseline)
                    self._dip_samples = [(t, f)]
            elif rel > opt.touchdown_n:
                self._dip_start = None  # a short dip: still in stance
                self._dip_samples = []
            else:
                self._dip_samples.append((t, f))
                if t - self._dip_start[0] >= opt.min_flight_s:
                    to = self._dip_start[0]
                    events.append(ContactEvent("takeoff", to, self._dip_start[1]))
                    self._record_stance(self._touchdown_s, to, cut_start=self._touchdown_cut, cut_end=False)
                    self._enter_flight(to)
                    for ts, fs in self._dip_samples:
                        self._update_flight_baseline(ts, fs)
                    self._dip_start = None
                    self._dip_samples = []
                    rel = f - self._baseline
        self._prev = (t, rel)

    def _crossing_time(self, t: float, rel: float) -> float:
        """Instant at which Fz - baseline crossed the event level between the previous sample and this one.

        Linear interpolation between the two samples; ``t`` itself if they do
        not bracket the level.
        """
        level = self.options.level_n
        t0, r0 = self._prev
        if np.isfinite(t0) and (r0 - level) * (rel - level) <= 0 and r0 != rel:
            return float(t0 + (level - r0) / (rel - r0) * (t - t0))
        return t

    def _enter_flight(self, t: float) -> None:
        self._state = "flight"
        self._flight = _FlightStats()
        self._flight_start_s = t

    def _update_flight_baseline(self, t: float, f: float) -> None:
        if t - self._flight_start_s < self.options.settle_s:
            return
        self._flight.n += 1
        self._flight.total += f
        if t - self._flight_start_s >= 2 * self.options.settle_s:
            self._baseline = self._flight.total / self._flight.n

    def _close_flight(self) -> None:
        if self._flight.n:
            self._prev_flight_baseline = self._flight.total / self._flight.n
        if self._pending_after is not None:
            self._finish_pending(self._prev_flight_baseline)

    def _finish_pending(self, after: float = float("nan")) -> None:
        if self._pending_after is not None:
            s = self._pending_after
            self.stances.append(replace(s, baseline_after_n=after))
            self._pending_after = None

    def _record_stance(self, td: float, to: float, cut_start: bool, cut_end: bool) -> None:
        reason = None
        if cut_start:
            reason = "incomplete: cut by start of recording"
        elif cut_end:
            reason = "incomplete: cut by end of recording"
        elif to - td < self.options.min_stance_s:
            reason = f"too short: {to - td:.3f} s < {self.options.min_stance_s:.3f} s"
        self._pending_after = Stance(
            td,
            to,
            not (cut_start or cut_end),
            reason,
            float("nan") if cut_start else self._baseline_before,
            cut_start=cut_start,
            cut_end=cut_end,
        )


def detect_stances(t_s: np.ndarray, fz_n: np.ndarray, options: DetectorOptions | None = None) -> list[Stance]:
    """Batch wrapper: run :class:`StanceDetector` over a whole record.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Sample times (s).
    fz_n : ndarray, shape (N,)
        Raw vertical ground reaction force (N).

    Returns
    -------
    list of Stance
        In time order, complete and incomplete ones.
    """
    det = StanceDetector(options)
    det.push(t_s, fz_n)
    det.flush()
    return det.stances
