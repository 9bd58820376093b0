"""Equations of motion of the four-segment sagittal chain (feet, shanks, thighs, HAT).

Generalized coordinates
-----------------------
``g = [x_toe, z_toe, q1, q2, q3, q4]`` (m, m, rad x 4): the toe (contact point)
in the lab's x-z plane and the absolute segment angles of
:mod:`hop_impedance.biomech.joint_angles` (q_i = atan2(dz, dx) of the segment's
distal->proximal vector, counter-clockwise positive in the x-z picture seen
from the subject's right).

Formulation
-----------
Segment i has its centre of mass at
``p_i = toe + sum_{j<i} L_j e(q_j) + a_i e(q_i) + b_i n(q_i)`` with
``e(q) = (cos q, sin q)``, ``n(q) = (-sin q, cos q)`` and (a_i, b_i) the
body model's ``(com_along_m, com_perp_m)``. With the COM Jacobians
``J_i = dp_i/dg`` (2 x 6) and the rotation Jacobian (q_i is the segment's
absolute angle), the principle of virtual work gives

    M(g) g'' + h(g, g') = Q_gravity + Q_joints + Q_ground,
    M = sum_i m_i J_i^T J_i + I_i u_i u_i^T,     h = sum_i m_i J_i^T (dJ_i/dt g'),

where ``dJ_i/dt g' = -sum_{j<i} L_j q_j'^2 e(q_j) - q_i'^2 (a_i e + b_i n)(q_i)``.
:func:`equations_of_motion` evaluates these sums in closed form, as constant 4 x 4 coefficients of
``cos(q_k - q_j)`` and ``sin(q_k - q_j)`` (:class:`EomConstants`), compiled by numba (``_eom_compiled``, the one place
the closed form is written); the tests check it against the Jacobian sums (`bench/bench_stance_dynamics.py` times both).
:func:`accelerations`, the stance ODE's inner loop, solves the same compiled form (``_accelerations_compiled``:
44 -> 6 us a call, the stance 1.5x faster, ``discover`` 1.6x; ``test_sim_dynamics`` checks it against
:func:`equations_of_motion` solved by LAPACK).
Joint moments M_j are extensor positive and do virtual work ``-M_j d(rho_j)``
(ankle rho1 = q1 - q2 + alpha, knee rho2 = q3 - q2 + pi, hip rho3 = q3 - q4 + pi),
so ``Q_joints = -D^T M`` with ``D = d(rho)/dq`` (constant, 3 x 4). The ground
force ``F = (Fx, Fz)`` on the subject acts at the toe: ``Q_ground = [Fx, Fz, 0, 0, 0, 0]``.

Coordinates held fixed (e.g. ``x_toe`` under the no-slip constraint) are removed
by taking the sub-system of the free coordinates; the generalized force that
the equations of the fixed coordinates then require *is* the constraint force
(:func:`constraint_forces`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numba
import numpy as np

from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.recording import GRAVITY_M_S2

#: d(rho)/dq of Eq. 2 (rows ankle, knee, hip; columns q1..q4). Constant.
JOINT_JACOBIAN = np.array(
    [
        [1.0, -1.0, 0.0, 0.0],
        [0.0, -1.0, 1.0, 0.0],
        [0.0, 0.0, 1.0, -1.0],
    ]
)

N_COORDS = 6


@dataclass(frozen=True)
class Chain:
    """Arrays of the four segments, foot first, for vectorised dynamics.

    Attributes
    ----------
    mass_kg, length_m, com_along_m, com_perp_m, inertia_kgm2 : ndarray, shape (4,)
        Per segment (foot, shank, thigh, HAT); lengths toe->ankle, ankle->knee,
        knee->hip, hip->head marker.
    alpha_rad : float
        Foot angle alpha of Eq. 2 (rad).
    heel_along_m, heel_perp_m : float
        Heel marker in the foot frame (m).
    gravity_m_s2 : float
    toe_marker_along_m, toe_marker_perp_m : float
        Toe marker in the foot frame (m); zero when the ground contact (the chain's
        origin, ``g[0:2]``) is the toe marker itself (:func:`contact_ahead_of_toe_marker`).
    """

    mass_kg: np.ndarray
    length_m: np.ndarray
    com_along_m: np.ndarray
    com_perp_m: np.ndarray
    inertia_kgm2: np.ndarray
    alpha_rad: float
    heel_along_m: float
    heel_perp_m: float
    gravity_m_s2: float = GRAVITY_M_S2
    toe_marker_along_m: float = 0.0
    toe_marker_perp_m: float = 0.0

    @property
    def total_mass_kg(self) -> float:
        """Sum of segment masses (kg)."""
        return float(self.mass_kg.sum())

    @cached_property
    def eom_constants(self) -> EomConstants:
        """The chain's constant mass-matrix terms (:class:`EomConstants`), computed once per chain."""
        return EomConstants.of(self)


