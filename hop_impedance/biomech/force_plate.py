"""Force plate: sagittal wrench, baseline zeroing during flight, centre of pressure.

Frames and signs
----------------
The plate frame is the lab frame with its origin at the centre of the top
surface (contract). The sagittal wrench used everywhere downstream is
``[Fx, Fz, Mo]``: the anterior and vertical ground reaction force on the
subject (N) and the *counter-clockwise* sagittal moment about the plate
origin (N m), ``Mo = -torque.y`` (see docs/ARCHITECTURE.md: a moment about
+y is clockwise in the x-z picture). The centre of pressure on the surface
(z = 0) is ``cop_x = Mo / Fz = -torque.y / force.z`` (contract).

Zeroing
-------
Real plates drift and carry offsets. During flight the true wrench is zero,
so each flight's mean (over its interior, ``margin_s`` away from the
take-off and touchdown) is an offset sample; the offset at any instant is
the linear interpolation in time between the flight centres (constant before
the first and after the last flight). This removes constant offsets exactly
and linear drift to first order.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.recording import ForcePlateSeries

#: Default margin kept free at both ends of a flight when estimating the offset (s).
DEFAULT_FLIGHT_MARGIN_S = 0.02


def sagittal_wrench(force: ForcePlateSeries) -> np.ndarray:
    """``[Fx, Fz, Mo]`` per sample, shape (N, 3) (N, N, N m); Mo = -torque.y (counter-clockwise)."""
    return np.column_stack([force.force_n[:, 0], force.force_n[:, 2], -force.torque_nm[:, 1]])


def centre_of_pressure_x(wrench: np.ndarray, min_fz_n: float = 50.0) -> np.ndarray:
    """Anterior centre of pressure on the plate surface (m), shape (N,); NaN where Fz < ``min_fz_n``.

    Parameters
    ----------
    wrench : ndarray, shape (N, 3)
        Sagittal wrench ``[Fx, Fz, Mo]`` (see module docstring).
    """
    w = np.asarray(wrench, float)
    out = np.full(w.shape[0], np.nan)
    ok = w[:, 1] >= min_fz_n
    out[ok] = w[ok, 2] / w[ok, 1]
    return out


def flight_intervals(stance_times: list[tuple[float, float]], t_start_s: float, t_end_s: float) -> list[tuple[float, float]]:
    """Flights as the complement of the stances within [t_start_s, t_end_s] (s).

    Parameters
    ----------
    stance_times : list of (touchdown_s, takeoff_s)
        In time order.
    """
    flights, t = [], t_start_s
    for td, to in stance_times:
        if td > t:
            flights.append((t, td))
        t = max(t, to)
    if t_end_s > t:
        flights.append((t, t_end_s))
    return flights


def flight_offsets(
    t_s: np.ndarray, wrench: np.ndarray, flights: list[tuple[float, float]], margin_s: float = DEFAULT_FLIGHT_MARGIN_S
) -> tuple[np.ndarray, np.ndarray]:
    """Mean wrench over each flight's interior: the plate offset at the flight centre.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
    wrench : ndarray, shape (N, C)
        Raw signals (any channels).
    flights : list of (start_s, end_s)
    margin_s : float
        Samples closer than this to a flight's ends are skipped (s).

    Returns
    -------
    centres_s : ndarray, shape (K,)
        Centre of each usable flight (at least 3 interior samples).
    offsets : ndarray, shape (K, C)
    """
    centres, offsets = [], []
    for a, b in flights:
        sel = (t_s > a + margin_s) & (t_s < b - margin_s)
        if np.count_nonzero(sel) >= 3:
            centres.append(0.5 * (a + b))
            offsets.append(np.nanmean(wrench[sel], axis=0))
    c = np.asarray(wrench).shape[1]
    return np.asarray(centres, float), np.asarray(offsets, float).reshape(-1, c)


def subtract_offsets(t_s: np.ndarray, wrench: np.ndarray, centres_s: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Remove the offset interpolated linearly in time between flight centres.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
    wrench : ndarray, shape (N, C)
    centres_s, offsets : from :func:`flight_offsets`; with no flight the
        wrench is returned unchanged.

    Returns
    -------
    ndarray, shape (N, C)
    """
    w = np.array(wrench, float, copy=True)
    if len(centres_s) == 0:
        return w
    for c in range(w.shape[1]):
        w[:, c] -= np.interp(t_s, centres_s, offsets[:, c])
    return w
