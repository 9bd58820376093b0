"""Forward integration of one stance phase.

Model during stance: toe x held fixed (horizontal no-slip as a kinematic
constraint; the horizontal ground force is the constraint force), toe z free
on the surface law of :mod:`hop_impedance.simulation.ground`, segment angles
q1..q4 free: 5 degrees of freedom plus the impedance law's extra states.

Integration: ``scipy.integrate.solve_ivp`` with ``LSODA`` (switches to a stiff
method on the rigid surface), ``rtol = 1e-8``, ``atol = 1e-10`` by default,
dense output. Stance ends at the first of: the ground force reaches zero while
the toe rises (take-off), the toe leaves the surface (``y`` crosses 0 upward),
the body collapses (COM below ``collapse_height_m`` above the toe, or a joint
more than 1.5 rad from its touchdown angle), or ``t_max_s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from hop_impedance.biomech.joint_angles import joint_angles
from hop_impedance.simulation.dynamics import (
    JOINT_JACOBIAN,
    Chain,
    accelerations,
    body_com,
    com_velocity,
    mechanical_energy_j,
)
from hop_impedance.simulation.ground import GroundLaw
from hop_impedance.simulation.impedance_laws import ImpedanceLaw, TouchdownReference

#: Free coordinates in stance: z_toe, q1..q4 (x_toe fixed).
STANCE_FREE = np.array([False, True, True, True, True, True])

DEFAULT_RTOL = 1e-8
DEFAULT_ATOL = 1e-10
#: A joint moving further than this from its touchdown angle has collapsed (rad).
MAX_JOINT_EXCURSION_RAD = 1.5
#: Contact that ends sooner than this after touchdown is a bounce, not a stance.
MIN_STANCE_S = 0.02


@dataclass(frozen=True)
class TouchdownState:
    """State at the instant the toe meets the surface.

    Attributes
    ----------
    g : ndarray, shape (6,)
        ``[x_toe, z_toe, q1..q4]`` (m, rad); ``z_toe`` is normally 0.
    gd : ndarray, shape (6,)
        Velocities (m/s, rad/s); ``gd[0]`` (toe x velocity) must be 0 for the
        no-slip constraint.
    """

    g: np.ndarray
    gd: np.ndarray


@dataclass
class StanceSimulation:
    """One integrated stance, sampled at the solver's or requested instants.

    Attributes
    ----------
    t_s : ndarray, shape (N,)
        Time since touchdown (s).
    g, gd, gdd : ndarray, shape (N, 6)
        Generalized coordinates, velocities, accelerations.
    grf_n : ndarray, shape (N, 2)
        Ground force on the subject ``[Fx, Fz]`` (N) at the toe.
    moments_nm : ndarray, shape (N, 3)
        Joint moments, extensor positive (N m).
    rho_rad, omega_rad_s : ndarray, shape (N, 3)
        Joint angles and velocities.
    law_states : ndarray, shape (N, n_states)
    end_reason : str
        ``"take_off"``, ``"collapse"`` or ``"t_max"``.
    ref : TouchdownReference
    dense : callable
        ``dense(t) -> y`` continuous solution (ODE state) for ``t`` in [0, t_end].
    """

    t_s: np.ndarray
    g: np.ndarray
    gd: np.ndarray
    gdd: np.ndarray
    grf_n: np.ndarray
    moments_nm: np.ndarray
    rho_rad: np.ndarray
    omega_rad_s: np.ndarray
    law_states: np.ndarray
    end_reason: str
    ref: TouchdownReference
    dense: object

    @property
    def duration_s(self) -> float:
        """Stance time (s)."""
        return float(self.t_s[-1])


class _StanceSystem:
    """ODE right-hand side and helpers for one stance (internal)."""

    def __init__(self, chain: Chain, law: ImpedanceLaw, ground: GroundLaw, td: TouchdownState):
        self.chain, self.law, self.ground = chain, law, ground
        self.x_toe = float(td.g[0])
        q0 = np.asarray(td.g[2:], float)
        # rho = D q + offset (Eq. 2), checked against joint_angles at touchdown.
        self.rho_offset = np.array([chain.alpha_rad, np.pi, np.pi])
        self.ref = TouchdownReference(
            joint_angles(q0[None], chain.alpha_rad)[0], JOINT_JACOBIAN @ np.asarray(td.gd[2:], float)
        )

    def unpack(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        g = np.empty(6)
        g[0], g[1:] = self.x_toe, y[0:5]
        gd = np.empty(6)
        gd[0], gd[1:] = 0.0, y[5:10]
        return g, gd, y[10:]

    def evaluate(self, t: float, y: np.ndarray):
        g, gd, s = self.unpack(y)
        rho = JOINT_JACOBIAN @ g[2:] + self.rho_offset
        omega = JOINT_JACOBIAN @ gd[2:]
        moments = self.law.moments_nm(np.float64(t), rho, omega, s, self.ref)
        fz = self.ground.force_n(g[1], gd[1])
        gdd, constraint = accelerations(self.chain, g, gd, moments, np.array([0.0, fz]), STANCE_FREE)
        rates = self.law.state_rates(np.float64(t), rho, omega, s, self.ref)
        return g, gd, gdd, np.array([constraint[0], fz]), moments, rho, omega, s, rates

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        _, gd, gdd, *_, rates = self.evaluate(t, y)
        return np.concatenate([gd[1:], gdd[1:], rates])


def simulate_stance(
    chain: Chain,
    law: ImpedanceLaw,
    ground: GroundLaw,
    touchdown: TouchdownState,
    t_max_s: float = 1.0,
    *,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    sample_times_s: np.ndarray | None = None,
    collapse_height_m: float = 0.3,
) -> StanceSimulation:
    """Integrate one stance forward from a touchdown state.

    Parameters
    ----------
    chain : Chain
        Segment parameters (see :func:`chain_from_body_model`).
    law : ImpedanceLaw
        Joint torque law; its time argument is time since touchdown.
    ground : GroundLaw
        Vertical surface law at the toe.
    touchdown : TouchdownState
        Initial state; ``gd[0]`` must be 0 (no-slip).
    t_max_s : float
        Longest stance integrated (s).
    rtol, atol : float
        ``solve_ivp`` tolerances.
    sample_times_s : ndarray, optional
        Times since touchdown at which to report (clipped to the stance); by
        default the solver's own steps.
    collapse_height_m : float
        The stance stops with ``end_reason = "collapse"`` if the COM falls below
        this height above the toe (m).

    Returns
    -------
    StanceSimulation
    """
    if abs(float(touchdown.gd[0])) > 1e-9:
        raise ValueError(f"touchdown toe x velocity must be 0 under the no-slip constraint, got {touchdown.gd[0]}")
    system = _StanceSystem(chain, law, ground, touchdown)
    y0 = np.concatenate([touchdown.g[1:], touchdown.gd[1:], np.zeros(law.n_states)])

    def lift_off(t, y):  # law force reaches zero while rising
        if t < MIN_STANCE_S:
            return 1.0
        return ground.unclipped_force_n(y[0], y[5])

    def leaves_surface(t, y):
        return y[0] if t >= MIN_STANCE_S else -1.0

    def collapse(t, y):
        g, _, _ = system.unpack(y)
        return body_com(chain, g)[1] - g[1] - collapse_height_m

    def overflexion(t, y):  # a joint leaves the anatomical range
        rho = JOINT_JACOBIAN @ y[1:5] + system.rho_offset
        return MAX_JOINT_EXCURSION_RAD - np.abs(rho - system.ref.rho0_rad).max()

    lift_off.terminal, lift_off.direction = True, -1
    leaves_surface.terminal, leaves_surface.direction = True, 1
    collapse.terminal, collapse.direction = True, -1
    overflexion.terminal, overflexion.direction = True, -1
    sol = solve_ivp(
        system.rhs, (0.0, t_max_s), y0, method="LSODA", rtol=rtol, atol=atol,
        dense_output=True, events=(lift_off, leaves_surface, collapse, overflexion),
    )
    if sol.status == -1:
        raise RuntimeError(f"stance integration failed: {sol.message}")
    if len(sol.t_events[2]) or len(sol.t_events[3]):
        end = "collapse"
    elif len(sol.t_events[0]) or len(sol.t_events[1]):
        end = "take_off"
    else:
        end = "t_max"
    t_end = float(sol.t[-1])
    if sample_times_s is None:
        times = sol.t
    else:
        times = np.asarray(sample_times_s, float)
        times = times[(times >= 0) & (times <= t_end)]
    ys = sol.sol(times).T if len(times) else np.zeros((0, len(y0)))
    return _collect(system, times, ys, end, sol.sol)


def _collect(system: _StanceSystem, times: np.ndarray, ys: np.ndarray, end: str, dense) -> StanceSimulation:
    n = len(times)
    out = {k: np.zeros((n, 6)) for k in ("g", "gd", "gdd")}
    grf, mom, rho, omg = (np.zeros((n, k)) for k in (2, 3, 3, 3))
    states = np.zeros((n, system.law.n_states))
    for i, (t, y) in enumerate(zip(times, ys)):
        g, gd, gdd, f, m, r, w, s, _ = system.evaluate(t, y)
        out["g"][i], out["gd"][i], out["gdd"][i] = g, gd, gdd
        grf[i], mom[i], rho[i], omg[i], states[i] = f, m, r, w, s
    return StanceSimulation(times, out["g"], out["gd"], out["gdd"], grf, mom, rho, omg, states, end, system.ref, dense)


def stance_energy_j(chain: Chain, law: ImpedanceLaw, ground: GroundLaw, stance: StanceSimulation) -> np.ndarray:
    """Total mechanical energy (J) at each sample: kinetic + gravity + joint springs + surface.

    Only defined for conservative laws (see :meth:`ImpedanceLaw.elastic_energy_j`).
    """
    kin_pot = np.array([sum(mechanical_energy_j(chain, g, gd)) for g, gd in zip(stance.g, stance.gd)])
    return kin_pot + law.elastic_energy_j(stance.rho_rad, stance.ref) + ground.stored_energy_j(stance.g[:, 1])


def take_off_com_velocity(chain: Chain, stance: StanceSimulation) -> np.ndarray:
    """COM velocity ``[vx, vz]`` (m/s) at the last sample of the stance."""
    return com_velocity(chain, stance.g[-1], stance.gd[-1])
