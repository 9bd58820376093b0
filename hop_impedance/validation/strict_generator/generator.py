"""Strict stance family (issue 16): lossless, time-symmetric stances from random mid-stance postures.

Model (sagittal plane, subject facing +x, both legs lumped)
----------------------------------------------------------
Coordinates in stance ``q = [z_toe, a, r1, r2, r3]``: toe height (m; the toe's x is pinned, the
horizontal ground force is the constraint force), the foot's toe->ankle line angle ``a`` from +x, and
relative angles ``r1 = th_shank - a``, ``r2 = th_thigh - th_shank``, ``r3 = th_hat - th_thigh``
(each ``th`` the absolute direction of the distal->proximal segment vector). Flexion of each joint is
``phi_j = s_j (r_j - r_j,mid)`` with ``s = (-1, +1, -1)`` (dorsiflexion, knee flexion, hip flexion).
Joint law (extensor moment, conservative): ``M_j = M_mid_j + k0_j dphi + k1_j dphi^2 / 2`` with
``dphi = phi_j - phi_mid_j``, acting on ``r_j`` as the generalised force ``-s_j M_j``; ground
``Fz = K_GROUND |z_toe|^1.5`` for ``z_toe < 0`` (no damper). With ``k1 = 0`` this is the strict
baseline ``M = M_td + K phi`` of the outside generator; ``k1 > 0`` is an angle-dependent stiffness
(stiffness ``k0 + k1 dphi`` kept >= 0 over the stance, seed 000's Eq. 7: a draw that breaks it is re-drawn).
Where ``k1`` is referenced (``StrictConfig.angle_reference``): at touchdown, as seed 000's Eq. 10 (``rho_j0`` "at
the beginning of the stance phase") and the outside generator have it, the stiffness at touchdown ``k0 - k1 phi_mid``
is one number per recording and joint; the mid-stance form above then carries a per-stance ``k0`` that is found by a
fixed-point iteration over ``phi_mid`` (:func:`_stance`). Sessions 15-17 referenced ``k1`` to mid-stance (one ``k0``
there per recording, so the touchdown stiffness varied from stance to stance with ``phi_mid``).

Equations of motion: segment centre-of-mass positions and angles are written in ``q`` with sympy; the
mass matrix is ``sum m J^T J + I j^T j`` and the velocity term ``sum m J^T (dJ/dt qd) + ...`` (Kane's
projection), lambdified to numpy. Integrated with ``scipy.integrate.solve_ivp(method="DOP853")``.

Joint stiffness ``k0`` is drawn once per recording (one subject, one law), as in the outside generator
(its nulls' truth files hold one ``kc`` per recording and a different ``M_td`` per hop). A stiffness that
changes from stance to stance is not the strict baseline but an effect of its own: it is available as
``StrictConfig.stiffness_spread`` (off by default) to measure what the discovery does with it.

Stances are time-symmetric by construction: each starts at a random mid-stance posture with all
velocities zero (moments set so the joints do not accelerate there), is integrated forward to take-off
and mirrored (``q(-t) = q(t)``). Flights join take-off and the next touchdown by cubic Hermite curves
in every coordinate (smooth, not ballistic; duration from the vertical COM speeds), no plate force.

Sensors: 1 kHz plate (force noise 2 N, torque noise 0.5 N m), 100 Hz markers (1 mm noise, random
sampling phase), optional plate offset and marker latency.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from hop_impedance.ode_events import TerminalEvent
from hop_impedance.recording import MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording, Subject

G = 9.81
#: Lossless near-rigid ground: Fz = K_GROUND |y|^1.5 (N, m); ~3 mm sink at 3 body weights.
K_GROUND = 1.0e7
GROUND_EXP = 1.5
#: Flexion sign of each relative angle (ankle, knee, hip).
FLEX_SIGN = np.array([-1.0, 1.0, -1.0])
#: Winter (2009) segment table, both legs lumped: mass fraction, length / height, COM from the distal
#: end / length, radius of gyration / length. HAT length = hip to head marker.
WINTER = {
    "foot": (2 * 0.0145, 0.152, 0.50, 0.475),
    "shank": (2 * 0.0465, 0.246, 0.567, 0.302),
    "thigh": (2 * 0.100, 0.245, 0.567, 0.323),
    "hat": (0.678, 0.40, 0.374, 0.496),
}
ANKLE_HEIGHT_H = 0.039
#: Ankle's position along the sole from the toe (share of foot length).
ANKLE_ALONG = 0.75


#: Where the angle law's ``k1`` is referenced (``StrictConfig.angle_reference``).
ANGLE_REFERENCES = ("touchdown", "mid-stance")


@dataclass(frozen=True)
class StrictConfig:
    """One strict recording.

    Attributes
    ----------
    hops : int
    seed : int
    angle_k1 : float
        Angle-dependent stiffness (1/rad) on every joint (0 = strict baseline); its reference is ``angle_reference``.
    angle_reference : str
        ``"touchdown"`` (the default since session 18; seed 000's Eq. 10): ``K = k_td (1 + angle_k1 phi)`` with
        ``phi`` the flexion from touchdown and ``k_td = k0 / (1 + angle_k1 PHI_MID_TYPICAL)`` one number per
        recording and joint (so that the mid-stance stiffness of a typical stance stays the recording's ``k0``,
        as in the strict null); ``K`` grows from touchdown to mid-stance and stays > 0. ``"mid-stance"``
        (sessions 15-17): ``k1 = angle_k1 * k0`` referenced to mid-stance (maximal flexion), so the stiffness
        falls towards touchdown and take-off, ``K = k0 (1 - angle_k1 R)`` at an extension ``R`` from mid-stance;
        a draw in which ``K`` turns negative anywhere in the stance (against seed 000's Eq. 7) is re-drawn, so
        ``angle_k1`` must stay below ``1 / R`` of the joint that moves most (the ankle, R 0.8-0.9 rad here).
    force_offset_n : float
        Constant added to the plate Fz (N).
    marker_latency_s : float
        Markers show the body this much later than the plate (s).
    mass_kg, height_m : float
    stiffness_spread : float
        Stance-to-stance spread of ``k0`` around the recording's value: each stance's ``k0`` is the recording's
        times ``1 + stiffness_spread * U(-1, 1)`` per joint (0 = one law per recording, the strict baseline).
    """

    hops: int = 8
    seed: int = 0
    angle_k1: float = 0.0
    angle_reference: str = "touchdown"
    force_offset_n: float = 0.0
    marker_latency_s: float = 0.0
    mass_kg: float = 60.0
    height_m: float = 1.65
    force_noise_n: float = 2.0
    torque_noise_nm: float = 0.5
    marker_noise_m: float = 0.001
    stiffness_spread: float = 0.0

    def __post_init__(self) -> None:
        if self.angle_reference not in ANGLE_REFERENCES:
            raise ValueError(f"strict generator: angle_reference {self.angle_reference!r} (one of {ANGLE_REFERENCES})")

    @property
    def effects(self) -> list[str]:
        """Effect names (issue 8 spelling) this configuration hides."""
        out = []
        if self.angle_k1:
            out.append("angle_dependent_stiffness")
        if self.force_offset_n:
            out.append("force_plate_offset")
        if self.marker_latency_s:
            out.append("stream_latency")
        return out


@dataclass(frozen=True)
class Body:
    """Perturbed segment parameters (SI): per segment foot, shank, thigh, hat."""

    mass: np.ndarray
    length: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    sole: float
    ankle_height: float

    def as_tuple(self) -> tuple:
        return (tuple(self.mass), tuple(self.length), tuple(self.com), tuple(self.inertia), self.sole, self.ankle_height)


def perturbed_body(mass_kg: float, height_m: float, rng: np.random.Generator) -> Body:
    """Winter's table with every entry scaled by U(0.95, 1.05); masses renormalised to the body mass."""
    table = np.array(list(WINTER.values()))
    f = rng.uniform(0.95, 1.05, table.shape)
    t = table * f
    mass = t[:, 0] / t[:, 0].sum() * mass_kg
    length = t[:, 1] * height_m
    sole = length[0]
    ankle_h = ANKLE_HEIGHT_H * height_m * rng.uniform(0.95, 1.05)
    length[0] = np.hypot(ANKLE_ALONG * sole, ankle_h)  # toe -> ankle line
    com = t[:, 2]
    inertia = mass * (t[:, 3] * np.r_[sole, length[1:]]) ** 2
    return Body(mass, length, com, inertia, sole, ankle_h)


@lru_cache(maxsize=8)
def _equations(body_key: tuple):
    """Lambdified ``M(q)``, ``h(q, qd)`` (velocity + gravity terms), COM accelerations and marker points."""
    mass, length, com, inertia, sole, ankle_h = body_key
    z, a, r1, r2, r3 = q = sp.symbols("z a r1 r2 r3")
    qd = sp.symbols("zd ad r1d r2d r3d")
    a0 = sp.atan2(ankle_h, -ANKLE_ALONG * sole)  # toe->ankle direction with the sole flat

    def rot(v, ang):
        return sp.Matrix([v[0] * sp.cos(ang) - v[1] * sp.sin(ang), v[0] * sp.sin(ang) + v[1] * sp.cos(ang)])

    toe = sp.Matrix([0, z])
    tilt = a - a0
    ankle = toe + length[0] * sp.Matrix([sp.cos(a), sp.sin(a)])
    heel = toe + rot((-sole, 0), tilt)
    foot_com = toe + rot((-com[0] * sole, 0.35 * ankle_h), tilt)
    th = [a + r1, a + r1 + r2, a + r1 + r2 + r3]
    knee = ankle + length[1] * sp.Matrix([sp.cos(th[0]), sp.sin(th[0])])
    hip = knee + length[2] * sp.Matrix([sp.cos(th[1]), sp.sin(th[1])])
    head = hip + length[3] * sp.Matrix([sp.cos(th[2]), sp.sin(th[2])])
    coms = [foot_com,
            ankle + com[1] * length[1] * sp.Matrix([sp.cos(th[0]), sp.sin(th[0])]),
            knee + com[2] * length[2] * sp.Matrix([sp.cos(th[1]), sp.sin(th[1])]),
            hip + com[3] * length[3] * sp.Matrix([sp.cos(th[2]), sp.sin(th[2])])]
    angles = [a] + th
    qv, qdv = sp.Matrix(q), sp.Matrix(qd)
    mm = sp.zeros(5, 5)
    h = sp.zeros(5, 1)
    acc_bias = []
    jac = []
    for m, c, ang, inert in zip(mass, coms, angles, inertia):
        j = c.jacobian(qv)
        bias = (j * qdv).jacobian(qv) * qdv  # dJ/dt qd
        jw = sp.Matrix([[sp.diff(ang, v) for v in q]])  # angle rates are constant combinations: no bias
        mm += m * j.T * j + inert * jw.T * jw
        h += m * j.T * bias + m * j.T * sp.Matrix([0, G])
        acc_bias.append(bias)
        jac.append(j)
    args = (q, qd)
    f_m = sp.lambdify(args, mm, "numpy", cse=True)
    f_h = sp.lambdify(args, h, "numpy", cse=True)
    f_j = sp.lambdify(args, jac, "numpy", cse=True)
    f_b = sp.lambdify(args, acc_bias, "numpy", cse=True)
    f_pts = sp.lambdify((q,), [toe, heel, ankle, knee, hip, head], "numpy", cse=True)
    f_com = sp.lambdify((q,), coms, "numpy", cse=True)
    return f_m, f_h, f_j, f_b, f_pts, f_com, np.array(mass)


class StanceModel:
    """Right-hand side of one stance: body, joint law around the mid-stance state."""

    def __init__(self, body: Body, r_mid: np.ndarray, m_mid: np.ndarray, k0: np.ndarray, k1: np.ndarray):
        self.f_m, self.f_h, self.f_j, self.f_b, self.f_pts, self.f_com, self.mass = _equations(body.as_tuple())
        self.r_mid, self.m_mid, self.k0, self.k1 = r_mid, m_mid, k0, k1

    def moments(self, r: np.ndarray) -> np.ndarray:
        """Extensor moments (N m) at relative angles ``r``."""
        d = FLEX_SIGN * (np.asarray(r) - self.r_mid)
        return self.m_mid + self.k0 * d + self.k1 * d**2 / 2

    @staticmethod
    def ground(z: float) -> float:
        return K_GROUND * (-z) ** GROUND_EXP if z < 0 else 0.0

    def generalised_forces(self, q: np.ndarray) -> np.ndarray:
        return np.r_[self.ground(q[0]), 0.0, -FLEX_SIGN * self.moments(q[2:])]

    def accelerations(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        mm = np.asarray(self.f_m(q, qd), float)
        h = np.asarray(self.f_h(q, qd), float).ravel()
        return np.linalg.solve(mm, self.generalised_forces(q) - h)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        return np.r_[y[5:], self.accelerations(y[:5], y[5:])]

    def horizontal_force(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> float:
        """Ground's horizontal force on the body (N): total horizontal momentum rate."""
        jac, bias = self.f_j(q, qd), self.f_b(q, qd)
        return float(sum(m * (np.asarray(j, float)[0] @ qdd + float(np.asarray(b, float)[0, 0]))
                         for m, j, b in zip(self.mass, jac, bias)))

    def energy_j(self, q: np.ndarray, qd: np.ndarray) -> float:
        """Total mechanical energy (J): kinetic + gravity + ground spring + joint springs (conserved)."""
        kinetic = 0.5 * qd @ np.asarray(self.f_m(q, qd), float) @ qd
        gravity = G * sum(m * np.asarray(c, float)[1, 0] for m, c in zip(self.mass, self.f_com(q)))
        ground = K_GROUND * (-q[0]) ** (GROUND_EXP + 1) / (GROUND_EXP + 1) if q[0] < 0 else 0.0
        d = FLEX_SIGN * (np.asarray(q[2:]) - self.r_mid)
        joints = float(np.sum(self.m_mid * d + self.k0 * d**2 / 2 + self.k1 * d**3 / 6))
        return float(kinetic + gravity + ground + joints)

    def com_x(self, q: np.ndarray) -> float:
        return float(sum(m * np.asarray(c, float)[0, 0] for m, c in zip(self.mass, self.f_com(q))) / self.mass.sum())

    def com_z_rate(self, q: np.ndarray, qd: np.ndarray) -> float:
        return float(sum(m * (np.asarray(j, float)[1] @ qd) for m, j in zip(self.mass, self.f_j(q, qd))) / self.mass.sum())


#: Nominal joint stiffness (N m/rad; ankle, knee, hip) before the per-recording draw U(0.8, 1.2).
K0_NOMINAL = np.array([250.0, 250.0, 150.0])


def recording_stiffness(rng: np.random.Generator) -> np.ndarray:
    """The recording's joint stiffness ``k0`` (N m/rad): :data:`K0_NOMINAL` times U(0.8, 1.2) per joint."""
    return K0_NOMINAL * rng.uniform(0.8, 1.2, 3)


#: Typical flexion at mid-stance from touchdown (rad; ankle, knee, hip): the medians of the strict null's draws
#: (seeds 0-3: 0.72 / 0.41 / 0.13), used only to scale the touchdown-referenced angle law's ``k_td`` so that a
#: typical stance's mid-stance stiffness is the recording's ``k0`` (``StrictConfig.angle_reference``).
PHI_MID_TYPICAL = np.array([0.72, 0.41, 0.13])


def _mid_posture(body: Body, rng: np.random.Generator, cfg: StrictConfig, k0_rec: np.ndarray):
    """Random mid-stance state at rest and the law that holds the joints still there.

    ``k0``/``k1`` returned are the mid-stance form's with the recording's (or the stance's, with
    ``stiffness_spread``) stiffness; with the touchdown reference :func:`_stance` replaces ``k0`` by its fixed point.
    The posture and ``m_mid`` do not depend on them (statics at rest).
    """
    a0 = np.arctan2(body.ankle_height, -ANKLE_ALONG * body.sole)
    a = a0 - np.deg2rad(rng.uniform(30.0, 45.0))  # heel raised
    th_t = np.deg2rad(rng.uniform(100.0, 115.0))
    th_h = np.deg2rad(rng.uniform(65.0, 80.0))  # trunk leaning forward 10-25 deg
    k0 = k0_rec * (1.0 + cfg.stiffness_spread * rng.uniform(-1.0, 1.0, 3))
    k1 = cfg.angle_k1 * k0
    weight = body.mass.sum() * G
    f_mid = weight * rng.uniform(2.2, 2.8)
    z = -(f_mid / K_GROUND) ** (1.0 / GROUND_EXP)
    probe = StanceModel(body, np.zeros(3), np.zeros(3), k0, k1)

    def q_of(th_s):
        return np.array([z, a, th_s - a, th_t - th_s, th_h - th_t])

    # shank lean that puts the whole-body centre of mass above the toe (balanced mid-stance)
    q = q_of(brentq(lambda th: probe.com_x(q_of(th)), np.deg2rad(30.0), np.deg2rad(120.0)))
    # moments that keep the joints from accelerating at rest: unknowns [zdd, add, M1, M2, M3]
    mm = np.asarray(probe.f_m(q, np.zeros(5)), float)
    h = np.asarray(probe.f_h(q, np.zeros(5)), float).ravel()
    rhs = np.r_[probe.ground(z), 0.0, 0.0, 0.0, 0.0] - h
    lhs = np.zeros((5, 5))
    lhs[:, 0], lhs[:, 1] = mm[:, 0], mm[:, 1]
    lhs[2:, 2:] = np.diag(FLEX_SIGN)  # M q'' = Q - h with Q_r = -s M  ->  M q'' + s M_j = ...
    sol = np.linalg.solve(lhs, rhs)
    return q, sol[2:], k0, k1


def stiffness_along(k0: np.ndarray, k1: np.ndarray, r: np.ndarray, r_mid: np.ndarray) -> np.ndarray:
    """Joint stiffness ``dM/dphi = k0 + k1 dphi`` (N m/rad), shape (3, n), at relative angles ``r`` (3, n)."""
    return k0[:, None] + k1[:, None] * (FLEX_SIGN[:, None] * (np.asarray(r) - np.asarray(r_mid)[:, None]))


def _stance(body: Body, rng: np.random.Generator, cfg: StrictConfig, k0_rec: np.ndarray, tries: int = 20) -> dict:
    """One time-symmetric stance (mirrored around mid-stance); re-drawn until it is a plausible hop.

    With the touchdown-referenced angle law the stance's mid-stance ``k0`` is ``k_td + k1 phi_mid`` with ``phi_mid``
    the flexion from touchdown that the stance itself reaches: iterated to a fixed point (a draw that does not
    converge in :data:`FIXED_POINT_ITERATIONS` is re-drawn).
    """
    for _ in range(tries):
        q_mid, m_mid, k0, k1 = _mid_posture(body, rng, cfg, k0_rec)
        if cfg.angle_k1 and cfg.angle_reference == "touchdown":
            k_td = k0 / (1.0 + cfg.angle_k1 * PHI_MID_TYPICAL)
            k1 = cfg.angle_k1 * k_td
            k0, st = _touchdown_referenced(body, q_mid, m_mid, k_td, k1)
        else:
            st = _integrate(body, q_mid, m_mid, k0, k1)
        if st is None:
            continue
        half, y_to, v_com = st["half_s"], st["y_takeoff"], st["v_com"]
        if not (0.1 < half < 0.25 and v_com > 0.5 and abs(y_to[1] - q_mid[1]) < 0.6):
            continue
        if np.min(stiffness_along(k0, k1, st["y"][2:5], q_mid[2:])) < 0.0:  # seed Eq. 7: K >= 0 in stance
            continue
        return {"model": st["model"], "dense": st["dense"], "half_s": half, "y_takeoff": y_to, "v_com": v_com,
                "k0": k0, "k1": k1, "m_mid": m_mid, "q_mid": q_mid}
    raise ValueError("strict generator: no plausible stance in 20 draws")


#: Most iterations of the touchdown-referenced law's fixed point over ``phi_mid`` (:func:`_stance`).
FIXED_POINT_ITERATIONS = 30


def _touchdown_referenced(body: Body, q_mid: np.ndarray, m_mid: np.ndarray, k_td: np.ndarray,
                          k1: np.ndarray) -> tuple[np.ndarray, dict | None]:
    """The mid-stance form's ``k0 = k_td + k1 phi_mid`` at its fixed point over ``phi_mid`` and its half stance.

    ``phi_mid`` (flexion at mid-stance from touchdown; the touchdown posture is the take-off's) starts at
    :data:`PHI_MID_TYPICAL`; the half stance is None when a step does not take off or the iteration does not settle
    to 1e-9 rad in :data:`FIXED_POINT_ITERATIONS`.
    """
    phi_mid = PHI_MID_TYPICAL.copy()
    for _ in range(FIXED_POINT_ITERATIONS):
        k0 = k_td + k1 * phi_mid
        st = _integrate(body, q_mid, m_mid, k0, k1)
        if st is None:
            return k0, None
        new = FLEX_SIGN * (q_mid[2:] - st["y_takeoff"][2:5])
        if np.max(np.abs(new - phi_mid)) < 1e-9:
            return k0, st
        phi_mid = new
    return k0, None


def _integrate(body: Body, q_mid: np.ndarray, m_mid: np.ndarray, k0: np.ndarray, k1: np.ndarray) -> dict | None:
    """The half stance from mid-stance at rest to take-off (None when it does not take off within 0.4 s)."""
    model = StanceModel(body, q_mid[2:], m_mid, k0, k1)

    def takeoff(t, y):
        return y[0] if t > 1e-3 else -1.0

    sol = solve_ivp(model.rhs, (0.0, 0.4), np.r_[q_mid, np.zeros(5)], method="DOP853", rtol=1e-9,
                    atol=1e-11, events=TerminalEvent(takeoff, 1), dense_output=True)
    if sol.status != 1:
        return None
    y_to = sol.y_events[0][0]
    return {"model": model, "dense": sol.sol, "half_s": float(sol.t_events[0][0]), "y_takeoff": y_to,
            "v_com": model.com_z_rate(y_to[:5], y_to[5:]), "y": sol.y}


def _stance_state(st: dict, t_rel: float) -> tuple[np.ndarray, np.ndarray]:
    """(q, qd) at time ``t_rel`` from touchdown (mirror of the forward half)."""
    tau = t_rel - st["half_s"]
    y = st["dense"](abs(tau))
    q, qd = y[:5], y[5:]
    return q, (qd if tau >= 0 else -qd)


def _hermite(p0, v0, p1, v1, s, dur):
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * p0 + h10 * dur * v0 + h01 * p1 + h11 * dur * v1


#: Approach flight before the first touchdown of a strict recording (s).
LEAD_S = 0.15


def strict_recording(cfg: StrictConfig) -> tuple[Recording, dict]:
    """Contract recording of ``cfg.hops`` strict hops and its truth.

    Returns
    -------
    recording : Recording
    truth : dict
        ``effects``, ``subject`` (perturbed segment parameters), ``per_hop`` (touchdown/take-off s,
        ``k0``, ``k1``, touchdown moments ``M_td`` (N m, extensor), flexion at mid-stance).
    """
    rng = np.random.default_rng(cfg.seed)
    body = perturbed_body(cfg.mass_kg, cfg.height_m, rng)
    k0_rec = recording_stiffness(rng)
    timeline = _Timeline.of([_stance(body, rng, cfg, k0_rec) for _ in range(cfg.hops)])
    t_f, force, torque = _plate_series(timeline, cfg, rng)
    t_m, pos = _marker_series(timeline, cfg, rng)
    start_ns = 1_710_000_000_000_000_000 + int(cfg.seed) * 1_000_000_000
    subject = Subject(f"strict{cfg.seed}", round(float(cfg.mass_kg), 1), round(float(cfg.height_m), 3))
    rec = Recording(force=ForcePlateSeries(start_ns + np.round(t_f * 1e9).astype(np.int64), force, torque),
                    markers=MarkerSeries(start_ns + np.round(t_m * 1e9).astype(np.int64), MARKER_NAMES, pos),
                    subject=subject, source="hop_impedance.validation.strict_generator")
    truth = {"effects": cfg.effects or ["none"], "generator": "strict_generator (sympy EOM, DOP853)",
             "config": {k: getattr(cfg, k) for k in cfg.__dataclass_fields__},
             "subject": {"mass_kg": body.mass.tolist(), "length_m": body.length.tolist(), "com": body.com.tolist(),
                         "inertia_kg_m2": body.inertia.tolist()},
             "per_hop": _per_hop_truth(timeline)}
    return rec, truth


@dataclass(frozen=True)
class _Timeline:
    """The strict hops laid out in recording time: an approach of :data:`LEAD_S`, then stance, flight, ...

    ``segments`` are ``(kind, t_start_s, t_end_s, payload)``: a stance's payload is its
    :func:`_stance` dict, a flight's the (take-off, next touchdown) stance pair; the last flight
    leads to the mirror of the last stance's own touchdown.
    """

    first: dict
    segments: list
    t_end_s: float

    @classmethod
    def of(cls, stances: list[dict]) -> _Timeline:
        """Each stance lasts twice its half; each flight lasts (take-off + next touchdown COM speed) / g."""
        t = LEAD_S
        segments: list[tuple[str, float, float, dict | tuple[dict, dict]]] = []
        for k, st in enumerate(stances):
            segments.append(("stance", t, t + 2 * st["half_s"], st))
            t += 2 * st["half_s"]
            nxt = stances[k + 1] if k + 1 < len(stances) else st
            t_f = (st["v_com"] + nxt["v_com"]) / G
            segments.append(("flight", t, t + t_f, (st, nxt)))
            t += t_f
        return cls(stances[0], segments, t)

    def state_at(self, time_s: float) -> tuple[np.ndarray, np.ndarray, float, float]:
        """(q, qd, Fz, Fx) at a recording time."""
        if time_s < LEAD_S:  # approach: the mirror of the first stance's take-off flight, ending at touchdown
            q1, v1 = _stance_state(self.first, 0.0)
            q0, v0 = q1 * 1.0, -v1
            q0 = q0.copy()
            q0[0] = 0.0
            s = (time_s - 0.0) / LEAD_S
            return _hermite(q0 + np.r_[0.03, 0, 0, 0, 0], np.zeros(5), q1, v1, s, LEAD_S), np.zeros(5), 0.0, 0.0
        # the first segment not over at time_s (the last one after the recording end)
        kind, t0, t1, payload = next((seg for seg in self.segments if time_s <= seg[2]), self.segments[-1])
        if kind == "stance":
            q, qd = _stance_state(payload, time_s - t0)
            model = payload["model"]
            qdd = model.accelerations(q, qd)
            return q, qd, model.ground(q[0]), model.horizontal_force(q, qd, qdd)
        a_st, b_st = payload
        q0, v0 = _stance_state(a_st, 2 * a_st["half_s"])
        q1, v1 = _stance_state(b_st, 0.0)
        dur = t1 - t0
        s = np.clip((time_s - t0) / dur, 0.0, 1.0)
        return _hermite(q0, v0, q1, v1, s, dur), np.zeros(5), 0.0, 0.0


def _plate_series(timeline: _Timeline, cfg: StrictConfig, rng: np.random.Generator):
    """1 kHz plate: (times s, force (N, 3) N, torque (N, 3) N m) with noise and ``cfg.force_offset_n`` on Fz.

    The torque about y is the horizontal force's moment about the plate surface (toe below it: ``z_toe Fx``).
    """
    t_f = np.arange(0.0, timeline.t_end_s, 1e-3)
    fz = np.zeros_like(t_f)
    fx = np.zeros_like(t_f)
    toe_z = np.zeros_like(t_f)
    for i, tt in enumerate(t_f):
        q, _, fz[i], fx[i] = timeline.state_at(tt)
        toe_z[i] = q[0]
    force = np.stack([fx, np.zeros_like(fx), fz], axis=1) + rng.normal(0.0, cfg.force_noise_n, (len(t_f), 3))
    force[:, 2] += cfg.force_offset_n
    torque = np.stack([np.zeros_like(fx), np.minimum(toe_z, 0.0) * fx, np.zeros_like(fx)], axis=1)
    torque += rng.normal(0.0, cfg.torque_noise_nm, torque.shape)
    return t_f, force, torque


def _marker_series(timeline: _Timeline, cfg: StrictConfig, rng: np.random.Generator):
    """100 Hz markers with a random sampling phase: (times s, positions (N, markers, 3) m), ``cfg.marker_latency_s`` late."""
    phase = rng.uniform(0.0, 0.01)
    t_m = np.arange(phase, timeline.t_end_s, 0.01)
    pos = np.zeros((len(t_m), len(MARKER_NAMES), 3))
    pos[:, :, 1] = -0.1
    pts_fn = timeline.first["model"].f_pts
    for i, tt in enumerate(t_m):
        q = timeline.state_at(max(tt - cfg.marker_latency_s, 0.0))[0]
        pts = np.array([np.asarray(p, float).ravel() for p in pts_fn(q)])
        pos[i, :, 0], pos[i, :, 2] = pts[:, 0], pts[:, 1]
    pos += rng.normal(0.0, cfg.marker_noise_m, pos.shape)
    return t_m, pos


def _per_hop_truth(timeline: _Timeline) -> list[dict]:
    """Per stance: touchdown/take-off (s), k0 (the mid-stance form's), k1, the stiffness at touchdown ``k0 - k1
    flex_mid`` (seed 000's k0), touchdown moments (N m, extensor), flexion at mid-stance (rad)."""
    per_hop = []
    for kind, t0, t1, st in timeline.segments:
        if kind != "stance":
            continue
        q_td = _stance_state(st, 0.0)[0]
        flex_mid = FLEX_SIGN * (st["q_mid"][2:] - q_td[2:])
        per_hop.append({"t_td": t0, "t_to": t1, "k0": st["k0"].tolist(), "k1": st["k1"].tolist(),
                        "k_touchdown": (st["k0"] - st["k1"] * flex_mid).tolist(),
                        "M_td": st["model"].moments(q_td[2:]).tolist(), "flex_mid_rad": flex_mid.tolist()})
    return per_hop
