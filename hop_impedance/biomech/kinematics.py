"""Sagittal kinematics from the six contract markers.

Processing order (chosen here; tests in ``test/biomech/test_kinematics.py``)
---------------------------------------------------------------------------
1. Markers are projected on the sagittal plane (lab x, z).
2. Gaps are filled (:func:`hop_impedance.biomech.filtering.fill_gaps`).
3. Low-pass at the marker rate (zero-lag Butterworth, default 12 Hz).
4. Segment angles q1..q4 (``joint_angles.segment_angle``) and segment
   centres of mass are computed at the marker rate from the filtered markers.
5. Joint points, angles and centres of mass are interpolated with cubic
   splines (``scipy.interpolate.CubicSpline``) and evaluated, with their first
   and second derivatives, on the *force-plate* time base. Markers are
   upsampled onto force time (not the reverse) because the force carries the
   fast events (touchdown within a millisecond); the filtered marker signals
   have no content above the cut-off, far below the marker Nyquist frequency,
   so the spline and its derivatives are accurate there. Differentiating the
   spline is exact for the interpolant, avoiding a second numerical
   differentiation step.

Both time bases must be on the same clock (seconds since the recording's
first message, from the ``header.stamp`` of each stream).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.sparse import csr_matrix

from hop_impedance.biomech.body_model import BodyModel, body_model, foot_geometry_from_points, with_overrides
from hop_impedance.biomech.filtering import (
    DEFAULT_CUTOFF_HZ,
    DEFAULT_MAX_GAP_S,
    Gap,
    fill_gaps,
    lowpass,
    sampling_rate_hz,
    uniform_times,
)
from hop_impedance.biomech.joint_angles import joint_angles, joint_rates, segment_angle
from hop_impedance.recording import MARKER_NAMES, MarkerSeries, Subject

#: Joint points used by the dynamics, in order: contact point and the proximal end of each segment.
POINT_NAMES: tuple[str, ...] = ("toe", "ankle", "knee", "hip", "head")
_POINT_IDX = [MARKER_NAMES.index(n) for n in POINT_NAMES]


@dataclass
class Kinematics:
    """Sagittal kinematics on one time base.

    Attributes
    ----------
    t_s : ndarray, shape (N,)
        Time (s).
    points_xz : ndarray, shape (N, 5, 2)
        toe, ankle, knee, hip, head ``[x, z]`` (m).
    q, qd, qdd : ndarray, shape (N, 4)
        Segment angles q1..q4 (rad), rates (rad/s), accelerations (rad/s^2);
        counter-clockwise positive from the forward horizontal.
    rho, rhod : ndarray, shape (N, 3)
        Joint angles (rad) and rates (rad/s), ankle, knee, hip; increase with flexion.
    com_xz, com_acc : ndarray, shape (N, 4, 2)
        Segment centres of mass (m) and their accelerations (m/s^2), foot..HAT.
    reliable : ndarray, shape (N,), bool
        False where a marker lay in an unfilled gap or outside the marker
        recording's span.
    """

    t_s: np.ndarray
    points_xz: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    rho: np.ndarray
    rhod: np.ndarray
    com_xz: np.ndarray
    com_acc: np.ndarray
    reliable: np.ndarray

    def body_com_xz(self, model: BodyModel) -> np.ndarray:
        """Whole-body centre of mass (m), shape (N, 2): mass-weighted segment COMs."""
        m = np.array([s.mass_kg for s in model.segments])
        com: np.ndarray = np.einsum("s,nsk->nk", m, self.com_xz) / m.sum()
        return com


def sagittal_markers(markers: MarkerSeries) -> np.ndarray:
    """Contract markers as ``[x, z]``, shape (M, 6, 2) (m), in :data:`MARKER_NAMES` order.

    Raises ValueError naming any contract marker the series lacks.
    """
    missing = [n for n in MARKER_NAMES if n not in markers.names]
    if missing:
        raise ValueError(f"marker series lacks contract marker(s) {missing}; has {list(markers.names)}")
    idx = [markers.names.index(n) for n in MARKER_NAMES]
    return markers.positions_m[:, idx, :][:, :, [0, 2]]


def body_model_from_markers(
    subject: Subject, markers: MarkerSeries, overrides: dict[str, dict[str, float]] | None = None
) -> BodyModel:
    """de Leva model with segment lengths and foot triangle measured from the markers.

    Lengths are the medians, over frames where both end markers are visible,
    of the sagittal distances ankle-knee, knee-hip and hip-head; the foot
    triangle is the median toe, heel and ankle positions relative to the toe
    in the foot frame.

    Parameters
    ----------
    subject : Subject
        Mass, stature and sex.
    markers : MarkerSeries
    overrides : dict, optional
        Per-segment overrides (:func:`body_model.with_overrides`).
    """
    xz = sagittal_markers(markers)
    toe, heel, ankle, knee, hip, head = (xz[:, i, :] for i in range(6))

    def median_dist(a: np.ndarray, b: np.ndarray, name: str) -> float:
        d = np.hypot(*(b - a).T)
        d = d[np.isfinite(d)]
        if d.size == 0:
            raise ValueError(f"cannot measure the {name} length: its markers are never visible together")
        return float(np.median(d))

    lengths = {
        "shank": median_dist(ankle, knee, "shank"),
        "thigh": median_dist(knee, hip, "thigh"),
        "hat": median_dist(hip, head, "hat"),
    }
    ok = np.all(np.isfinite(np.stack([toe, heel, ankle], axis=1)), axis=(1, 2))
    if not ok.any():
        raise ValueError("cannot measure the foot: toe, heel and ankle markers are never visible together")
    e1 = ankle[ok] - toe[ok]
    e1 /= np.hypot(*e1.T)[:, None]
    e2 = np.column_stack([-e1[:, 1], e1[:, 0]])
    rel_a = ankle[ok] - toe[ok]
    rel_h = heel[ok] - toe[ok]
    ankle_local = np.array([np.median(np.sum(rel_a * e1, 1)), 0.0])
    heel_local = np.array([np.median(np.sum(rel_h * e1, 1)), np.median(np.sum(rel_h * e2, 1))])
    geometry = foot_geometry_from_points(np.zeros(2), heel_local, ankle_local)
    model = body_model(subject.body_mass_kg, lengths, geometry, subject.sex, subject.body_height_m)
    return with_overrides(model, overrides) if overrides else model


def segment_angles_from_points(points_xz: np.ndarray) -> np.ndarray:
    """q1..q4 (rad), shape (N, 4), from points toe, ankle, knee, hip, head, shape (N, 5, 2)."""
    return np.stack([segment_angle(points_xz[:, i], points_xz[:, i + 1]) for i in range(4)], axis=1)


def segment_coms(points_xz: np.ndarray, q: np.ndarray, model: BodyModel) -> np.ndarray:
    """Segment centres of mass (m), shape (N, 4, 2).

    Each COM is placed from the segment's distal point along the segment
    axis (angle q) by ``com_along_m`` and perpendicular (+90 deg) by ``com_perp_m``.
    """
    along = np.array([s.com_along_m for s in model.segments])
    perp = np.array([s.com_perp_m for s in model.segments])
    e1 = np.stack([np.cos(q), np.sin(q)], axis=-1)
    e2 = np.stack([-np.sin(q), np.cos(q)], axis=-1)
    coms: np.ndarray = points_xz[:, :4, :] + along[None, :, None] * e1 + perp[None, :, None] * e2
    return coms


def _evaluate_spline(
    spline: CubicSpline, t: np.ndarray, columns: tuple[slice, slice, slice] = (slice(None),) * 3
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Value, first and second derivative of a cubic spline at ``t`` (inside its breakpoints).

    Same numbers as ``spline(t, nu)`` for nu = 0, 1, 2 (to rounding), but the
    interval search is done once, and each derivative order is one sparse
    matrix (4 non-zeros per output sample: the powers of the local offset)
    times the spline's coefficient table: about 2x faster than three calls
    of ``spline(t, nu)`` on long records. ``columns`` selects which columns
    are needed for each order.
    """
    x, c = spline.x, spline.c  # c: (4, M - 1, columns), highest power first
    m = len(x) - 1
    idx = np.clip(np.searchsorted(x, t, side="right") - 1, 0, m - 1)
    dx = t - x[idx]
    one, zero = np.ones_like(dx), np.zeros_like(dx)
    indices = (np.arange(4)[None, :] * m + idx[:, None]).ravel()
    indptr = np.arange(0, 4 * t.size + 1, 4)
    table = c.reshape(4 * m, -1)
    weights = (
        (dx**3, dx**2, dx, one),
        (3 * dx**2, 2 * dx, one, zero),
        (6 * dx, 2 * one, zero, zero),
    )
    return tuple(
        csr_matrix((np.column_stack(w).ravel(), indices, indptr), shape=(t.size, 4 * m)) @ np.ascontiguousarray(table[:, cols])
        for w, cols in zip(weights, columns)
    )