@dataclass(frozen=True)
class EomConstants:
    """Constant terms of :func:`equations_of_motion` for one chain.

    Segment i's COM velocity is ``v_toe + sum_j R(q_j) u_ij qd_j`` with the segment-frame vectors
    ``u_ij = (0, L_j)`` for j < i (the links below it), ``u_ii = (-b_i, a_i)`` (its own COM) and 0 for
    j > i; ``R(q)`` rotates by q. Since ``u^T R(q_j)^T R(q_k) w = cos(q_k - q_j) (u . w) + sin(q_k - q_j)
    (u_1 w_0 - u_0 w_1)``, the angle block of ``M = sum_i m_i J_i^T J_i + diag(I)`` is
    ``A_jk cos(q_k - q_j) + B_jk sin(q_k - q_j)`` with constant ``A, B``; the toe-angle block is
    ``R(q_j) w_j`` with ``w_j = sum_i m_i u_ij``; the velocity products follow from ``dR/dq = R J90``.
    """

    cos_terms: np.ndarray  # A (4, 4), inertias on the diagonal
    sin_terms: np.ndarray  # B (4, 4)
    cos_products: np.ndarray  # A without the inertias: the velocity products' cosine-free terms (4, 4)
    first_moments: np.ndarray  # w (4, 2), kg m
    total_mass_kg: float

    @classmethod
    def of(cls, chain: Chain) -> EomConstants:
        u = np.zeros((4, 4, 2))
        for i in range(4):
            u[i, :i, 1] = chain.length_m[:i]
            u[i, i] = (-chain.com_perp_m[i], chain.com_along_m[i])
        m = chain.mass_kg
        dot = np.einsum("i,ija,ika->jk", m, u, u)
        cross = np.einsum("i,ij,ik->jk", m, u[..., 1], u[..., 0]) - np.einsum("i,ij,ik->jk", m, u[..., 0], u[..., 1])
        return cls(dot + np.diag(chain.inertia_kgm2), cross, dot, np.einsum("i,ija->ja", m, u), chain.total_mass_kg)


def chain_from_body_model(model: BodyModel) -> Chain:
    """Collect the body model's segment parameters into a :class:`Chain`."""
    segs = model.segments
    return Chain(
        mass_kg=np.array([s.mass_kg for s in segs]),
        length_m=np.array([s.length_m for s in segs]),
        com_along_m=np.array([s.com_along_m for s in segs]),
        com_perp_m=np.array([s.com_perp_m for s in segs]),
        inertia_kgm2=np.array([s.inertia_kgm2 for s in segs]),
        alpha_rad=model.foot_geometry.alpha_rad,
        heel_along_m=model.foot_geometry.heel_along_m,
        heel_perp_m=model.foot_geometry.heel_perp_m,
    )


