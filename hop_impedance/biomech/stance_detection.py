"""Streaming stance detection on vertical ground reaction force.

A state machine with hysteresis runs sample by sample, so the same object
serves the live ROS node (chunks of ``(t, fz)`` as they arrive) and the batch
analysis (one call over the whole record): both give identical events.

Rules (defaults in :class:`DetectorOptions`, the one place they are set)
------------------------------------------------------------------------
- **Flight baseline from the data.** Forces are compared with the flight
  baseline: the running mean of Fz over the current flight (from
  ``settle_s`` after take-off on), or the previous flight's mean while the
  current one is still shorter than ``2 settle_s``. Nothing assumes that the
  plate reads zero: a recording whose first sample is below
  ``start_flight_max_n`` (100 N, or ``start_flight_max_bw`` = 0.25 body
  weights if larger) starts in flight and its baseline is the mean of the
  samples from the first one on; above it, the recording starts in stance
  (cut by the start) with a prior baseline of 0 N until the first flight.
  Offset and drift of the plate are followed flight by flight.
- **Thresholds relative to body weight, with absolute floors and a noise
  floor.** Touchdown when Fz - baseline rises above
  ``max(touchdown_n, touchdown_bw * BW, 2 * noise_factor * sd)``; take-off
  candidate when it falls below ``max(takeoff_n, takeoff_bw * BW,
  noise_factor * sd)``, where BW is the body weight (N) when known and sd the
  SD of the plate in flight (measured in the flights seen so far). Defaults
  3 % / 6 % of body weight, floors 10 N / 20 N, noise factor 4: 20.6 / 41 N
  for a 70 kg subject (the former fixed 20 / 40 N), 10 / 20 N for a 30 kg
  child (floors; 8.8 / 17.6 N would be 3 % / 6 %), 20 / 40 N with a plate
  noise of 5 N SD whatever the mass.
- FLIGHT -> STANCE when Fz - baseline rises above the touchdown level.
- STANCE -> FLIGHT when Fz - baseline stays below the take-off level for
  ``min_flight_s`` (0.05 s); shorter dips are not flights. The take-off event
  is therefore emitted ``min_flight_s`` late.
- **Provisional take-off.** Once the force has stayed below the take-off
  level for ``provisional_s`` (5 ms), a ``takeoff_provisional`` event is
  emitted at once, with the same (interpolated) take-off instant the
  confirmed event will carry, and :attr:`StanceDetector.provisional_stance`
  holds the stance it ends. If the force rises above the touchdown level
  again before ``min_flight_s`` (a dip, not a flight), a ``takeoff_withdrawn``
  event says so and the stance goes on. Consumers that act at take-off (the
  controller feed, issue 15) analyse the provisional stance and withdraw
  what they published on a withdrawal; the stances themselves (and so the
  offline analysis) are those of the confirmed take-offs only.
- **Detector failure.** A "stance" longer than ``max_stance_s`` (1.0 s; a
  hopping or drop-jump contact lasts 0.15-0.8 s) whose force over the last
  ``steady_s`` (0.1 s) is steady (SD below ``max(steady_sd_n, 3 sd)``) and far
  from body weight (mean more than ``standing_tolerance_bw`` = 0.25 BW away
  from 1 BW; without a body weight: mean below ``start_flight_max_n``) is not
  a stance but a flight the baseline was wrong for (an unzeroed plate, an
  offset step): the baseline is re-estimated as that window's mean and the
  samples since the false touchdown (or the start of the recording) are run
  again with it, so the hops inside are found; a warning says so
  (:attr:`StanceDetector.warnings`). Steady force *near* body weight is
  quiet standing (before or after hopping, as in a countermovement jump):
  a long stance, not a failure. The re-run is a loop over a queue of
  samples (no recursion), and a "failure" whose steady level is already
  within the take-off level of the baseline is none (a re-run would repeat
  itself).
- **Message loss.** Samples missing inside a stance for longer than
  ``min_flight_s`` could hide a whole flight (and the next touchdown), so
  the stance is never bridged over such a gap: it ends at the last sample
  before the gap, rejected as "incomplete: cut by message loss", and the
  first sample after the gap starts afresh with the same baseline (in
  flight, or in a stance that is cut at its start by the loss). Two stances
  therefore never merge into one row, however much is lost (issue 14: at
  50x replay two hops used to come out as one 1.31 s contact). Shorter
  gaps cannot hide a flight; the stance is kept and the analysis rejects it
  for its lost samples (:func:`hop_impedance.biomech.stages.missing_samples_reason`,
  "... (message loss)"). Either way the failure test's clock restarts after
  the gap, so a gap is never read as a long steady stance (a 1 s gap inside
  a stance used to recurse without end here).
- Event times are sub-sample: the linear interpolation of the instant at
  which Fz - baseline crosses ``event_level_n`` (default = the take-off
  level), the level at which "a person looking at the curve" sees the force
  leave zero.
- A stance shorter than ``min_stance_s`` (0.08 s) is still reported (never
  silently dropped) but carries a rejection reason.
- A recording starting in stance: that stance is *incomplete* (cut by the
  start); so is a stance whose touchdown comes before the initial flight
  lasted ``settle_s`` (no baseline yet); one still in progress at
  :meth:`StanceDetector.flush` is incomplete (cut by the end).
"""

