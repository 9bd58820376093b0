"""Synthetic data with known answers for the biomechanics tests.

- :func:`pinned_chain`: the four-segment model with the toe pinned at a fixed
  point and smooth prescribed segment angles; positions, accelerations and the
  ground wrench are analytic (forward Newton-Euler: the ground supplies the
  whole body's rate of change of linear and angular momentum), and the true
  joint moments come from a *top-down* Newton-Euler pass starting at the HAT,
  which never uses the ground reaction force. Our bottom-up inverse dynamics
  must reproduce them.
- :func:`hopping_recording`: a contract :class:`Recording` of periodic hops
  (half-sine vertical force, flights, plate offset and drift, a moving
  centre of pressure, six markers) for detection, zeroing, streaming and CLI
  tests. Its joint motion is smooth but not dynamically consistent with the
  force, so it is *not* used to check moment values.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.biomech.body_model import body_model, foot_geometry_from_points
from hop_impedance.recording import GRAVITY_M_S2, MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording, Subject

G = np.array([0.0, -GRAVITY_M_S2])

#: Mean posture q1..q4 (rad): foot toe->ankle pointing up and back, shank
#: leaning forward, thigh back, trunk slightly forward.
Q_MEAN = np.array([2.55, 1.35, 1.95, 1.45])
Q_AMP = np.array([0.15, 0.25, 0.30, 0.10])
Q_PHASE = np.array([0.0, 0.4, 0.9, 1.5])


def make_model(mass_kg: float = 60.0, height_m: float = 1.65):
    """A de Leva model with fixed lengths and a foot triangle (heel 0.15 m behind the toe)."""
    geom = foot_geometry_from_points(np.zeros(2), np.array([-0.15, 0.0]), np.array([-0.12, 0.08]))
    return body_model(mass_kg, {"shank": 0.42, "thigh": 0.40, "hat": 0.75}, geom, "female", height_m)


def angles(t: np.ndarray, freq_hz: float = 2.0):
    """q, qd, qdd (rad, rad/s, rad/s^2), each shape (N, 4): sinusoids about Q_MEAN."""
    w = 2 * np.pi * freq_hz
    arg = w * t[:, None] + Q_PHASE
    q = Q_MEAN + Q_AMP * np.sin(arg)
    qd = Q_AMP * w * np.cos(arg)
    qdd = -Q_AMP * w**2 * np.sin(arg)
    return q, qd, qdd


def _e(q):
    return np.stack([np.cos(q), np.sin(q)], axis=-1)


def _n(q):
    return np.stack([-np.sin(q), np.cos(q)], axis=-1)


def _cross(r, f):
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def pinned_chain(t: np.ndarray, model, toe_xz=(0.05, 0.0), freq_hz: float = 2.0) -> dict:
    """Analytic kinematics, ground wrench and top-down joint moments (see module docstring).

    Returns a dict with points (N,5,2), q, qd, qdd (N,4), com, com_acc
    (N,4,2), wrench (N,3) = [Fx, Fz, Mo ccw about the origin], moment_ccw
    (N,3) = couple of proximal on distal segment at ankle, knee, hip.
    """
    q, qd, qdd = angles(t, freq_hz)
    n = t.size
    segs = model.segments
    lengths = [model.foot_geometry.toe_ankle_m, segs[1].length_m, segs[2].length_m, segs[3].length_m]
    p = np.zeros((n, 5, 2))
    pa = np.zeros((n, 5, 2))
    p[:, 0] = toe_xz
    for i in range(4):
        e, nn = _e(q[:, i]), _n(q[:, i])
        p[:, i + 1] = p[:, i] + lengths[i] * e
        pa[:, i + 1] = pa[:, i] + lengths[i] * (qdd[:, i, None] * nn - qd[:, i, None] ** 2 * e)
    com = np.zeros((n, 4, 2))
    acc = np.zeros((n, 4, 2))
    for i, s in enumerate(segs):
        e, nn = _e(q[:, i]), _n(q[:, i])
        com[:, i] = p[:, i] + s.com_along_m * e + s.com_perp_m * nn
        acc[:, i] = (
            pa[:, i]
            + s.com_along_m * (qdd[:, i, None] * nn - qd[:, i, None] ** 2 * e)
            + s.com_perp_m * (-qdd[:, i, None] * e - qd[:, i, None] ** 2 * nn)
        )
    m = np.array([s.mass_kg for s in segs])
    inertia = np.array([s.inertia_kgm2 for s in segs])
    lin = m[None, :, None] * (acc - G)
    force = lin.sum(axis=1)
    mo = (_cross(com, lin) + inertia * qdd).sum(axis=1)
    # Top-down: the couple/force of the proximal segment on the distal one at hip, knee, ankle.
    moment = np.zeros((n, 3))
    f_on = lin[:, 3]  # force of the thigh on the HAT at the hip
    c_on = inertia[3] * qdd[:, 3] - _cross(p[:, 3] - com[:, 3], f_on)
    for j in (2, 1, 0):  # the segment below the joint j+1 ... walk down
        moment[:, j] = -c_on  # on segment j from segment j+1
        f_prox, c_prox = -f_on, -c_on
        f_dist = lin[:, j] - f_prox
        c_dist = inertia[j] * qdd[:, j] - c_prox - _cross(p[:, j + 1] - com[:, j], f_prox) - _cross(p[:, j] - com[:, j], f_dist)
        f_on, c_on = f_dist, c_dist
    # After the foot, (f_on, c_on) is the ground load at the toe: a check of the wrench.
    return {
        "points": p,
        "q": q,
        "qd": qd,
        "qdd": qdd,
        "com": com,
        "com_acc": acc,
        "wrench": np.column_stack([force, mo]),
        "moment_ccw": moment,
        "ground_at_toe": (f_on, c_on),
    }


def markers_from_points(points: np.ndarray, model) -> np.ndarray:
    """Six contract markers (M, 6, 3) from toe, ankle, knee, hip, head points (M, 5, 2) (y = 0.1 m)."""
    g = model.foot_geometry
    e = points[:, 1] - points[:, 0]
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    nn = np.stack([-e[:, 1], e[:, 0]], axis=1)
    heel = points[:, 0] + g.heel_along_m * e + g.heel_perp_m * nn
    xz = np.stack([points[:, 0], heel, points[:, 1], points[:, 2], points[:, 3], points[:, 4]], axis=1)
    out = np.full(xz.shape[:2] + (3,), 0.1)
    out[..., 0], out[..., 2] = xz[..., 0], xz[..., 1]
    return out


def hopping_recording(
    duration_s: float = 4.0,
    hop_hz: float = 2.0,
    contact_s: float = 0.30,
    first_touchdown_s: float = 0.25,
    mass_kg: float = 60.0,
    force_hz: float = 1000.0,
    marker_hz: float = 100.0,
    offset_n: float = 8.0,
    drift_n_per_s: float = 2.0,
    noise_n: float = 2.0,
    seed: int = 0,
    cut_end: bool = False,
    start_ns: int = 1_700_000_000_000_000_000,
) -> tuple[Recording, list[tuple[float, float]]]:
    """Periodic hops; returns the recording and the true (touchdown, take-off) times (s since start).

    Vertical force in stance: a half sine whose impulse gives a symmetric
    ballistic flight (peak = pi/2 * m g * period / contact). Joint angles are
    :func:`angles` with the toe pinned during stance and lifted by a smooth
    bump in flight. ``cut_end`` lets a last stance run past the end.
    """
    rng = np.random.default_rng(seed)
    model = make_model(mass_kg)
    period = 1.0 / hop_hz
    t = np.arange(0.0, duration_s, 1.0 / force_hz)
    events = []
    td = first_touchdown_s
    while td + contact_s < duration_s or (cut_end and td < duration_s):
        events.append((td, td + contact_s))
        td += period
    peak = np.pi / 2 * mass_kg * GRAVITY_M_S2 * period / contact_s
    fz = np.zeros_like(t)
    for a, b in events:
        sel = (t >= a) & (t <= b)
        fz[sel] = peak * np.sin(np.pi * (t[sel] - a) / contact_s)
    cop = 0.05 - 0.06 * np.cos(np.pi * np.clip((t - first_touchdown_s) % period / contact_s, 0, 1))
    fx = 0.05 * fz * np.sin(2 * np.pi * hop_hz * t)
    force = np.zeros((t.size, 3))
    force[:, 0] = fx + rng.normal(0, noise_n, t.size)
    force[:, 2] = fz + offset_n + drift_n_per_s * t + rng.normal(0, noise_n, t.size)
    torque = np.zeros((t.size, 3))
    torque[:, 1] = -cop * fz + rng.normal(0, 0.2, t.size)
    tm = np.arange(0.0, duration_s, 1.0 / marker_hz)
    chain = pinned_chain(tm, model, freq_hz=hop_hz)
    pts = chain["points"].copy()
    phase = (tm - first_touchdown_s) % period
    flight = phase > contact_s
    lift = np.where(flight, 0.08 * np.sin(np.pi * (phase - contact_s) / (period - contact_s)) ** 2, 0.0)
    pts[..., 1] += lift[:, None]
    markers = MarkerSeries(start_ns + np.round(tm * 1e9).astype(np.int64), MARKER_NAMES, markers_from_points(pts, model))
    rec = Recording(
        ForcePlateSeries(start_ns + np.round(t * 1e9).astype(np.int64), force, torque),
        markers,
        Subject("synthetic", mass_kg, 1.65),
        source="synthetic hopping",
    )
    return rec, events


def push_in_chunks(stage, data, edges_s: np.ndarray):
    """Feed ``data`` (a SpanData) to a StanceAnalysisStage between consecutive ``edges_s`` (s).

    Yields ``(chunk end s, stances the chunk completed)`` per chunk, as a live
    node would see them; the caller flushes the stage at the end.
    """
    fi, mi = np.searchsorted(data.force_t_s, edges_s), np.searchsorted(data.marker_t_s, edges_s)
    for i in range(len(edges_s) - 1):
        yield edges_s[i + 1], stage.push(
            (data.force_t_s[fi[i] : fi[i + 1]], data.wrench[fi[i] : fi[i + 1]]),
            (data.marker_t_s[mi[i] : mi[i + 1]], data.markers_xz[mi[i] : mi[i + 1]]),
        )
