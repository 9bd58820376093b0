"""One set of input checks for every path: ``hop-impedance analyze`` and the live nodes.

A recording or a live stream is checked against the contract
(shared/contract/RECORDINGS.md) by :class:`InputChecks`. Offline,
:func:`hop_impedance.io.recording_io.load_recording` feeds it the whole
arrays at once and raises :class:`InputCheckError`; live, the
``inverse_dynamics`` node feeds it every message (through
``nodes.common.InputGuard``), from the first seconds on and continuously
after, and a failure becomes an explicit state: ``/diagnostics`` ERROR naming
the rule, every stance rejected with :attr:`CheckFailure.reason`, and the
controller feed ``valid = false`` for every joint.

The rules (``CheckFailure.rule``), each decided the same way on both paths:

``force_sign``
    Counts of samples with ``force.z < -100 N`` and ``> +100 N``: once at least
    :data:`SIGN_MIN_SAMPLES` are below -100 N and they outnumber those above
    +100 N more than 5 to 1, the force is the force on the plate (z down),
    not on the subject. Decided during the first stance (50 ms at 1 kHz).
``force_units``
    The :data:`UNITS_MIN_SAMPLES`-th largest ``force.z`` exceeds 40 body
    weights (needs the subject): not newtons.
``subject_values``
    body mass outside 10-300 kg or height outside 0.5-2.6 m (kg and m are
    the contract's units; this also catches 0 and negative sizes).
``subject_missing``
    Live only: no ``/subject`` within ``subject_wait_s`` of stamp time after the
    first force sample and no fallback mass/height given (offline, ``analyze``
    asks for ``--mass-kg``/``--height-m`` instead).
``marker_names``
    A contract marker (after the optional name mapping) missing from the
    message's names; names are case-sensitive as the contract says.
``marker_units``
    At least :data:`MM_MIN_FRAMES` frames, and more than half the frames seen,
    have a median absolute coordinate above 20 (m): millimetres.
``rates``
    The nominal rate of a stream (median of its first 50 positive stamp steps,
    ``stages.NominalPeriod`` as the streaming stage uses) must exceed twice the low-pass
    cut-off, or no stance can be filtered (``--cutoff-hz 50`` on 100 Hz markers).

Duplicates and order are not failures: both paths sort by ``header.stamp``
and drop repeated stamps, and count them (:func:`order_by_stamp` offline,
``nodes.common.ReorderBuffer`` live).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from hop_impedance.io.mcap_io import RecordingError
from hop_impedance.recording import FORCE_TOPIC, GRAVITY_M_S2, MARKER_NAMES, MARKER_TOPIC, SUBJECT_TOPIC, Subject

#: Samples beyond +-100 N needed before the force sign is decided.
SIGN_MIN_SAMPLES = 50
SIGN_THRESHOLD_N = 100.0
#: Samples above 40 body weights that make the force "not newtons".
UNITS_MIN_SAMPLES = 10
UNITS_MAX_BW = 40.0
#: Frames that must look like millimetres (and more than half of those seen).
MM_MIN_FRAMES = 10
MM_MEDIAN_LIMIT = 20.0
MASS_RANGE_KG = (10.0, 300.0)
HEIGHT_RANGE_M = (0.5, 2.6)


#: Every rejection reason from a failed input check starts with this.
INPUT_CHECK_PREFIX = "input check "


@dataclass(frozen=True)
class CheckFailure:
    """A failed input check: the rule's name and a one-line message."""

    rule: str
    message: str

    @property
    def reason(self) -> str:
        """The rejection reason of every stance affected (names the rule)."""
        return f"{INPUT_CHECK_PREFIX}{self.rule}: {self.message}"

    def __str__(self) -> str:
        return self.reason


class InputCheckError(RecordingError):
    """Raised by the offline path for a failed check (a one-line :class:`RecordingError`); ``failure`` holds the rule."""

    def __init__(self, failure: CheckFailure) -> None:
        super().__init__(failure.reason)
        self.failure = failure


def subject_failure(mass_kg: float, height_m: float) -> CheckFailure | None:
    """``subject_values`` rule: mass and height in the contract's units and plausible ranges."""
    if not MASS_RANGE_KG[0] <= mass_kg <= MASS_RANGE_KG[1]:
        return CheckFailure("subject_values", f"{SUBJECT_TOPIC}: body_mass {mass_kg:g} kg is implausible "
                            f"(contract: kg, {MASS_RANGE_KG[0]:g}-{MASS_RANGE_KG[1]:g})")
    if not HEIGHT_RANGE_M[0] <= height_m <= HEIGHT_RANGE_M[1]:
        return CheckFailure("subject_values", f"{SUBJECT_TOPIC}: body_height {height_m:g} m is implausible "
                            f"(contract: m, {HEIGHT_RANGE_M[0]:g}-{HEIGHT_RANGE_M[1]:g})")
    return None