from __future__ import annotations

import collections
from dataclasses import dataclass, fields, replace

import numpy as np


@dataclass(frozen=True)
class DetectorOptions:
    """Thresholds of the stance state machine (N above the flight baseline, s).

    The defaults here are the only ones: ``analyze``, the streaming stages,
    the ``stance_detector`` and ``inverse_dynamics`` nodes and
    ``config/pipeline.yaml`` read them (see :func:`detector_options`).

    Attributes
    ----------
    touchdown_n, takeoff_n : float
        Absolute floors of the touchdown / take-off levels (N above the
        flight baseline); ``touchdown_n > takeoff_n > 0`` (hysteresis).
    touchdown_bw, takeoff_bw : float
        Levels as fractions of body weight, used when the body weight is
        known (the larger of floor, fraction and noise term applies).
    noise_factor : float
        Take-off level at least this many flight-noise SDs (touchdown twice as
        many).
    event_level_n : float or None
        Level whose crossing gives the event times (N); None = the take-off level.
    min_stance_s : float
        Shorter stances are rejected ("too short").
    min_flight_s : float
        A dip below the take-off level must last this long to count as flight (s).
    provisional_s : float
        After this long below the take-off level a take-off is announced
        provisionally (s, at most ``min_flight_s``); withdrawn if the force
        comes back within ``min_flight_s``.
    settle_s : float
        Flight samples closer than this to the take-off are not used for the
        baseline (s) (plate ringing).
    max_stance_s : float
        Physiological bound on a hopping contact (s); longer "stances" with a
        steady force far from body weight are detector failures.
    steady_s : float
        Window over which a long stance's force is tested for steadiness (s).
    steady_sd_n : float
        Floor of the steadiness SD limit (N).
    standing_tolerance_bw : float
        Steady force within this many body weights of 1 BW is quiet standing.
    start_flight_max_n, start_flight_max_bw : float
        A recording whose first sample is below the larger of these (N, body
        weights) starts in flight.
    """

    touchdown_n: float = 20.0
    takeoff_n: float = 10.0
    touchdown_bw: float = 0.06
    takeoff_bw: float = 0.03
    noise_factor: float = 4.0
    event_level_n: float | None = None
    min_stance_s: float = 0.08
    min_flight_s: float = 0.05
    provisional_s: float = 0.005
    settle_s: float = 0.02
    max_stance_s: float = 1.0
    steady_s: float = 0.1
    steady_sd_n: float = 10.0
    standing_tolerance_bw: float = 0.25
    start_flight_max_n: float = 100.0
    start_flight_max_bw: float = 0.25

    def __post_init__(self) -> None:
        if not self.touchdown_n > self.takeoff_n > 0:
            raise ValueError(
                f"need touchdown_n > takeoff_n > 0 N (hysteresis), got {self.touchdown_n} and {self.takeoff_n}"
            )
        if not self.touchdown_bw >= self.takeoff_bw >= 0 or self.noise_factor < 0:
            raise ValueError(f"need touchdown_bw >= takeoff_bw >= 0 and noise_factor >= 0, got "
                             f"{self.touchdown_bw}, {self.takeoff_bw}, {self.noise_factor}")
        if min(self.min_flight_s, self.min_stance_s, self.settle_s) < 0:
            raise ValueError("min_flight_s, min_stance_s and settle_s must be >= 0 s")
        if not 0 <= self.provisional_s <= self.min_flight_s:
            raise ValueError(f"need 0 <= provisional_s <= min_flight_s, got {self.provisional_s} and {self.min_flight_s}")
        if not self.max_stance_s > self.steady_s > 0:
            raise ValueError(f"need max_stance_s > steady_s > 0 s, got {self.max_stance_s} and {self.steady_s}")

    def levels(self, body_weight_n: float | None = None, noise_sd_n: float = 0.0) -> tuple[float, float]:
        """(touchdown, take-off) levels in N above the flight baseline (module docstring)."""
        bw = body_weight_n if body_weight_n is not None and body_weight_n > 0 else 0.0
        to = max(self.takeoff_n, self.takeoff_bw * bw, self.noise_factor * noise_sd_n)
        td = max(self.touchdown_n, self.touchdown_bw * bw, 2 * self.noise_factor * noise_sd_n)
        return td, to

    @classmethod
    def from_settings(cls, settings: list[str] | None) -> DetectorOptions:
        """Options from ``NAME=VALUE`` strings (the command line's ``--detector``); other fields keep their defaults.

        Raises ValueError with one line naming the bad setting and the valid names.
        """
        names = [f.name for f in fields(cls) if f.name != "event_level_n"] + ["event_level_n"]
        values: dict[str, float] = {}
        for item in settings or []:
            name, sep, value = item.partition("=")
            name = name.strip()
            if not sep or name not in names:
                raise ValueError(f"detector setting {item!r}: expected NAME=VALUE with NAME one of {', '.join(names)}")
            try:
                values[name] = float(value)
            except ValueError:
                raise ValueError(f"detector setting {item!r}: {value!r} is not a number") from None
        return cls(**values)

    @property
    def level_n(self) -> float:
        """Event level without a body weight or noise estimate (N)."""
        return self.levels()[1] if self.event_level_n is None else self.event_level_n