def contact_ahead_of_toe_marker(chain: Chain, ahead_m: float) -> Chain:
    """The same body touching the ground ``ahead_m`` in front of the toe marker, along the sole.

    The seed's model (seed 000, Methods) lets the foot touch the floor "through a virtual hinge
    located at the tip of the toe", while its toe marker sits at the fifth metatarsal head; our
    body model's foot link runs from that marker to the ankle. This moves the chain's contact
    point (the hinge the stance pivots about, where the force plate sees the force) forward along
    the heel->toe line by ``ahead_m`` (m, >= 0): the foot link becomes contact->ankle, ``alpha``
    is re-measured at the contact, the foot's centre of mass and the heel marker are expressed in
    the new foot frame, and the toe marker becomes a point of the foot. The joint angle rho1 is
    unchanged (the contact lies on the sole line, so ``q1 + alpha`` is still the sole's angle);
    masses and inertias are unchanged. ``ahead_m = 0`` returns ``chain`` itself.
    """
    if ahead_m < 0:
        raise ValueError(f"contact must lie ahead of the toe marker (ahead_m >= 0), got {ahead_m}")
    if ahead_m == 0:
        return chain
    old = np.array([[chain.toe_marker_along_m, chain.toe_marker_perp_m], [chain.heel_along_m, chain.heel_perp_m],
                    [chain.com_along_m[0], chain.com_perp_m[0]], [chain.length_m[0], 0.0]])
    toe, heel, com, ankle = old
    forward = (toe - heel) / np.linalg.norm(toe - heel)
    contact = toe + ahead_m * forward
    e1 = (ankle - contact) / np.linalg.norm(ankle - contact)
    frame = np.array([e1, [-e1[1], e1[0]]])  # rows: new axes in the old frame
    new_toe, new_heel, new_com = (frame @ (p - contact) for p in (toe, heel, com))
    length, along, perp = chain.length_m.copy(), chain.com_along_m.copy(), chain.com_perp_m.copy()
    length[0] = float(np.linalg.norm(ankle - contact))
    along[0], perp[0] = new_com
    return replace(chain, length_m=length, com_along_m=along, com_perp_m=perp,
                   alpha_rad=float(np.arctan2(new_heel[1], new_heel[0])),
                   heel_along_m=float(new_heel[0]), heel_perp_m=float(new_heel[1]),
                   toe_marker_along_m=float(new_toe[0]), toe_marker_perp_m=float(new_toe[1]))