def compute_kinematics(
    marker_t_s: np.ndarray,
    markers_xz: np.ndarray,
    t_out_s: np.ndarray,
    model: BodyModel,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
) -> tuple[Kinematics, list[Gap]]:
    """Filtered kinematics resampled onto ``t_out_s`` (see the module docstring).

    Parameters
    ----------
    marker_t_s : ndarray, shape (M,)
        Marker times (s), uniformly sampled.
    markers_xz : ndarray, shape (M, 6, 2)
        Sagittal markers in :data:`MARKER_NAMES` order (m); NaN = occluded.
    t_out_s : ndarray, shape (N,)
        Output times (s), e.g. the force-plate stamps on the same clock.
    model : BodyModel
    cutoff_hz, max_gap_s : float
        Low-pass cut-off (Hz) and longest filled gap (s).

    Returns
    -------
    Kinematics
        On ``t_out_s``; NaN and ``reliable=False`` outside the marker span.
    list of Gap
        Gaps found (column = marker index in :data:`MARKER_NAMES`).
    """
    smooth, reliable_m, gaps = _filled_filtered_markers(marker_t_s, markers_xz, cutoff_hz, max_gap_s)
    points = smooth[:, _POINT_IDX, :]
    q = segment_angles_from_points(points)
    com = segment_coms(points, q, model)
    t_out = np.asarray(t_out_s, float)
    inside = (t_out >= marker_t_s[0]) & (t_out <= marker_t_s[-1])
    value, rate, accel = _splined_signals(marker_t_s, points, q, com, t_out[inside])
    qv = _on_output(value[:, _Q_COLUMNS], (4,), inside)
    qd = _on_output(rate, (4,), inside)
    kin = Kinematics(
        t_s=t_out,
        points_xz=_on_output(value[:, _POINT_COLUMNS], (5, 2), inside),
        q=qv,
        qd=qd,
        qdd=_on_output(accel[:, :4], (4,), inside),
        rho=joint_angles(qv, model.foot_geometry.alpha_rad),
        rhod=joint_rates(qd),
        com_xz=_on_output(value[:, _COM_COLUMNS], (4, 2), inside),
        com_acc=_on_output(accel[:, 4:], (4, 2), inside),
        reliable=_reliable_on_output(marker_t_s, reliable_m, t_out, inside),
    )
    return kin, gaps


