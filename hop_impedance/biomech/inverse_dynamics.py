"""Planar Newton-Euler inverse dynamics from the ground up (foot, shank, thigh).

For each segment with centre of mass c, mass m, inertia I (about c) and
angular acceleration qdd, the loads at its distal end (force F_d applied at
point p_d, couple M_d) are known; the proximal joint load on it (force F_p at
p_p, couple M_p) follows from

    F_p = m (a_c - g) - F_d
    M_p = I qdd - M_d - (p_d - c) x F_d - (p_p - c) x F_p

with ``x`` the planar cross product ``r_x F_z - r_z F_x`` (counter-clockwise
positive in the x-z picture, i.e. about the lab's -y axis). The foot's distal
load is the ground reaction force: F = [Fx, Fz] acting at the plate origin
with the couple Mo = -torque.y, which is the same as F acting at the centre of
pressure on the surface. Using the wrench directly avoids dividing by a small
Fz near touchdown and take-off. The next segment up receives the opposite of
the proximal load (Newton's third law).

Sign conventions (docs/ARCHITECTURE.md, ``joint_angles``)
---------------------------------------------------------
``moment_ccw[:, j]`` is the couple the proximal segment applies to the distal
one (counter-clockwise positive). The reported net joint moment is extensor
(plantarflexor) positive, i.e. acting to decrease rho:

- ankle: rho1 = q1 - q2 + alpha; a ccw couple on the foot raises rho1, so
  M_ext = -M_ccw;
- knee: rho2 = q3 - q2 + pi; a ccw couple on the shank lowers rho2, so
  M_ext = +M_ccw;
- hip: rho3 = q3 - q4 + pi; a ccw couple on the thigh raises rho3, so
  M_ext = -M_ccw.

Joint power is P = -M_ext * d(rho)/dt, which equals
M_ccw * (omega_distal - omega_proximal).

References
----------
Winter D.A. (2009) Biomechanics and Motor Control of Human Movement, 4th ed., ch. 5.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.recording import GRAVITY_M_S2

#: Sign turning ``moment_ccw`` (on the distal segment) into extensor-positive moments: ankle, knee, hip.
EXTENSOR_SIGN = np.array([-1.0, 1.0, -1.0])

_G = np.array([0.0, -GRAVITY_M_S2])


@dataclass
class JointLoads:
    """Result of :func:`inverse_dynamics_2d`.

    Attributes
    ----------
    moment_nm : ndarray, shape (N, 3)
        Net joint moments, ankle, knee, hip, both legs together (N m),
        extensor/plantarflexor positive.
    moment_ccw_nm : ndarray, shape (N, 3)
        Same moments as the counter-clockwise couple on the distal segment (N m).
    force_n : ndarray, shape (N, 3, 2)
        Joint reaction force on the distal segment from the proximal one,
        ``[x, z]`` (N), ankle, knee, hip.
    hip_residual_force_n : ndarray, shape (N, 2)
        Top-down check on the HAT: m (a - g) minus the hip force acting on it
        (N); zero for perfect data.
    hip_residual_moment_nm : ndarray, shape (N,)
        Same for the moment about the HAT's centre of mass (N m, ccw).
    """

    moment_nm: np.ndarray
    moment_ccw_nm: np.ndarray
    force_n: np.ndarray
    hip_residual_force_n: np.ndarray
    hip_residual_moment_nm: np.ndarray


def cross2(r: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Planar cross product ``r_x f_z - r_z f_x`` over the last axis (ccw positive)."""
    out: np.ndarray = r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]
    return out


def proximal_load(
    mass_kg: float,
    inertia_kgm2: float,
    com_xz: np.ndarray,
    com_acc: np.ndarray,
    qdd: np.ndarray,
    distal_force: np.ndarray,
    distal_point: np.ndarray,
    distal_couple: np.ndarray,
    proximal_point: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Newton-Euler for one segment: the proximal joint's force and couple on it.

    Parameters
    ----------
    mass_kg, inertia_kgm2 : float
        Segment mass (kg), inertia about its COM (kg m^2).
    com_xz, com_acc : ndarray, shape (N, 2)
        COM position (m) and acceleration (m/s^2).
    qdd : ndarray, shape (N,)
        Angular acceleration (rad/s^2, ccw).
    distal_force : ndarray, shape (N, 2)
        Force applied on the segment at ``distal_point`` (N).
    distal_point, proximal_point : ndarray, shape (N, 2)
        Where the distal and proximal loads act (m).
    distal_couple : ndarray, shape (N,)
        Free couple applied on the segment at its distal end (N m, ccw).

    Returns
    -------
    force : ndarray, shape (N, 2)
        Force of the proximal neighbour on this segment (N).
    couple : ndarray, shape (N,)
        Couple of the proximal neighbour on this segment (N m, ccw).
    """
    force = mass_kg * (com_acc - _G) - distal_force
    couple = (
        inertia_kgm2 * qdd
        - distal_couple
        - cross2(distal_point - com_xz, distal_force)
        - cross2(proximal_point - com_xz, force)
    )
    return force, couple


def inverse_dynamics_2d(
    points_xz: np.ndarray,
    com_xz: np.ndarray,
    com_acc: np.ndarray,
    qdd: np.ndarray,
    wrench: np.ndarray,
    model: BodyModel,
) -> JointLoads:
    """Ankle, knee and hip net moments and forces, frame by frame, from the ground up.

    Parameters
    ----------
    points_xz : ndarray, shape (N, 5, 2)
        toe, ankle, knee, hip, head ``[x, z]`` (m), lab frame (plate origin).
    com_xz, com_acc : ndarray, shape (N, 4, 2)
        Segment COM positions (m) and accelerations (m/s^2), foot..HAT.
    qdd : ndarray, shape (N, 4)
        Segment angular accelerations (rad/s^2).
    wrench : ndarray, shape (N, 3)
        Ground reaction ``[Fx, Fz, Mo]`` on the subject (N, N, N m ccw about
        the plate origin), see :mod:`hop_impedance.biomech.force_plate`.
    model : BodyModel

    Returns
    -------
    JointLoads
    """
    n = points_xz.shape[0]
    force = np.asarray(wrench[:, :2], float)
    point = np.zeros((n, 2))  # the plate origin
    couple = np.asarray(wrench[:, 2], float)
    moments = np.empty((n, 3))
    forces = np.empty((n, 3, 2))
    for j, seg in enumerate(model.segments[:3]):
        f_p, m_p = proximal_load(
            seg.mass_kg, seg.inertia_kgm2, com_xz[:, j], com_acc[:, j], qdd[:, j], force, point, couple, points_xz[:, j + 1]
        )
        forces[:, j], moments[:, j] = f_p, m_p
        force, point, couple = -f_p, points_xz[:, j + 1], -m_p
    hat = model.hat
    res_f = hat.mass_kg * (com_acc[:, 3] - _G) - force
    res_m = hat.inertia_kgm2 * qdd[:, 3] - couple - cross2(point - com_xz[:, 3], force)
    return JointLoads(moments * EXTENSOR_SIGN, moments, forces, res_f, res_m)


def joint_power(moment_nm: np.ndarray, rhod_rad_s: np.ndarray) -> np.ndarray:
    """Joint power (W), shape (N, 3): ``-M_ext * d(rho)/dt`` (negative = absorbing, braking)."""
    power: np.ndarray = -np.asarray(moment_nm) * np.asarray(rhod_rad_s)
    return power