@dataclass(frozen=True)
class ContactEvent:
    """A touchdown or take-off.

    Attributes
    ----------
    kind : str
        ``"touchdown"``, ``"takeoff"`` (confirmed), ``"takeoff_provisional"``
        (announced after ``provisional_s`` below the level) or
        ``"takeoff_withdrawn"`` (the provisional one was a dip; ``time_s`` is
        when the force came back).
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
    squares: float = 0.0

    def add(self, f: float) -> None:
        self.n += 1
        self.total += f
        self.squares += f * f

    @property
    def mean(self) -> float:
        return self.total / self.n

    @property
    def sd(self) -> float:
        return float(np.sqrt(max(self.squares / self.n - self.mean**2, 0.0)))


#: Flight samples needed before their SD counts as the plate noise.
NOISE_MIN_SAMPLES = 30


#: Stamps are integer ns turned into float s: a gap of exactly ``min_flight_s`` (no room for a flight with
#: its edges) must not read as a longer one through round-off.
_STAMP_TOLERANCE_S = 1e-6


class StanceDetector:
    """Sample-by-sample stance state machine (see the module docstring).

    Use :meth:`push` with chunks of samples as they arrive; it returns the
    :class:`ContactEvent` s found so far and collects finished :class:`Stance`
    objects in :attr:`stances`. Call :meth:`flush` at the end of the data.

    Parameters
    ----------
    options : DetectorOptions
    body_weight_n : float or None
        Body weight (N) for the relative thresholds and the quiet-standing
        test; None uses the absolute floors only.
    """

    def __init__(self, options: DetectorOptions | None = None, body_weight_n: float | None = None) -> None:
        self.options = options or DetectorOptions()
        self.body_weight_n = body_weight_n if body_weight_n is not None and body_weight_n > 0 else None
        self.stances: list[Stance] = []
        #: Detector failures found and corrected (module docstring), one sentence each.
        self.warnings: list[str] = []
        self._last_t = np.nan
        self._noise_sd = 0.0
        #: The first take-off announced (provisional or confirmed, even if later withdrawn; s), NaN before.
        #: The body model is scaled from the marker frames up to it (analysis.calibration_markers).
        self.first_takeoff_s = np.nan
        self._reset(0.0, at_start=True)

    def _reset(self, baseline_n: float, at_start: bool, rerun: bool = False) -> None:
        """State before the first sample (``at_start``) or before a re-run after a detector failure (``rerun``)."""
        self._state: str | None = None  # None until the first sample, then "flight" / "stance"
        self._at_start = at_start
        self._rerun = rerun
        self._baseline = float(baseline_n)
        self._prev_flight_baseline = float(baseline_n)
        self._flight = _FlightStats()
        self._flight_start_s = -np.inf
        self._initial_flight = False
        self._prev = (np.nan, np.nan)  # last sample (t, fz - baseline)
        self._touchdown_s: float | None = None
        self._touchdown_cut = False
        self._touchdown_cut_why = "start of recording"
        self._baseline_before = float("nan")
        self._dip_start: tuple[float, float] | None = None  # (crossing time, baseline) of a candidate take-off
        self._dip_samples: list[tuple[float, float]] = []
        self._pending_after: Stance | None = None  # stance waiting for the next flight's baseline
        self._provisional: Stance | None = None  # stance of an announced, not yet confirmed take-off
        self._rise_s: float | None = None  # last upward crossing of the event level during flight
        self._stance_samples: collections.deque[tuple[float, float]] = collections.deque()  # raw (t, f) since the stance began
        self._first_t = np.nan
        self._set_levels()

    def _set_levels(self) -> None:
        self._td_level, self._to_level = self.options.levels(self.body_weight_n, self._noise_sd)
        self._event_level = self._to_level if self.options.event_level_n is None else self.options.event_level_n

    @property
    def levels_n(self) -> tuple[float, float]:
        """Touchdown and take-off levels in use (N above the flight baseline)."""
        return self._td_level, self._to_level

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

    @property
    def provisional_stance(self) -> Stance | None:
        """The stance ended by a provisional take-off (``takeoff_provisional`` event), until confirmed or withdrawn.

        Its fields are those the confirmed stance will have (same take-off
        instant), except ``baseline_after_n`` (NaN).
        """
        return self._provisional

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
            self._last_t = t
            replay = self._feed(t, f, events)
            if replay:
                self._run(replay, events)
        return events

    def flush(self) -> list[ContactEvent]:
        """End of data: close a stance in progress as incomplete (cut by the end)."""
        events: list[ContactEvent] = []
        if self._pending_after is not None and self._state == "flight":
            self._finish_pending(self._flight.mean if self._flight.n else float("nan"))
        if self._state == "stance" and self._touchdown_s is not None:
            events.append(ContactEvent("takeoff", self._last_t, self._baseline, cut=True))
            self._record_stance(self._touchdown_s, self._last_t, cut_start=self._touchdown_cut, cut_end=True)
            self._finish_pending()
            self._state = None
        return events

    # -- internals -------------------------------------------------------------

    def _run(self, samples: list[tuple[float, float]], events: list[ContactEvent]) -> None:
        """Feed samples through the state machine; a detector failure puts its stance's samples back in front.

        A loop over a queue, not recursion: a re-run may find another failure
        further on (its samples are queued again), and a run of any length
        never grows the stack.
        """
        queue = collections.deque(samples)
        while queue:
            t, f = queue.popleft()
            replay = self._feed(t, f, events)
            if replay:
                queue.extendleft(reversed(replay))

    def _feed(self, t: float, f: float, events: list[ContactEvent]) -> list[tuple[float, float]] | None:
        """One sample; returns the samples to run again after a detector failure, else None."""
        if self._state == "stance" and t - self._prev[0] > self.options.min_flight_s + _STAMP_TOLERANCE_S:
            self._cut_by_loss(t, f, events)
        else:
            self._step(t, f, events)
        if self._state == "stance":
            samples = self._stance_samples
            if samples and t - samples[-1][0] > self.options.steady_s:
                # Samples missing for longer than the steadiness window (message loss): the
                # failure test's clock restarts here, so a gap is never read as a long steady
                # stance (a 1 s gap inside a stance used to re-run the same samples with the
                # same baseline forever). The stance around the gap is kept and rejected for
                # its lost samples (stages.missing_samples_reason).
                samples.clear()
            samples.append((t, f))
            if t - samples[0][0] > self.options.max_stance_s:
                return self._check_failure(t)
        return None

    def _check_failure(self, t: float) -> list[tuple[float, float]] | None:
        """A long "stance" whose recent force is steady and far from body weight: the samples to re-run with a new baseline.

        Returns None when there is no failure (or a re-run could not change
        anything: the steady level is already within the take-off level of
        the baseline).
        """
        opt = self.options
        samples = self._stance_samples
        if len(samples) < 10:
            return None
        # the steady window: the last steady_s of samples
        i = len(samples) - 1
        while i > 0 and t - samples[i - 1][0] <= opt.steady_s:
            i -= 1
        if len(samples) - i < 5:
            return None
        window = np.fromiter((samples[j][1] for j in range(i, len(samples))), float, len(samples) - i)
        if np.std(window) > max(opt.steady_sd_n, 3 * self._noise_sd):
            return None
        level = float(np.mean(window))
        rel = level - self._baseline
        bw = self.body_weight_n
        if bw is not None:
            failure = abs(rel - bw) > opt.standing_tolerance_bw * bw
        else:
            failure = rel < opt.start_flight_max_n
        if failure and abs(rel) < self._to_level:
            failure = False  # the baseline is already right: a re-run would repeat this run
        if not failure:
            # quiet standing: keep only what a later failure test could need
            while len(samples) > 1 and t - samples[1][0] > opt.max_stance_s + 30.0:
                samples.popleft()
            return None
        replay = list(samples)
        cut = self._touchdown_cut
        what = "from the start of the recording" if cut else f"from {replay[0][0]:.3f} s"
        self.warnings.append(
            f"detector failure: steady Fz of {level:.1f} N ({rel:+.1f} N against the baseline "
            f"{self._baseline:.1f} N) read as a stance {what} to {t:.3f} s; flight baseline re-estimated "
            f"as {level:.1f} N and the samples run again"
        )
        self._reset(level, at_start=cut, rerun=True)
        if self.first_takeoff_s >= replay[0][0]:
            self.first_takeoff_s = np.nan  # announced inside the false stance: void
        return replay

    def _cut_by_loss(self, t: float, f: float, events: list[ContactEvent]) -> None:
        """Force samples missing from ``self._prev[0]`` to ``t`` inside a stance, long enough to hide a flight.

        The stance ends at the last sample before the gap (cut by message
        loss); the sample at ``t`` starts afresh with the baseline in use:
        flight below the take-off level, else a stance cut at its start by
        the same loss (module docstring, "Message loss").
        """
        last = self._prev[0]
        events.append(ContactEvent("takeoff", last, self._baseline, cut=True))
        self._record_stance(self._stance_touchdown_s, last, cut_start=self._touchdown_cut, cut_end=True,
                            cut_why=f"a {t - last:.3f} s force gap (message loss)")
        self._finish_pending()
        self._dip_start = None
        self._dip_samples = []
        self._stance_samples.clear()
        self._begin(t, f, f - self._baseline < self._to_level, cut=True,
                    cut_why=f"a {t - last:.3f} s force gap (message loss)")

    def _start(self, t: float, f: float) -> None:
        """First sample (of the recording, or of a re-run after a failure)."""
        opt = self.options
        self._first_t = t
        bw = self.body_weight_n or 0.0
        if self._at_start and not self._rerun:
            flight = f < max(opt.start_flight_max_n, opt.start_flight_max_bw * bw)
        else:  # a re-run: the baseline was just measured
            flight = f - self._baseline < self._to_level
        self._begin(t, f, flight, cut=self._at_start, cut_why="start of recording")

    def _begin(self, t: float, f: float, flight: bool, cut: bool, cut_why: str) -> None:
        """Enter flight or stance at sample ``t`` with no edge seen (first sample, re-run, after a force gap).

        A stance begun here is cut at its start (``cut``) by ``cut_why``.
        """
        if flight:
            self._enter_flight(t)
            self._initial_flight = True
            self._flight_start_s = t - 2 * self.options.settle_s  # no take-off ringing to wait for
            self._update_flight_baseline(t, f)
        else:
            self._state = "stance"
            self._touchdown_s = t
            self._touchdown_cut = cut
            self._touchdown_cut_why = cut_why
            self._baseline_before = self._baseline
        self._prev = (t, f - self._baseline)

    def _step(self, t: float, f: float, events: list[ContactEvent]) -> None:
        opt = self.options
        if self._state is None:
            self._start(t, f)
            return
        rel = f - self._baseline
        level = self._event_level
        if self._state == "flight":
            if rel >= level and (self._prev[1] < level or self._rise_s is None):
                self._rise_s = self._crossing_time(t, rel)  # where the rising edge left the zero line
            elif rel < level:
                self._rise_s = None
            if rel > self._td_level:
                td = self._rise_s if self._rise_s is not None else t
                self._rise_s = None
                no_baseline = self._initial_flight and self._at_start and t - self._first_t < opt.settle_s
                self._close_flight()
                self._state = "stance"
                self._touchdown_s = td
                self._touchdown_cut = no_baseline
                self._touchdown_cut_why = "start of recording"
                self._baseline_before = self._baseline
                self._stance_samples.clear()
                if not no_baseline:
                    events.append(ContactEvent("touchdown", td, self._baseline))
            elif rel < level:  # the rising edge of a touchdown must not bias the baseline
                self._update_flight_baseline(t, f)
                rel = f - self._baseline
        else:  # stance
            if self._dip_start is None:
                if rel < self._to_level:
                    self._dip_start = (self._crossing_time(t, rel), self._baseline)
                    self._dip_samples = [(t, f)]
            elif rel > self._td_level:
                if self._provisional is not None:
                    events.append(ContactEvent("takeoff_withdrawn", t, self._dip_start[1]))
                    self._provisional = None
                self._dip_start = None  # a short dip: still in stance
                self._dip_samples = []
            else:
                self._dip_samples.append((t, f))
                if t - self._dip_start[0] >= opt.min_flight_s:
                    to = self._dip_start[0]
                    self._provisional = None
                    events.append(ContactEvent("takeoff", to, self._dip_start[1]))
                    self._record_stance(self._stance_touchdown_s, to, cut_start=self._touchdown_cut, cut_end=False)
                    self._enter_flight(to)
                    for ts, fs in self._dip_samples:
                        self._update_flight_baseline(ts, fs)
                    self._dip_start = None
                    self._dip_samples = []
                    self._stance_samples.clear()
                    rel = f - self._baseline
                elif self._provisional is None and t - self._dip_start[0] >= opt.provisional_s - _STAMP_TOLERANCE_S:
                    to = self._dip_start[0]
                    self._provisional = self._stance(self._stance_touchdown_s, to, cut_start=self._touchdown_cut, cut_end=False)
                    if not np.isfinite(self.first_takeoff_s):
                        self.first_takeoff_s = to
                    events.append(ContactEvent("takeoff_provisional", to, self._dip_start[1]))
        self._prev = (t, rel)

    def _crossing_time(self, t: float, rel: float) -> float:
        """Instant at which Fz - baseline crossed the event level between the previous sample and this one.

        Linear interpolation between the two samples; ``t`` itself if they do
        not bracket the level.
        """
        level = self._event_level
        t0, r0 = self._prev
        if np.isfinite(t0) and (r0 - level) * (rel - level) <= 0 and r0 != rel:
            return float(t0 + (level - r0) / (rel - r0) * (t - t0))
        return t

    def _enter_flight(self, t: float) -> None:
        self._state = "flight"
        self._flight = _FlightStats()
        self._flight_start_s = t
        self._initial_flight = False

    def _update_flight_baseline(self, t: float, f: float) -> None:
        if t - self._flight_start_s < self.options.settle_s:
            return
        self._flight.add(f)
        if t - self._flight_start_s >= 2 * self.options.settle_s:
            self._baseline = self._flight.mean
        if self._flight.n == NOISE_MIN_SAMPLES and self._noise_sd == 0.0:
            self._noise_sd = self._flight.sd  # first estimate of the plate noise, at once
            self._set_levels()

    def _close_flight(self) -> None:
        if self._flight.n:
            self._prev_flight_baseline = self._flight.mean
            if self._flight.n >= NOISE_MIN_SAMPLES:
                self._noise_sd = self._flight.sd
                self._set_levels()
        if self._pending_after is not None:
            self._finish_pending(self._prev_flight_baseline)

    def _finish_pending(self, after: float = float("nan")) -> None:
        if self._pending_after is not None:
            s = self._pending_after
            self.stances.append(replace(s, baseline_after_n=after))
            self._pending_after = None

    @property
    def _stance_touchdown_s(self) -> float:
        """Touchdown time of the stance in progress: every entry into stance (_begin, _step) sets it."""
        assert self._touchdown_s is not None, "touchdown time read outside a stance"
        return self._touchdown_s

    def _record_stance(self, td: float, to: float, cut_start: bool, cut_end: bool, cut_why: str | None = None) -> None:
        self._provisional = None
        self._pending_after = self._stance(td, to, cut_start, cut_end, cut_why)
        if not np.isfinite(self.first_takeoff_s):
            self.first_takeoff_s = to

    def _stance(self, td: float, to: float, cut_start: bool, cut_end: bool, cut_why: str | None = None) -> Stance:
        reason = None
        if cut_start:
            reason = f"incomplete: cut by {self._touchdown_cut_why}"
        elif cut_end:
            reason = f"incomplete: cut by {cut_why or 'end of recording'}"
        elif to - td < self.options.min_stance_s:
            reason = f"too short: {to - td:.3f} s < {self.options.min_stance_s:.3f} s"
        return Stance(
            td,
            to,
            not (cut_start or cut_end),
            reason,
            float("nan") if cut_start else self._baseline_before,
            cut_start=cut_start,
            cut_end=cut_end,
        )


def detect_stances(
    t_s: np.ndarray, fz_n: np.ndarray, options: DetectorOptions | None = None, body_weight_n: float | None = None
) -> list[Stance]:
    """Batch wrapper: run :class:`StanceDetector` over a whole record.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Sample times (s).
    fz_n : ndarray, shape (N,)
        Raw vertical ground reaction force (N).
    options : DetectorOptions, optional
    body_weight_n : float, optional
        Body weight (N) for the relative thresholds; None = floors only.

    Returns
    -------
    list of Stance
        In time order, complete and incomplete ones.
    """
    det = StanceDetector(options, body_weight_n)
    det.push(t_s, fz_n)
    det.flush()
    return det.stances
