"""Several force plates as the contract's one wrench (pure core, no ROS).

The contract carries one wrench: the ground reaction force on the subject and
its moment about *one* origin, so that ``cop_x = -torque.y / force.z`` is the
combined centre of pressure. With one plate per foot the forces add and each
plate's moment is carried to the common origin:
``M = sum_i (M_i + (r_i - O) x F_i)`` (:func:`total_wrench`). The importers
(C3D, MOT) and the live plate combiner (``nodes/plate_combiner.py``) both use
this one function.

Live, each plate arrives as its own wrench stream; :class:`PlateCombinerStage`
pairs their samples and sums them (what the ``plate_combiner`` node wraps).

Pairing (choice, documented and tested)
---------------------------------------
Plates on one amplifier sample at the same instants; what differs is the
*stamp*, by a constant skew (separate drivers or clocks) plus jitter. Samples
are therefore paired, never interpolated: the skew of each plate against the
first one (the reference plate) is locked from the first pair of samples
whose stamps differ by at most ``max_skew_ns``; after that plate k's sample at
``t_k`` belongs to the reference sample at ``t_0`` when
``|t_k - skew_k - t_0| <= jitter_ns``. The skew follows slow clock drift
(each pair moves it by 1/20 of its residual). The combined sample carries the
reference plate's stamp. A skew of exactly half a sample period (0.5 ms at
1 kHz) cannot be told apart by stamps from the same skew to the neighbouring
sample: the lock takes the first pair within ``max_skew_ns``, which is the
neighbour (-0.5 ms, one sample off) when the other plate's stream starts
earlier than the reference's (tested). Below half a period there is no
ambiguity.

A missing plate is never summed as zero: an instant for which some plate
has no sample (lost, or the plate stopped) yields no output, is counted
against that plate (:attr:`PlateCombinerStage.missing`), and a plate whose
newest stamp lags the newest of all plates by more than ``wait_ns`` is
reported by :meth:`PlateCombinerStage.silent_plates`. The instants are
dropped once another plate's stamps run ``wait_ns`` ahead (or at
:meth:`PlateCombinerStage.flush`), so downstream sees a hole (counted as
lost samples) instead of a half-weight wrench.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import cast

import numpy as np
import numpy.typing as npt


def total_wrench(
    forces_n: np.ndarray, moments_nm: np.ndarray, points_m: np.ndarray, origin_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sum of several plates' wrenches, moment about one common origin.

    Parameters
    ----------
    forces_n : ndarray, shape (P, N, 3)
        Force of each of P plates at N samples (N), any frame common to all.
    moments_nm : ndarray, shape (P, N, 3)
        Moment of each plate about its reference point (N m), same frame.
    points_m : ndarray, shape (P, N, 3) or (P, 3)
        Reference point of each plate's moment (m), same frame (per sample,
        e.g. the centre of pressure, or fixed, e.g. the plate centre).
    origin_m : ndarray, shape (3,)
        The common origin (m).

    Returns
    -------
    force_n : ndarray, shape (N, 3)
        Total force.
    moment_nm : ndarray, shape (N, 3)
        Total moment about ``origin_m``.

    Notes
    -----
    Samples where a plate is unloaded often carry NaN or garbage centres of
    pressure; a plate with zero force contributes only its moment, and a NaN
    reference point is treated as zero lever arm when the force is exactly
    zero.
    """
    f = np.asarray(forces_n, float)
    m = np.asarray(moments_nm, float)
    r = np.asarray(points_m, float)
    if r.ndim == 2:
        r = np.broadcast_to(r[:, None, :], f.shape)
    lever = r - np.asarray(origin_m, float)
    unloaded = np.all(f == 0.0, axis=-1, keepdims=True)
    lever = np.where(unloaded & ~np.isfinite(lever), 0.0, lever)
    return f.sum(axis=0), (m + np.cross(lever, f)).sum(axis=0)