def wrench_through_marker_chain(
    force_t_s: np.ndarray, wrench: np.ndarray, measured_t_s: np.ndarray, filter_t_s: np.ndarray, cutoff_hz: float
) -> np.ndarray:
    """The ground wrench processed as the marker kinematics are: their sampling, their filter, their spline.

    Inverse dynamics balances the wrench against segment accelerations from
    positions sampled once per marker frame, low-passed on the markers' grid,
    differentiated twice through a cubic spline (:func:`compute_kinematics`). Low-passing the 1 kHz wrench at the same
    cut-off on its own clock (Bisseling & Hof 2006; Kristianslund et al.
    2012) is another filter (a 40 Hz Butterworth at 100 Hz is warped towards
    Nyquist; the spline puts knots every marker period): the touchdown step
    then left a +-20 % of peak oscillation in the hip moment of a noise-free
    simulated stance (docs/impedance_model.md, "Stance edges").

    Rule (choice): the wrench passes the markers' own chain. Its double time
    integral (for the force, mass times the centre-of-mass path: a position,
    as a marker is), exact for the wrench linear between plate samples, is
    sampled at ``measured_t_s`` (the stamps the markers were measured at),
    interpolated by cubic spline onto ``filter_t_s`` when the markers were
    resampled before filtering (the per-leg rigid fit's 1 kHz grid), low-passed
    there at ``cutoff_hz`` by :func:`lowpass`, and differentiated twice
    through the cubic spline on those samples at the plate times. A force
    that varies slowly across a marker frame comes back as the low-pass of
    itself (the spline reproduces cubics); a step is spread as the kinematics
    spread an acceleration step. Plate times outside the marker grid, and a
    cut-off at or above that grid's Nyquist frequency (the markers cannot
    carry it), fall back to :func:`lowpass` on the plate clock (what the
    analysis did before 2026-11-24).

    Parameters
    ----------
    force_t_s : ndarray, shape (N,)
        Plate times (s), uniformly sampled.
    wrench : ndarray, shape (N, C)
        Zeroed wrench on those times.
    measured_t_s : ndarray, shape (M,)
        Times (s) the markers were measured at, same clock.
    filter_t_s : ndarray, shape (K,)
        Times (s) of the grid the markers are low-passed on (``measured_t_s`` unless they were resampled).
    cutoff_hz : float
        Low-pass cut-off (Hz).

    Returns
    -------
    ndarray, shape (N, C)
    """
    t = np.asarray(force_t_s, float)
    f: np.ndarray = np.asarray(wrench, float)
    out: np.ndarray = lowpass(f, sampling_rate_hz(t), cutoff_hz)
    tm = np.asarray(measured_t_s, float)
    tm = tm[(tm >= t[0]) & (tm <= t[-1])]
    tg = np.asarray(filter_t_s, float)
    tg = tg[(tg >= max(t[0], tm[0] if tm.size else np.inf)) & (tg <= min(t[-1], tm[-1] if tm.size else -np.inf))]
    if tm.size < 4 or tg.size < 8 or not cutoff_hz < sampling_rate_hz(tg) / 2:
        return out
    sampled = _double_integral_at(t, f, tm)
    on_grid = sampled if tg.size == tm.size and np.allclose(tg, tm) else CubicSpline(tm, sampled, axis=0)(tg)
    inside = (t >= tg[0]) & (t <= tg[-1])
    out[inside] = CubicSpline(tg, _lowpassed_positions(on_grid, tg, cutoff_hz), axis=0)(t[inside], 2)
    return out