def _unit(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """e(q) and n(q) = de/dq, each shape q.shape + (2,)."""
    c, s = np.cos(q), np.sin(q)
    e = np.empty(np.shape(q) + (2,))
    n = np.empty_like(e)
    e[..., 0], e[..., 1] = c, s
    n[..., 0], n[..., 1] = -s, c
    return e, n


def joint_positions(chain: Chain, g: np.ndarray) -> np.ndarray:
    """Toe, ankle, knee, hip and head points in the x-z plane (m).

    Parameters
    ----------
    g : ndarray, shape (..., 6)
        Generalized coordinates.

    Returns
    -------
    ndarray, shape (..., 5, 2)
        ``[toe, ankle, knee, hip, head]``, each ``[x, z]``.
    """
    g = np.asarray(g, float)
    e, _ = _unit(g[..., 2:])
    steps = chain.length_m[:, None] * e  # (..., 4, 2)
    toe = g[..., None, 0:2]
    return np.concatenate([toe, toe + np.cumsum(steps, axis=-2)], axis=-2)


def heel_position(chain: Chain, g: np.ndarray) -> np.ndarray:
    """Heel marker ``[x, z]`` (m), shape (..., 2), from the foot frame."""
    g = np.asarray(g, float)
    e, n = _unit(g[..., 2])
    return g[..., 0:2] + chain.heel_along_m * e + chain.heel_perp_m * n


def toe_marker_position(chain: Chain, g: np.ndarray) -> np.ndarray:
    """Toe marker ``[x, z]`` (m), shape (..., 2): the contact point unless the chain touches ahead of it."""
    g = np.asarray(g, float)
    e, n = _unit(g[..., 2])
    return g[..., 0:2] + chain.toe_marker_along_m * e + chain.toe_marker_perp_m * n


def segment_com_positions(chain: Chain, g: np.ndarray) -> np.ndarray:
    """Segment centres of mass ``[x, z]`` (m), shape (..., 4, 2)."""
    g = np.asarray(g, float)
    e, n = _unit(g[..., 2:])
    joints = joint_positions(chain, g)[..., :4, :]
    return joints + chain.com_along_m[:, None] * e + chain.com_perp_m[:, None] * n


def body_com(chain: Chain, g: np.ndarray) -> np.ndarray:
    """Whole-body centre of mass ``[x, z]`` (m), shape (..., 2)."""
    p = segment_com_positions(chain, g)
    return np.einsum("i,...ik->...k", chain.mass_kg, p) / chain.total_mass_kg


_BEFORE = np.tril(np.ones((4, 4)), -1)  # [i, j] = 1 where segment j lies below segment i
_OWN = np.eye(4)


def com_jacobians(chain: Chain, q: np.ndarray) -> np.ndarray:
    """Jacobians of the segment COMs with respect to g, shape (4, 2, 6).

    Parameters
    ----------
    q : ndarray, shape (4,)
        Segment angles (rad).
    """
    e, n = _unit(np.asarray(q, float))
    own = chain.com_along_m[:, None] * n - chain.com_perp_m[:, None] * e  # (4, 2)
    link = chain.length_m[:, None] * n
    jac = np.empty((4, 2, N_COORDS))
    jac[:, :, 0:2] = np.eye(2)
    jac[:, :, 2:] = _BEFORE[:, None, :] * link.T[None] + _OWN[:, None, :] * own.T[None]
    return jac


def _velocity_products(chain: Chain, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """dJ_i/dt g' for each segment COM, shape (4, 2) (m/s^2)."""
    e, n = _unit(q)
    link = -(chain.length_m * qd**2)[:, None] * e  # (4, 2)
    own = -(qd**2)[:, None] * (chain.com_along_m[:, None] * e + chain.com_perp_m[:, None] * n)
    before = np.cumsum(link, axis=0) - link  # sum over j < i
    return before + own


def equations_of_motion(chain: Chain, g: np.ndarray, gd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass matrix, velocity-product and gravity terms at one state.

    Parameters
    ----------
    g, gd : ndarray, shape (6,)
        Generalized coordinates (m, rad) and velocities (m/s, rad/s).

    Returns
    -------
    mass : ndarray, shape (6, 6)
        M(g) (kg, kg m, kg m^2 blocks).
    bias : ndarray, shape (6,)
        h(g, g'), the velocity-product term on the left-hand side.
    gravity : ndarray, shape (6,)
        Q_gravity (N, N m) on the right-hand side.
    """
    k = chain.eom_constants  # the closed form of sum_i m_i J_i^T J_i (EomConstants; test_sim_dynamics checks it)
    # One closed form, compiled (_eom_compiled): with no joint moment and no ground force its right-hand side is
    # Q_gravity - h, and Q_gravity is -g times the body's weight on z and -g times M's z row on the angles.
    mass, rhs = _eom_compiled(k.cos_terms, k.sin_terms, k.cos_products, k.first_moments, k.total_mass_kg,
                              chain.gravity_m_s2, np.asarray(g[2:], float), np.asarray(gd[2:], float), np.zeros(3), 0.0, 0.0)
    gravity = np.zeros(N_COORDS)
    gravity[1] = -chain.gravity_m_s2 * k.total_mass_kg
    gravity[2:] = -chain.gravity_m_s2 * mass[1, 2:]
    bias = gravity - rhs
    return mass, bias, gravity


def joint_generalized_forces(moments_nm: np.ndarray) -> np.ndarray:
    """Q on g of extensor-positive joint moments (ankle, knee, hip), shape (6,).

    A positive (extensor) moment acts to decrease rho: its virtual work is
    ``-M . d(rho)``, hence ``Q_q = -D^T M``.
    """
    out = np.zeros(N_COORDS)
    out[2:] = -JOINT_JACOBIAN.T @ np.asarray(moments_nm, float)
    return out


def accelerations(
    chain: Chain,
    g: np.ndarray,
    gd: np.ndarray,
    moments_nm: np.ndarray,
    toe_force_n: np.ndarray,
    free: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Generalized accelerations with some coordinates held fixed.

    Parameters
    ----------
    g, gd : ndarray, shape (6,)
        State; the fixed coordinates must have zero velocity.
    moments_nm : ndarray, shape (3,)
        Joint moments, extensor positive (N m).
    toe_force_n : ndarray, shape (2,)
        Known ground force at the toe ``[Fx, Fz]`` on the subject (N); for a
        fixed coordinate put 0 there, its force is returned as a constraint force.
    free : ndarray of bool, shape (6,)
        Which coordinates move.

    Returns
    -------
    gdd : ndarray, shape (6,)
        Accelerations (zero for the fixed coordinates).
    constraint : ndarray, shape (6,)
        Generalized constraint forces (non-zero only on fixed coordinates);
        on ``x_toe``/``z_toe`` these are the ground force components (N).
    """
    k = chain.eom_constants
    gdd, constraint, info = _accelerations_compiled(
        k.cos_terms, k.sin_terms, k.cos_products, k.first_moments, k.total_mass_kg, chain.gravity_m_s2,
        np.asarray(g, float), np.asarray(gd, float), np.asarray(moments_nm, float), float(toe_force_n[0]),
        float(toe_force_n[1]), np.asarray(free, bool))
    if info != 0:
        raise np.linalg.LinAlgError(f"singular mass matrix (pivot {info} is zero)")
    return gdd, constraint


@numba.njit(cache=True)
def _eom_compiled(cos_terms, sin_terms, cos_products, w, total_mass, grav, q, qd, moments, fx, fz):  # noqa: PLR0913
    """M and the right-hand side ``Q_gravity + Q_joints + Q_ground - h`` of :func:`equations_of_motion`, compiled.

    The same closed form (:class:`EomConstants`), written as loops that numba compiles: with the solve,
    :func:`accelerations` went from 43.8 to 5.8 us a call (`bench/bench_stance_dynamics.py`, session 35); it was most
    of the stance ODE's right-hand side, the inner loop of every simulated trial and of ``discover`` (issue 16).
    :func:`equations_of_motion` calls it with no moment and no ground force, so ``test_sim_dynamics`` checks it
    against the Jacobian sums there and against :func:`joint_generalized_forces` through :func:`accelerations`.
    """
    mass = np.zeros((6, 6))
    rhs = np.zeros(6)
    mass[0, 0] = total_mass
    mass[1, 1] = total_mass
    rhs[0] = fx
    rhs[1] = fz - grav * total_mass
    for j in range(4):
        c, s, qd2 = np.cos(q[j]), np.sin(q[j]), qd[j] * qd[j]
        mass[0, 2 + j] = mass[2 + j, 0] = w[j, 0] * c - w[j, 1] * s
        mass[1, 2 + j] = mass[2 + j, 1] = w[j, 0] * s + w[j, 1] * c
        rhs[0] += (w[j, 1] * c + w[j, 0] * s) * qd2
        rhs[1] -= (w[j, 0] * c - w[j, 1] * s) * qd2
    for j in range(4):
        bias = 0.0
        for k in range(4):
            cd, sd = np.cos(q[k] - q[j]), np.sin(q[k] - q[j])
            mass[2 + j, 2 + k] = cos_terms[j, k] * cd + sin_terms[j, k] * sd
            bias += (sin_terms[j, k] * cd - cos_products[j, k] * sd) * qd[k] * qd[k]
        rhs[2 + j] = -grav * mass[1, 2 + j] - bias
    # Q_joints = -D^T M (JOINT_JACOBIAN): ankle rho = q1 - q2, knee q3 - q2, hip q3 - q4
    rhs[2] -= moments[0]
    rhs[3] += moments[0] + moments[1]
    rhs[4] -= moments[1] + moments[2]
    rhs[5] += moments[2]
    return mass, rhs


@numba.njit(cache=True)
def _accelerations_compiled(cos_terms, sin_terms, cos_products, w, total_mass, grav, g, gd, moments, fx, fz, free):  # noqa: PLR0913
    """(gdd, constraint, info) of :func:`accelerations`: Gaussian elimination with partial pivoting on the free block."""
    mass, rhs = _eom_compiled(cos_terms, sin_terms, cos_products, w, total_mass, grav, g[2:], gd[2:], moments, fx, fz)
    idx = np.flatnonzero(free)
    n = idx.size
    a = np.empty((n, n))
    b = np.empty(n)
    for i in range(n):
        b[i] = rhs[idx[i]]
        for k in range(n):
            a[i, k] = mass[idx[i], idx[k]]
    info = 0
    for col in range(n):
        piv = col + np.argmax(np.abs(a[col:, col]))
        if a[piv, col] == 0.0:
            info = col + 1
            break
        if piv != col:
            for k in range(n):
                a[col, k], a[piv, k] = a[piv, k], a[col, k]
            b[col], b[piv] = b[piv], b[col]
        for i in range(col + 1, n):
            f = a[i, col] / a[col, col]
            for k in range(col, n):
                a[i, k] -= f * a[col, k]
            b[i] -= f * b[col]
    gdd = np.zeros(6)
    if info == 0:
        for i in range(n - 1, -1, -1):
            acc = b[i]
            for k in range(i + 1, n):
                acc -= a[i, k] * gdd[idx[k]]
            gdd[idx[i]] = acc / a[i, i]
    constraint = mass @ gdd - rhs
    for i in range(6):
        if free[i]:
            constraint[i] = 0.0
    return gdd, constraint, info


def mechanical_energy_j(chain: Chain, g: np.ndarray, gd: np.ndarray) -> tuple[float, float]:
    """Kinetic and gravitational potential energy (J) at one state (z = 0 datum)."""
    mass, _, _ = equations_of_motion(chain, g, gd)
    kinetic = 0.5 * float(gd @ mass @ gd)
    z = segment_com_positions(chain, g)[:, 1]
    return kinetic, float(chain.gravity_m_s2 * chain.mass_kg @ z)


def com_velocity(chain: Chain, g: np.ndarray, gd: np.ndarray) -> np.ndarray:
    """Whole-body COM velocity ``[vx, vz]`` (m/s), shape (2,)."""
    jac = com_jacobians(chain, g[2:])
    return np.einsum("i,iak,k->a", chain.mass_kg, jac, gd) / chain.total_mass_kg


def com_height_above_contact(chain: Chain, q: np.ndarray) -> float:
    """Body COM height above the chain's origin (the toe) at segment angles ``q`` (m), ``body_com(g)[1] - g[1]``.

    From the first moments of :class:`EomConstants`: the COM's offset from the toe is ``sum_j R(q_j) J90 w_j / m``,
    whose z is ``(w_j1 sin q_j - w_j0 cos q_j) / m``; a few flops, for the stance's collapse event at every solver step
    (``body_com`` builds every segment's point).
    """
    k = chain.eom_constants
    w = k.first_moments
    return float(w[:, 1] @ np.sin(q) - w[:, 0] @ np.cos(q)) / k.total_mass_kg


def com_offset_jacobian(chain: Chain, q: np.ndarray) -> np.ndarray:
    """d(COM - toe)/dq, shape (2, 4) (m/rad): how the angles move the COM relative to the toe."""
    jac = com_jacobians(chain, q)
    return np.einsum("i,iak->ak", chain.mass_kg, jac[:, :, 2:]) / chain.total_mass_kg


def internal_mass_matrix(chain: Chain, q: np.ndarray) -> np.ndarray:
    """4 x 4 matrix ``M_int`` with ``0.5 qd^T M_int qd`` the kinetic energy of the segments' motion
    relative to the whole-body COM (kg m^2).

    By König's theorem the kinetic energy is ``0.5 m v_com^2`` plus this internal part; with the COM at
    rest the toe moves at ``-d(COM - toe)/dq qd``, so ``M_int = T^T M T`` with ``T = [-J_offset; I]``.
    """
    q = np.asarray(q, float)
    mass, _, _ = equations_of_motion(chain, np.r_[0.0, 0.0, q], np.zeros(N_COORDS))
    transform = np.vstack([-com_offset_jacobian(chain, q), np.eye(4)])
    return transform.T @ mass @ transform


def internal_kinetic_energy_j(chain: Chain, q: np.ndarray, qd: np.ndarray) -> float:
    """Kinetic energy of segment motion relative to the whole-body COM (J); see :func:`internal_mass_matrix`."""
    qd = np.asarray(qd, float)
    return 0.5 * float(qd @ internal_mass_matrix(chain, q) @ qd)


def hip_over_com_drop_bound(chain: Chain) -> float:
    """Largest ratio of the hip's vertical drop to the whole-body COM's drop for a small sink with the trunk upright.

    Issue 17 (the seed's hip excursion against the COM drop its own peak GRF and stance imply): with the HAT
    translating with the hip (no pitch change, so its COM falls exactly as far as the hip), the thigh turning
    about a knee that does not fall, and shank and foot still, the hip falls ``h`` while the thigh's COM falls
    ``h a_3 / L_3`` (its COM ``a_3`` from the knee along a thigh of length ``L_3``; exact for any ``h`` when
    ``com_perp_m[2] = 0``, as the COM's height is linear along the segment). Any fall of the knee, shank or foot,
    or a forward pitch of the trunk, lowers the COM more and the ratio below this bound,
    ``M / (m_HAT + m_thigh a_3 / L_3)``. It bounds the drops from the touchdown posture; a stance *range* of the
    hip can exceed it when the hip stands higher at take-off than at touchdown.
    """
    thigh_share = chain.com_along_m[2] / chain.length_m[2]
    return float(chain.total_mass_kg / (chain.mass_kg[3] + chain.mass_kg[2] * thigh_share))