def marker_columns(names: list[str], marker_map: dict[str, str] | None = None) -> tuple[list[int] | None, CheckFailure | None]:
    """``marker_names`` rule: column of each contract marker in ``names`` (after ``marker_map``)."""
    wanted = {name: (marker_map or {}).get(name, name) for name in MARKER_NAMES}
    missing = [f"{c} (as {n!r})" if c != n else c for c, n in wanted.items() if n not in names]
    if missing:
        return None, CheckFailure(
            "marker_names",
            f"{MARKER_TOPIC}: missing marker(s) {', '.join(missing)}; the recording has {list(names)} "
            "(names are case-sensitive; if they differ, import the session with a marker mapping: "
            "hop-impedance import --markers NAME or YAML)",
        )
    return [names.index(wanted[c]) for c in MARKER_NAMES], None


def order_by_stamp(stamps: np.ndarray, label: str, warnings: list[str]) -> np.ndarray:
    """Indices that sort samples by stamp and drop exact duplicates; notes what was done in ``warnings``."""
    order = np.argsort(stamps, kind="stable")
    n_out_of_order = int(np.count_nonzero(np.diff(stamps) < 0))
    if n_out_of_order:
        warnings.append(f"{label}: {n_out_of_order} message(s) arrived out of order; re-sorted by header.stamp")
    sorted_stamps = stamps[order]
    keep = np.concatenate([[True], np.diff(sorted_stamps) > 0]) if len(order) else np.zeros(0, bool)
    n_dup = int(np.count_nonzero(~keep))
    if n_dup:
        warnings.append(f"{label}: {n_dup} message(s) with a repeated header.stamp dropped")
    return order[keep]


class _Rate:
    """Nominal rate of a stream: :class:`hop_impedance.biomech.stages.NominalPeriod` on stamps in ns."""

    def __init__(self) -> None:
        from hop_impedance.biomech.stages import NominalPeriod

        self.period = NominalPeriod()
        self.t0: int | None = None

    @property
    def hz(self) -> float | None:
        return None if self.period.value is None else 1.0 / self.period.value

    def add(self, stamps_ns: np.ndarray) -> bool:
        """Take stamps (ns, in arrival order); True when the rate became known now."""
        if self.period.value is not None or len(stamps_ns) == 0:
            return False
        s = np.asarray(stamps_ns, np.int64)
        self.t0 = int(s[0]) if self.t0 is None else self.t0
        self.period.update((s - self.t0) * 1e-9)
        return self.period.value is not None