def _double_integral_at(t: np.ndarray, f: np.ndarray, at_s: np.ndarray) -> np.ndarray:
    """Double time integral from ``t[0]`` of ``f`` (N, C), exact for ``f`` linear between its samples ``t``, at ``at_s``."""
    h = np.diff(t)[:, None]
    i1 = np.concatenate([np.zeros((1, f.shape[1])), np.cumsum(h * (f[:-1] + f[1:]) / 2, axis=0)])
    i2 = np.concatenate([np.zeros((1, f.shape[1])), np.cumsum(i1[:-1] * h + h**2 * (2 * f[:-1] + f[1:]) / 6, axis=0)])
    k = np.clip(np.searchsorted(t, at_s, side="right") - 1, 0, t.size - 2)
    dt = (at_s - t[k])[:, None]
    out: np.ndarray = i2[k] + i1[k] * dt + f[k] * dt**2 / 2 + (f[k + 1] - f[k]) / h[k] * dt**3 / 6
    return out


def _lowpassed_positions(y: np.ndarray, grid_s: np.ndarray, cutoff_hz: float) -> np.ndarray:
    """``y`` (K, C) on the uniform ``grid_s`` low-passed as far as a cubic spline's second derivative can tell.

    The low-pass runs on the second differences (the wrench as the grid sees
    it: bounded, where its double integral grows without bound over a
    recording and filtering it lost up to 6 significant digits), with which
    it commutes; a spline's second derivative depends only on second
    differences, so the sequence rebuilt from the filtered ones (up to a
    linear part) gives the same one.
    """
    hg = float(np.median(np.diff(grid_s)))
    smooth = lowpass(np.diff(y, 2, axis=0) / hg**2, 1.0 / hg, cutoff_hz)
    rebuilt: np.ndarray = np.zeros_like(y)
    rebuilt[2:] = np.cumsum(np.cumsum(smooth * hg**2, axis=0), axis=0)
    return rebuilt


