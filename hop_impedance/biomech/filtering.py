"""Low-pass filtering and marker gap filling.

Choices (documented here, tested in ``test/biomech/test_kinematics.py``)
-----------------------------------------------------------------------
- Zero-lag low-pass: 2nd-order Butterworth run forwards and backwards
  (``scipy.signal.sosfiltfilt``), i.e. an effective 4th-order response with no
  phase lag. The cut-off passed in is the -3 dB point of the *single* pass;
  the forward-backward pass is -6 dB there.
- Default cut-off 12 Hz for markers *and* forces. Hopping at 1.5-3 Hz has
  almost all joint-angle power below 10 Hz (Winter 2009, ch. 2: 6-12 Hz for
  lower-limb kinematics); using the same cut-off on the ground reaction force
  avoids the spurious impact peaks that appear in joint moments when a
  sharp force is combined with smoothed accelerations (Bisseling & Hof 2006;
  Kristianslund et al. 2012).
- Gaps (NaN runs) up to ``max_gap_s`` are filled with a cubic spline through
  the valid samples (Howarth & Callaghan 2010 recommend splines for short
  gaps). Longer gaps are bridged linearly only so that the filter can run;
  they are flagged as unreliable and the stances they touch are rejected.
  The duration of a gap is the time between the last valid sample before it
  and the first valid sample after it (the span the interpolation bridges).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import butter, sosfiltfilt

#: Default low-pass cut-off for markers and forces (Hz); see the module docstring.
DEFAULT_CUTOFF_HZ = 12.0
#: Default Butterworth order of one pass.
DEFAULT_ORDER = 2
#: Default longest marker gap that is filled (s).
DEFAULT_MAX_GAP_S = 0.05


@dataclass(frozen=True)
class Gap:
    """A run of missing samples in one signal.

    Attributes
    ----------
    column : int
        Index of the signal (e.g. marker index) along the first trailing axis.
    start_s, end_s : float
        Last valid sample before and first valid sample after the gap (s);
        ``-inf``/``inf`` when the gap touches the start/end of the data.
    filled : bool
        True if it was short enough to be filled by interpolation.
    """

    column: int
    start_s: float
    end_s: float
    filled: bool

    @property
    def duration_s(self) -> float:
        """Bridged span (s)."""
        return self.end_s - self.start_s


def lowpass(x: np.ndarray, fs_hz: float, cutoff_hz: float = DEFAULT_CUTOFF_HZ, order: int = DEFAULT_ORDER) -> np.ndarray:
    """Zero-lag Butterworth low-pass along axis 0.

    Parameters
    ----------
    x : ndarray, shape (N, ...)
        Uniformly sampled signal(s); must be finite.
    fs_hz : float
        Sampling rate (Hz).
    cutoff_hz : float
        -3 dB frequency of one pass (Hz); must be below ``fs_hz / 2``.
    order : int
        Order of one pass (the zero-lag result has twice the order).

    Returns
    -------
    ndarray, same shape as ``x``.
    """
    if not 0 < cutoff_hz < fs_hz / 2:
        raise ValueError(f"cutoff_hz must be in (0, fs/2 = {fs_hz / 2:g}) Hz, got {cutoff_hz:g}")
    x = np.asarray(x, float)
    if not np.all(np.isfinite(x)):
        raise ValueError("lowpass: signal contains NaN or inf; fill gaps first")
    sos = _butter_sos(int(order), float(cutoff_hz), float(fs_hz))
    # Odd-extension padding of three cut-off periods keeps the edge transient short.
    padlen = min(int(np.ceil(3 * fs_hz / cutoff_hz)), x.shape[0] - 1)
    filtered: np.ndarray = sosfiltfilt(sos, x, axis=0, padlen=padlen)  # scipy.signal has no type information
    return filtered


@lru_cache(maxsize=32)
def _butter_sos(order: int, cutoff_hz: float, fs_hz: float) -> np.ndarray:
    """Butterworth low-pass design (cached: designing costs more than filtering a short window)."""
    sos: np.ndarray = butter(order, cutoff_hz, btype="low", output="sos", fs=fs_hz)
    return sos


def sampling_rate_hz(t_s: np.ndarray) -> float:
    """Median sampling rate (Hz) of time stamps ``t_s`` (s), shape (N,), N >= 2."""
    dt = np.diff(np.asarray(t_s, float))
    step = float(np.median(dt)) if dt.size else 0.0  # once: a median is most of this function's cost
    if not step > 0:
        raise ValueError("need at least two increasing time stamps to get a sampling rate")
    return 1.0 / step


def uniform_times(start_s: float, end_s: float, rate_hz: float) -> np.ndarray:
    """Times (s) every 1 / ``rate_hz`` s from ``start_s`` up to ``end_s`` (included when on the grid)."""
    return start_s + np.arange(int(np.floor((end_s - start_s) * rate_hz + 1e-6)) + 1) / rate_hz


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Start (inclusive) and end (exclusive) indices of True runs in a 1-D mask."""
    padded = np.concatenate([[False], mask, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def fill_gaps(t_s: np.ndarray, x: np.ndarray, max_gap_s: float = DEFAULT_MAX_GAP_S) -> tuple[np.ndarray, np.ndarray, list[Gap]]:
    """Fill NaN runs per column; short ones by cubic spline, long ones linearly (flagged).

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Sample times (s), increasing.
    x : ndarray, shape (N, C, ...)
        Signals; a column ``x[:, c]`` counts as missing at a sample if any of
        its trailing values is NaN (a marker's x, y, z go missing together).
    max_gap_s : float
        Longest bridged span that is filled and trusted (s).

    Returns
    -------
    filled : ndarray, same shape as ``x``
        No NaN left (a column with no valid sample at all stays NaN).
    reliable : ndarray, shape (N, C), bool
        False inside gaps longer than ``max_gap_s`` and in NaN runs touching
        the ends of the data (nothing to interpolate between).
    gaps : list of Gap
        Every NaN run found.
    """
    t_s = np.asarray(t_s, float)
    x = np.array(x, float, copy=True)
    n, ncol = x.shape[0], x.shape[1]
    flat = x.reshape(n, ncol, -1)
    missing = ~np.all(np.isfinite(flat), axis=2)
    reliable = ~missing
    gaps: list[Gap] = []
    for c in range(ncol):
        if not missing[:, c].any():
            continue
        valid = np.flatnonzero(~missing[:, c])
        if valid.size == 0:
            gaps.append(Gap(c, -np.inf, np.inf, False))
            continue
        spline = CubicSpline(t_s[valid], flat[valid, c, :], axis=0) if valid.size >= 4 else None
        for i0, i1 in _runs(missing[:, c]):
            start = t_s[i0 - 1] if i0 > 0 else -np.inf
            end = t_s[i1] if i1 < n else np.inf
            short = (end - start) <= max_gap_s + 1e-9
            idx = np.arange(i0, i1)
            if short and spline is not None:
                flat[idx, c, :] = spline(t_s[idx])
                reliable[idx, c] = True
            else:
                for k in range(flat.shape[2]):
                    flat[idx, c, k] = np.interp(t_s[idx], t_s[valid], flat[valid, c, k])
                short = short and spline is not None
            gaps.append(Gap(c, float(start), float(end), bool(short)))
    return flat.reshape(x.shape), reliable, gaps