class InputChecks:
    """The contract checks on a stream (or a whole recording fed at once); see the module docstring.

    Parameters
    ----------
    cutoff_hz : float or None
        Low-pass cut-off the analysis will use (``rates`` rule); None skips it.
    marker_map : dict, optional
        Contract marker name -> name in the messages.
    subject_wait_s : float or None
        Live: stamp time after the first force sample to wait for a subject
        before ``fallback`` is taken or ``subject_missing`` fails; None
        (offline) never fails for a missing subject.
    fallback : Subject, optional
        Mass and height to use when no ``/subject`` arrives in time.

    Attributes
    ----------
    failure : CheckFailure or None
        The first failed rule (sticky: a stream that failed once stays failed).
    subject : Subject or None
        The subject in use (message or fallback).
    notes : list of str
        One-line notes (e.g. the fallback subject was taken).
    """

    def __init__(self, cutoff_hz: float | None = None, marker_map: dict[str, str] | None = None,
                 subject_wait_s: float | None = None, fallback: Subject | None = None) -> None:
        self.cutoff_hz = cutoff_hz
        self.marker_map = marker_map
        self.subject_wait_s = subject_wait_s
        self.fallback = fallback
        self.failure: CheckFailure | None = None
        self.subject: Subject | None = None
        self.notes: list[str] = []
        self.n_neg = self.n_pos = 0
        self._top: list[float] = []  # the UNITS_MIN_SAMPLES largest force.z (min-heap)
        self.frames = self.mm_frames = 0
        self._names: list[str] | None = None
        self.columns: list[int] | None = None
        self._force_rate, self._marker_rate = _Rate(), _Rate()
        self._first_force_ns: int | None = None

    # -- feeding ---------------------------------------------------------------

    def _fail(self, failure: CheckFailure | None) -> CheckFailure | None:
        if failure is not None and self.failure is None:
            self.failure = failure
        return self.failure

    def set_subject(self, subject: Subject) -> CheckFailure | None:
        """A ``/subject`` message (or the user's mass/height)."""
        self.subject = subject
        self._fail(subject_failure(subject.body_mass_kg, subject.body_height_m))
        self._check_units()
        return self.failure

    def force(self, stamps_ns, fz) -> CheckFailure | None:
        """Force samples: stamps (ns) and vertical force (N), arrays or scalars."""
        s = np.atleast_1d(np.asarray(stamps_ns, np.int64))
        f = np.atleast_1d(np.asarray(fz, float))
        if not len(s):
            return self.failure
        if self._first_force_ns is None:
            self._first_force_ns = int(s[0])
        self.n_neg += int(np.count_nonzero(f < -SIGN_THRESHOLD_N))
        self.n_pos += int(np.count_nonzero(f > SIGN_THRESHOLD_N))
        if self.n_neg >= SIGN_MIN_SAMPLES and self.n_neg > 5 * self.n_pos:
            self._fail(CheckFailure(
                "force_sign", f"{FORCE_TOPIC}: force.z is mostly negative ({self.n_neg} samples below "
                f"-{SIGN_THRESHOLD_N:.0f} N, {self.n_pos} above +{SIGN_THRESHOLD_N:.0f} N); the contract wants the "
                "force on the subject (z up), this looks like the force on the plate"))
        finite = f[np.isfinite(f)]
        if len(self._top) < UNITS_MIN_SAMPLES or (finite.size and finite.max() > self._top[0]):
            for v in (finite if finite.size <= UNITS_MIN_SAMPLES
                      else np.partition(finite, -UNITS_MIN_SAMPLES)[-UNITS_MIN_SAMPLES:]):
                if len(self._top) < UNITS_MIN_SAMPLES:
                    heapq.heappush(self._top, float(v))
                elif v > self._top[0]:
                    heapq.heapreplace(self._top, float(v))
            self._check_units()
        if self._force_rate.add(s):
            self._check_rate("force", self._force_rate.hz)
        self._check_subject_wait(int(s[-1]))
        return self.failure

    def marker_names(self, names: list[str]) -> list[int] | None:
        """Columns of the contract markers in a message's ``names`` (None and a failure if any is missing)."""
        if names != self._names:
            self._names = list(names)
            self.columns, failure = marker_columns(self._names, self.marker_map)
            self._fail(failure)
        return self.columns

    def markers(self, stamps_ns, positions_m) -> CheckFailure | None:
        """Marker frames in contract order: stamps (ns) and positions (n, 6, 3) or (6, 3) (m)."""
        s = np.atleast_1d(np.asarray(stamps_ns, np.int64))
        pos = np.asarray(positions_m, float)
        if pos.ndim == 2:
            pos = pos[None]
        if not len(s):
            return self.failure
        flat = np.abs(pos.reshape(len(pos), -1))
        with np.errstate(all="ignore"):
            medians = np.nanmedian(np.where(np.isfinite(flat), flat, np.nan), axis=1) if flat.shape[1] else np.zeros(len(pos))
        self.frames += len(pos)
        self.mm_frames += int(np.count_nonzero(medians > MM_MEDIAN_LIMIT))
        if self.mm_frames >= MM_MIN_FRAMES and 2 * self.mm_frames > self.frames:
            self._fail(CheckFailure(
                "marker_units", f"{MARKER_TOPIC}: {self.mm_frames} of {self.frames} frames have a median coordinate "
                f"magnitude above {MM_MEDIAN_LIMIT:g}; they look like millimetres, but the contract says metres"))
        if self._marker_rate.add(s):
            self._check_rate("marker", self._marker_rate.hz)
        return self.failure

    # -- rules needing two inputs ---------------------------------------------

    def _check_units(self) -> None:
        if self.subject is None or len(self._top) < UNITS_MIN_SAMPLES:
            return
        bw = self.subject.body_mass_kg * GRAVITY_M_S2
        if bw > 0 and self._top[0] > UNITS_MAX_BW * bw:
            self._fail(CheckFailure(
                "force_units", f"{FORCE_TOPIC}: force.z reaches {self._top[0]:.0f} N, {self._top[0] / bw:.0f} body "
                "weights; not newtons?"))

    def _check_rate(self, name: str, hz: float | None) -> None:
        if hz is None or self.cutoff_hz is None or hz > 2.0 * self.cutoff_hz:
            return
        self._fail(CheckFailure(
            "rates", f"{name} samples arrive at {hz:.1f} Hz; the {self.cutoff_hz:g} Hz low-pass needs more than "
            f"{2 * self.cutoff_hz:g} Hz (lower the cut-off, e.g. --cutoff-hz {0.4 * hz:g})"))

    def _check_subject_wait(self, newest_ns: int) -> None:
        if self.subject is not None or self.subject_wait_s is None or self._first_force_ns is None:
            return
        if (newest_ns - self._first_force_ns) * 1e-9 < self.subject_wait_s:
            return
        if self.fallback is not None:
            self.notes.append(f"no {SUBJECT_TOPIC} within {self.subject_wait_s:g} s: using body_mass "
                              f"{self.fallback.body_mass_kg:g} kg, body_height {self.fallback.body_height_m:g} m from parameters")
            self.set_subject(self.fallback)
            return
        self._fail(CheckFailure(
            "subject_missing", f"no {SUBJECT_TOPIC} message within {self.subject_wait_s:g} s of data and no "
            "body_mass_kg/body_height_m parameters; mass and height are needed"))

    def raise_if_failed(self) -> None:
        """Offline: raise :class:`InputCheckError` for a failed rule."""
        if self.failure is not None:
            raise InputCheckError(self.failure)