def measured_marker_times(marker_t_s: np.ndarray, measured_rate_hz: float | None) -> np.ndarray:
    """Times (s) the markers were measured at: their own stamps, or, for markers resampled from a
    measurement at ``measured_rate_hz`` (the per-leg rigid-fit markers on a 1 kHz grid), every
    1 / ``measured_rate_hz`` s from the first one."""
    tm = np.asarray(marker_t_s, float)
    return tm if measured_rate_hz is None else uniform_times(float(tm[0]), float(tm[-1]), measured_rate_hz)


def _filled_filtered_markers(
    marker_t_s: np.ndarray, markers_xz: np.ndarray, cutoff_hz: float, max_gap_s: float
) -> tuple[np.ndarray, np.ndarray, list[Gap]]:
    """Steps 2 and 3 of the module docstring: gaps filled, then the zero-lag low-pass at the marker rate.

    Returns the filtered markers (m), shape (M, 6, 2), the per-frame
    reliability of each marker from
    :func:`~hop_impedance.biomech.filtering.fill_gaps`, shape (M, 6), and the
    gaps found. Raises ValueError for fewer than 8 frames or a marker that is
    never visible.
    """
    if len(marker_t_s) < 8:
        raise ValueError(f"need at least 8 marker frames, got {len(marker_t_s)}")
    filled, reliable_m, gaps = fill_gaps(marker_t_s, markers_xz, max_gap_s)
    if not np.all(np.isfinite(filled)):
        bad = [MARKER_NAMES[c] for c in range(filled.shape[1]) if not np.isfinite(filled[:, c]).all()]
        raise ValueError(f"marker(s) {bad} never visible: cannot compute kinematics")
    fs = sampling_rate_hz(marker_t_s)
    return lowpass(filled, fs, cutoff_hz), reliable_m, gaps


#: Columns of the one spline through every signal (:func:`_splined_signals`): points, q, segment COMs.
_POINT_COLUMNS, _Q_COLUMNS, _COM_COLUMNS = slice(0, 10), slice(10, 14), slice(14, 22)


def _splined_signals(
    marker_t_s: np.ndarray, points: np.ndarray, q: np.ndarray, com: np.ndarray, t_in: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 5 of the module docstring: one cubic spline through every signal, evaluated at ``t_in``.

    ``t_in`` are the output times inside the marker span. Columns as in
    ``_POINT_COLUMNS``, ``_Q_COLUMNS``, ``_COM_COLUMNS``: points (10), q (4),
    COM (8). Only what the dynamics need is evaluated: all values (22
    columns); rates of q (4); accelerations of q and the COMs (12, q first).
    """
    n_m = len(marker_t_s)
    stacked = np.concatenate([points.reshape(n_m, -1), q, com.reshape(n_m, -1)], axis=1)
    spline = CubicSpline(marker_t_s, stacked, axis=0)
    return _evaluate_spline(spline, t_in, (slice(None), _Q_COLUMNS, slice(10, 22)))


def _on_output(values: np.ndarray, shape: tuple[int, ...], inside: np.ndarray) -> np.ndarray:
    """``values`` (one row per output time inside the marker span) on every output time, NaN outside.

    ``inside`` (bool, one per output time) marks the output times in the
    marker span; each row is reshaped to ``shape``.
    """
    if len(values) == inside.size:
        return np.ascontiguousarray(values).reshape((-1,) + shape)
    full = np.full((inside.size,) + shape, np.nan)
    full[inside] = values.reshape((-1,) + shape)
    return full


def _reliable_on_output(marker_t_s: np.ndarray, reliable_m: np.ndarray, t_out: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Reliability on the output times: a frame is reliable if the nearest marker frames on both sides were.

    A marker frame is reliable when every marker is (``reliable_m``, shape
    (M, 6)); output times outside the marker span are not reliable.
    """
    ok_m = np.all(reliable_m, axis=1).astype(float)
    reliable = np.zeros(t_out.size, bool)
    reliable[inside] = np.interp(t_out[inside], marker_t_s, ok_m) >= 1.0
    return reliable