@dataclass(frozen=True)
class PlateLayout:
    """Where one plate is in the lab.

    Attributes
    ----------
    name : str
        Label used in reports (e.g. ``"left"``, or the plate's topic).
    origin_m : tuple of 3 float
        Point about which the plate reports its moment (its top-surface
        centre for the contract's convention), in the lab frame (m).
    yaw_deg : float
        Rotation of the plate's axes about the vertical, relative to the lab
        frame (deg): a plate mounted turned round is 180. The plate's force
        and moment are rotated into the lab frame before summing.
    """

    name: str
    origin_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: float = 0.0

    def rotation(self) -> np.ndarray:
        """Plate axes -> lab axes, shape (3, 3)."""
        c, s = np.cos(np.radians(self.yaw_deg)), np.sin(np.radians(self.yaw_deg))
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def combine_plates(
    layouts: list[PlateLayout], forces_n: np.ndarray, moments_nm: np.ndarray, origin_m: npt.ArrayLike = (0.0, 0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray]:
    """Paired samples of P plates (plate axes) -> one wrench about ``origin_m`` (lab axes).

    Parameters
    ----------
    layouts : list of P :class:`PlateLayout`
    forces_n, moments_nm : ndarray, shape (P, N, 3)
        Each plate's force and moment about its own origin, in its own axes.
    origin_m : 3 floats
        Common origin (lab frame, m): the contract frame's origin.

    Returns
    -------
    force_n, moment_nm : ndarray, shape (N, 3)
    """
    f = np.asarray(forces_n, float)
    m = np.asarray(moments_nm, float)
    rot = np.stack([lay.rotation() for lay in layouts])
    f_lab = np.einsum("pij,pnj->pni", rot, f)
    m_lab = np.einsum("pij,pnj->pni", rot, m)
    points = np.array([lay.origin_m for lay in layouts], float)
    return total_wrench(f_lab, m_lab, points, np.asarray(origin_m, float))


class PlateCombinerStage:
    """Pairs the samples of P plate streams and sums them (see the module docstring).

    ``push(k, stamps_ns, wrench)`` feeds plate ``k`` (stamps in ns, int;
    wrench shape (n, 6): force x, y, z, moment x, y, z in the plate's axes
    about its origin) and returns what became complete:
    ``(stamps_ns (m,), force_n (m, 3), moment_nm (m, 3))`` in the lab frame
    about ``origin_m``. Each plate's samples must be pushed in stamp order
    (the node sorts them over its reorder window first); an older one is
    counted in :attr:`late` and skipped.
    """

    #: Fraction of each pair's residual by which the locked skew follows drift.
    DRIFT_GAIN = 0.05

    def __init__(
        self,
        layouts: list[PlateLayout],
        origin_m: npt.ArrayLike = (0.0, 0.0, 0.0),
        max_skew_ns: int = 600_000,
        jitter_ns: int = 200_000,
        wait_ns: int = 500_000_000,
    ) -> None:
        if len(layouts) < 1:
            raise ValueError("plate combiner: at least one plate is needed")
        names = [lay.name for lay in layouts]
        if len(set(names)) != len(names):
            raise ValueError(f"plate combiner: plate names must differ, got {names}")
        if not (0 <= jitter_ns <= max_skew_ns):
            raise ValueError(f"plate combiner: need 0 <= jitter ({jitter_ns} ns) <= max skew ({max_skew_ns} ns)")
        self.layouts = list(layouts)
        self.origin_m = np.asarray(origin_m, float)
        self.max_skew_ns = int(max_skew_ns)
        self.jitter_ns = int(jitter_ns)
        self.wait_ns = int(wait_ns)
        p = len(layouts)
        self._queues: list[deque[tuple[int, np.ndarray]]] = [deque() for _ in range(p)]  # (stamp ns, wrench row)
        self._skew: list[float | None] = [0.0] + [None] * (p - 1)
        self.newest_ns: list[int | None] = [None] * p
        #: Per plate: instants some other plate had but this one did not (its sample is missing).
        self.missing = [0] * p
        #: Per plate: samples older than the plate's newest (out of order), skipped.
        self.late = [0] * p
        #: Instants dropped because a plate was missing (no output for them).
        self.dropped = 0
        #: Combined samples produced.
        self.combined = 0

    @property
    def skew_ns(self) -> list[float | None]:
        """Locked stamp skew of each plate against the reference plate (ns; None until locked)."""
        return list(self._skew)

    def silent_plates(self) -> list[str]:
        """Plates with no sample yet, or whose newest stamp lags the newest of all by more than ``wait_ns``."""
        known = [n for n in self.newest_ns if n is not None]
        if not known:
            return []
        newest = max(known)
        return [lay.name for lay, n in zip(self.layouts, self.newest_ns)
                if n is None or newest - n > self.wait_ns]

    def push(self, plate: int, stamps_ns: npt.ArrayLike, wrench: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Feed plate ``plate``'s samples; returns the combined samples now complete."""
        stamps = np.asarray(stamps_ns, np.int64).reshape(-1)
        w = np.asarray(wrench, float).reshape(-1, 6)
        if stamps.shape[0] != w.shape[0]:
            raise ValueError(f"plate combiner: {stamps.shape[0]} stamps for {w.shape[0]} wrench samples")
        q = self._queues[plate]
        for ns, row in zip(stamps.tolist(), w):
            if self.newest_ns[plate] is not None and ns <= self.newest_ns[plate]:
                self.late[plate] += 1
                continue
            self.newest_ns[plate] = ns
            q.append((ns, row))
        return self._drain(final=False)

    def flush(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """End of the streams: pair what can be paired, drop (and count) the rest."""
        return self._drain(final=True)

    def _drop_head(self, k: int, missing_from: list[int]) -> None:
        self._queues[k].popleft()
        for j in missing_from:
            self.missing[j] += 1
        self.dropped += 1

    def _drain(self, final: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        qs, p = self._queues, len(self._queues)
        out_ns: list[int] = []
        out_w: list[np.ndarray] = []
        while True:
            empty = [k for k in range(p) if not qs[k]]
            if empty:
                # An instant waits for the empty plates until another plate runs wait_ns ahead.
                known = [n for n in self.newest_ns if n is not None]
                newest = max(known) if known else 0
                progressed = False
                for k in range(p):
                    if qs[k] and (final or newest - qs[k][0][0] > self.wait_ns):
                        self._drop_head(k, empty)
                        progressed = True
                if not progressed:
                    break
                continue
            heads = [qs[k][0][0] for k in range(p)]
            if any(s is None for s in self._skew):
                if not self._lock(heads):
                    continue
            # Skew-corrected head stamps relative to the reference's (differences first: int64 ns
            # stamps near 1.7e18 lose 256 ns as float64).
            skew = cast("list[float]", self._skew)  # the same list, every plate locked by now
            rel = [(heads[k] - heads[0]) - skew[k] for k in range(p)]
            latest = max(rel)
            early = [k for k in range(p) if rel[k] < latest - self.jitter_ns]
            if early:
                late_plates = [k for k in range(p) if k not in early]
                for k in early:
                    self._drop_head(k, late_plates)
                continue
            for k in range(1, p):
                skew[k] += self.DRIFT_GAIN * rel[k]
            out_ns.append(heads[0])
            out_w.append(np.stack([qs[k].popleft()[1] for k in range(p)]))
        if not out_ns:
            return np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3))
        w = np.stack(out_w, axis=1)  # (P, m, 6)
        force, moment = combine_plates(self.layouts, w[:, :, :3], w[:, :, 3:], self.origin_m)
        self.combined += len(out_ns)
        return np.asarray(out_ns, np.int64), force, moment

    def _lock(self, heads: list[int]) -> bool:
        """Lock the skew of every unlocked plate whose head is within ``max_skew_ns`` of the reference's.

        Returns False after dropping a head that cannot pair (its partner
        was lost before the lock), True when every plate is locked.
        """
        for k, s in enumerate(self._skew):
            if s is not None:
                continue
            d = heads[k] - heads[0]
            if abs(d) <= self.max_skew_ns:
                self._skew[k] = float(d)
            elif d < 0:
                self._drop_head(k, [0])
                return False
            else:
                self._drop_head(0, [k])
                return False
        return True
