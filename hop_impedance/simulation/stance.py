"""Forward integration of one stance phase.

Model during stance: toe x held fixed while the foot sticks (horizontal
no-slip as a kinematic constraint; the horizontal ground force is the
constraint force), toe z free on the surface law of
:mod:`hop_impedance.simulation.ground`, segment angles q1..q4 free: 5 degrees
of freedom plus the impedance law's extra states.

Coulomb friction (``friction_coefficient`` mu; the hopping trials use
``DEFAULT_FRICTION_COEFFICIENT`` = 0.8, rubber sole on a plate): the foot sticks while the constraint
force satisfies |Fx| <= mu Fz (+ ``FRICTION_TOLERANCE_N``).
When it would need more (in the last few milliseconds before take-off, where
Fz falls to zero while the joint springs still push), the toe slides: x
becomes free and the ground applies Fx = sign(Fx at slip) mu Fz, opposing the
slide. A slide that stops (toe x velocity back to zero) sticks again. Without
this limit the horizontal force would fall from tens of newtons to zero in one
step at take-off, a step no force plate records. ``friction_coefficient=None``
(the default of :func:`simulate_stance`) keeps the unlimited no-slip contact;
the hopping trials (and so the bundled recordings) use mu = 0.8. The discovery
stance sets keep the unlimited contact: their passive stances on the soft
surface unload slowly and with mu = 0.8 the toe slides ~3 cm and the hop does
not take off.

Integration: ``scipy.integrate.solve_ivp`` with ``LSODA`` (switches to a stiff
method on the rigid surface), ``rtol = 1e-8``, ``atol = 1e-10`` by default,
dense output. Stance ends at the first of: the ground force reaches zero while
the toe rises (take-off), the toe leaves the surface (``y`` crosses 0 upward),
the body collapses (COM below ``collapse_height_m`` above the toe, or a joint
more than 1.5 rad from its touchdown angle), or ``t_max_s``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from hop_impedance.biomech.joint_angles import joint_angles
from hop_impedance.ode_events import TerminalEvent
from hop_impedance.simulation.dynamics import (
    JOINT_JACOBIAN,
    N_COORDS,
    Chain,
    accelerations,
    com_height_above_contact,
    com_velocity,
    mechanical_energy_j,
)
from hop_impedance.simulation.ground import Ground
from hop_impedance.simulation.impedance_laws import ImpedanceLaw, TouchdownReference, TrunkBalance

#: Free coordinates in stance: z_toe, q1..q4 (x_toe fixed).
STANCE_FREE = np.array([False, True, True, True, True, True])

DEFAULT_RTOL = 1e-8
DEFAULT_ATOL = 1e-10
#: A joint moving further than this from its touchdown angle has collapsed (rad).
MAX_JOINT_EXCURSION_RAD = 1.5
#: Contact that ends sooner than this after touchdown is a bounce, not a stance.
MIN_STANCE_S = 0.02
#: Default Coulomb friction coefficient between sole and plate (rubber on steel/aluminium: 0.6-1.0).
DEFAULT_FRICTION_COEFFICIENT = 0.8
#: Coordinates free while the toe slides (all six).
SLIDE_FREE = np.ones(6, dtype=bool)
#: Friction-cone excess tolerated before the toe slides (N): below force-plate noise; it keeps a contact
#: that starts from zero force (lossless surface laws) from chattering between stick and slip.
FRICTION_TOLERANCE_N = 0.5
#: Upper bound on stick/slip alternations in one stance (chatter guard).
MAX_FRICTION_PHASES = 20


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


@dataclass(frozen=True)
class StanceStart:
    """A start inside the stance (issue 16, session 22; :func:`simulate_stance`'s ``start``).

    The law's clock and reference (``rho0``, ``omega0``) stay the touchdown's (``simulate_stance``'s ``touchdown``):
    the integration runs, and times are reported, from ``t_s`` (time since touchdown) on,
    from ``state`` (the toe already in the surface, ``gd[0]`` 0: sticking), with the law's extra states at
    ``law_states`` (their integrals from touchdown to ``t_s``; None: zeros).

    Attributes
    ----------
    t_s : float
        Time since touchdown of ``state`` (s), >= 0.
    state : TouchdownState
        ``[x_toe, z_toe, q1..q4]`` and rates at ``t_s``.
    law_states : ndarray, shape (n_states,), or None
    """

    t_s: float
    state: TouchdownState
    law_states: np.ndarray | None = None


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
    friction_phases : tuple of (t_start_s, slide_sign)
        Stick (0) and slide (+1/-1: sign of the friction force Fx) phases.
    friction_coefficient : float or None
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
    dense: Callable[[np.ndarray], np.ndarray]
    friction_phases: tuple = ((0.0, 0),)
    friction_coefficient: float | None = None
    trunk_balance: TrunkBalance | None = None
    trunk_moments_nm: np.ndarray | None = None
    #: Time since touchdown the integration started at (:class:`StanceStart`; 0: from the touchdown).
    start_s: float = 0.0

    @property
    def slid(self) -> bool:
        """True if the toe slid at some point of the stance."""
        return any(sign != 0 for _, sign in self.friction_phases)

    @property
    def duration_s(self) -> float:
        """Stance time (s)."""
        return float(self.t_s[-1])


class _StanceSystem:
    """ODE right-hand side and helpers for one stance (internal).

    ODE state ``y = [x_toe, z_toe, q1..q4, xd_toe, zd_toe, qd1..qd4, law states]``;
    ``x_toe`` only moves in sliding phases. ``phases`` lists ``(t_start, slide_sign)``
    in time order: ``slide_sign`` 0 = sticking, +1/-1 = sliding with the ground's
    friction force ``Fx = slide_sign mu Fz``.
    """

    def __init__(self, chain: Chain, law: ImpedanceLaw, ground: Ground, td: TouchdownState,
                 friction_coefficient: float | None, phases: tuple = ((0.0, 0),),
                 trunk_balance: TrunkBalance | None = None):
        self.chain, self.law, self.ground = chain, law, ground
        self.trunk = trunk_balance
        self.q4_touchdown = float(td.g[5])
        self.mu = friction_coefficient
        self.phases: list[tuple[float, int]] = list(phases)
        q0 = np.asarray(td.g[2:], float)
        # rho = D q + offset (Eq. 2), checked against joint_angles at touchdown.
        self.rho_offset = np.array([chain.alpha_rad, np.pi, np.pi])
        self.ref = TouchdownReference(
            joint_angles(q0[None], chain.alpha_rad)[0], JOINT_JACOBIAN @ np.asarray(td.gd[2:], float)
        )

    def slide_sign(self, t: float) -> int:
        """Friction mode at time ``t`` since touchdown (the last phase started at or before ``t``)."""
        sign = 0
        for start, mode in self.phases:
            if start <= t:
                sign = mode
        return sign

    @staticmethod
    def unpack(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return y[0:6], y[6:12], y[12:]

    def evaluate(self, t: float, y: np.ndarray, sign: int | None = None):
        g, gd, s = self.unpack(y)
        sign = self.slide_sign(t) if sign is None else sign
        rho = JOINT_JACOBIAN @ g[2:] + self.rho_offset
        omega = JOINT_JACOBIAN @ gd[2:]
        t64 = np.float64(t)
        moments = self.law.moments_nm(t64, rho, omega, s, self.ref)
        if self.trunk is not None:
            moments = moments + np.array([0.0, 0.0, self.trunk.hip_moment_nm(g[5], gd[5], self.q4_touchdown)])
        fz = self.ground.force_n(g[1], gd[1])
        if sign == 0:
            gdd, constraint = accelerations(self.chain, g, gd, moments, np.array([0.0, fz]), STANCE_FREE)
            fx = constraint[0]
        else:
            assert self.mu is not None  # sliding phases exist only with friction (see _integrate_friction_phases)
            fx = sign * self.mu * fz
            gdd, _ = accelerations(self.chain, g, gd, moments, np.array([fx, fz]), SLIDE_FREE)
        rates = self.law.state_rates(t64, rho, omega, s, self.ref)
        return g, gd, gdd, np.array([fx, fz]), moments, rho, omega, s, rates

    def rhs_for(self, sign: int):
        """ODE right-hand side of one friction mode on the full state (see class docstring)."""
        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            _, gd, gdd, *_, rates = self.evaluate(t, y, sign)
            return np.concatenate([gd, gdd, rates])
        return rhs


class _PhaseState:
    """Map between the full state and the integrated one of a phase.

    While the toe sticks, ``x_toe`` and its velocity are not integrated (they
    are the fixed contact point and 0): the solver sees exactly the 5-DOF
    system, so with ``friction_coefficient=None`` results are identical to a
    stance model without friction.
    """

    def __init__(self, sign: int, full_size: int, x_toe_m: float) -> None:
        self.sign, self.x_toe_m = sign, x_toe_m
        self.index = np.arange(full_size) if sign != 0 else np.r_[1:6, 7:full_size]
        self.full_size = full_size

    def reduce(self, y_full: np.ndarray) -> np.ndarray:
        return y_full[self.index]

    def expand(self, y: np.ndarray) -> np.ndarray:
        """Full state(s) from integrated state(s), shape (n,) or (n, k)."""
        if self.sign != 0:
            return y
        full = np.zeros((self.full_size,) + np.shape(y)[1:])
        full[self.index] = y
        full[0] = self.x_toe_m
        return full

    def wrap(self, fun):
        """A function of (t, full y) as a function of (t, integrated y), keeping event attributes."""
        def wrapped(t, y):
            return fun(t, self.expand(y))
        for attr in ("terminal", "direction", "__name__"):
            if hasattr(fun, attr):
                setattr(wrapped, attr, getattr(fun, attr))
        return wrapped

    def rhs(self, full_rhs):
        if self.sign != 0:
            return full_rhs

        def rhs(t, y):
            return full_rhs(t, self.expand(y))[self.index]
        return rhs


class _PiecewiseDense:
    """Dense output over consecutive phases: ``dense(t) -> full y`` (columns = times), as solve_ivp's ``sol``."""

    def __init__(self) -> None:
        self.pieces: list[tuple[float, object, _PhaseState]] = []  # (phase end s, solve_ivp sol, phase)

    def append(self, t_end_s: float, sol, phase: _PhaseState) -> None:
        self.pieces.append((t_end_s, sol, phase))

    def __call__(self, t):
        t = np.asarray(t, float)
        scalar = t.ndim == 0
        times = np.atleast_1d(t)
        ends = np.array([p[0] for p in self.pieces])
        which = np.minimum(np.searchsorted(ends, times, side="left"), len(self.pieces) - 1)
        out = np.empty((self.pieces[0][2].full_size, times.size))
        for k in np.unique(which):
            sel = which == k
            _, sol, phase = self.pieces[k]
            out[:, sel] = phase.expand(sol(times[sel]))
        return out[:, 0] if scalar else out


def simulate_stance(
    chain: Chain,
    law: ImpedanceLaw,
    ground: Ground,
    touchdown: TouchdownState,
    t_max_s: float = 1.0,
    *,
    rtol: float = DEFAULT_RTOL,
    atol: float | np.ndarray = DEFAULT_ATOL,
    sample_times_s: np.ndarray | None = None,
    collapse_height_m: float = 0.3,
    friction_coefficient: float | None = None,
    trunk_balance: TrunkBalance | None = None,
    start: StanceStart | None = None,
) -> StanceSimulation:
    """Integrate one stance forward from a touchdown state (or from a state inside the stance, ``start``).

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
        ``solve_ivp`` tolerances; ``atol`` may be an array over the full ODE state (:func:`state_atol`).
    sample_times_s : ndarray, optional
        Times since touchdown at which to report (clipped to the stance); by
        default the solver's own steps.
    collapse_height_m : float
        The stance stops with ``end_reason = "collapse"`` if the COM falls below
        this height above the toe (m).
    friction_coefficient : float or None
        Coulomb friction coefficient of the sole (module docstring); None (default)
        = the toe never slides. Hopping trials use ``DEFAULT_FRICTION_COEFFICIENT``
        (:class:`~hop_impedance.simulation.hopping_trial.HoppingConfig`).
    trunk_balance : TrunkBalance or None
        Postural moment on the trunk added at the hip (None: the hip carries the law only).
    start : StanceStart or None
        From a state inside the stance (session 22; :class:`StanceStart`); None (default): from ``touchdown``.

    Returns
    -------
    StanceSimulation
    """
    t0, y = _initial_state(touchdown, law, start)
    _check_stance_inputs(TouchdownState(y[0:6], y[6:12]), friction_coefficient)
    system = _StanceSystem(chain, law, ground, touchdown, friction_coefficient, trunk_balance=trunk_balance)
    events = _stance_events(system, collapse_height_m)
    run = _integrate_friction_phases(system, events, y, t_max_s, rtol, atol, t0)
    times = _report_times(run.steps, sample_times_s, run.t_end_s, t0)
    ys = run.dense(times).T if len(times) else np.zeros((0, len(y)))
    return _collect(system, times, ys, run.end_reason, run.dense, t0)


def _initial_state(touchdown: TouchdownState, law: ImpedanceLaw, start: StanceStart | None) -> tuple[float, np.ndarray]:
    """(time since touchdown, ODE state) the integration starts from: ``touchdown`` at 0 with the law's states 0, or
    ``start``'s."""
    if start is None:
        return 0.0, np.concatenate([touchdown.g, touchdown.gd, np.zeros(law.n_states)])
    states = np.zeros(law.n_states) if start.law_states is None else np.asarray(start.law_states, float)
    return float(start.t_s), np.concatenate([start.state.g, start.state.gd, states])


def _check_stance_inputs(touchdown: TouchdownState, friction_coefficient: float | None) -> None:
    """Raise ValueError for a touchdown that moves the toe horizontally or a non-positive friction coefficient."""
    if abs(float(touchdown.gd[0])) > 1e-9:
        raise ValueError(f"touchdown toe x velocity must be 0 under the no-slip constraint, got {touchdown.gd[0]}")
    if friction_coefficient is not None and not friction_coefficient > 0:
        raise ValueError(f"friction_coefficient must be positive (or None for no slipping), got {friction_coefficient}")


@dataclass
class _StanceEvents:
    """The ``solve_ivp`` events that end a stance phase (each terminal; module docstring).

    ``lift_off``: the law's ground force reaches zero while rising; ``leaves_surface``: the toe
    crosses z = 0 upward; ``collapse``: the COM falls below the collapse height above the toe;
    ``overflexion``: a joint leaves the anatomical range (:data:`MAX_JOINT_EXCURSION_RAD`);
    ``slips``: while sticking, the friction cone is left (|Fx| > mu Fz); ``sticks``: while sliding,
    the toe stops. The first two ignore the first :data:`MIN_STANCE_S` (a bounce, not a stance).
    """

    lift_off: TerminalEvent
    leaves_surface: TerminalEvent
    collapse: TerminalEvent
    overflexion: TerminalEvent
    slips: TerminalEvent
    sticks: TerminalEvent

    def for_phase(self, sign: int, friction: bool) -> list:
        """Events of a phase, in the order :func:`_integrate_friction_phases` reads ``t_events``.

        ``sign`` 0 = sticking (may slip), +1/-1 = sliding (may stick; the toe slides against the
        friction force, so its x velocity has sign -sign).
        """
        events = [self.lift_off, self.leaves_surface, self.collapse, self.overflexion]
        if friction:
            self.sticks.direction = sign
            events.append(self.slips if sign == 0 else self.sticks)
        return events


def state_atol(law: ImpedanceLaw, atol: float, toe_atol: float) -> np.ndarray:
    """Absolute tolerances over :func:`simulate_stance`'s full ODE state (:class:`_StanceSystem`'s ``y``):
    ``toe_atol`` on the toe's height and vertical velocity, ``atol`` on the rest."""
    tolerances = np.full(2 * N_COORDS + law.n_states, atol)
    tolerances[[1, N_COORDS + 1]] = toe_atol  # z_toe, zd_toe
    return tolerances


def _stance_events(system: _StanceSystem, collapse_height_m: float) -> _StanceEvents:
    """The terminal events of one stance (:class:`_StanceEvents`) on the full ODE state."""
    chain, ground, friction_coefficient = system.chain, system.ground, system.mu

    def lift_off(t, y):  # law force reaches zero while rising
        if t < MIN_STANCE_S:
            return 1.0
        return ground.unclipped_force_n(y[1], y[7])

    def leaves_surface(t, y):
        return y[1] if t >= MIN_STANCE_S else -1.0

    def collapse(t, y):
        return com_height_above_contact(chain, y[2:6]) - collapse_height_m

    def overflexion(t, y):  # a joint leaves the anatomical range
        rho = JOINT_JACOBIAN @ y[2:6] + system.rho_offset
        return MAX_JOINT_EXCURSION_RAD - np.abs(rho - system.ref.rho0_rad).max()

    def slips(t, y):  # sticking: friction cone left (|Fx| > mu Fz)
        _, _, _, force, *_ = system.evaluate(t, y, 0)
        return friction_coefficient * force[1] + FRICTION_TOLERANCE_N - abs(force[0])

    def sticks(t, y):  # sliding: the toe stops
        return y[6]

    return _StanceEvents(TerminalEvent(lift_off, -1), TerminalEvent(leaves_surface, 1), TerminalEvent(collapse, -1),
                         TerminalEvent(overflexion, -1), TerminalEvent(slips, -1), TerminalEvent(sticks))


@dataclass
class _PhasesRun:
    """What :func:`_integrate_friction_phases` integrated: end time (s), end reason, dense output, solver steps."""

    t_end_s: float
    end_reason: str
    dense: _PiecewiseDense
    steps: list


def _integrate_friction_phases(system: _StanceSystem, events: _StanceEvents, y: np.ndarray, t_max_s: float,
                               rtol: float, atol: float | np.ndarray, t_start_s: float = 0.0) -> _PhasesRun:
    """Integrate stick and slide phases in turn until take-off, collapse or ``t_max_s``.

    Each phase is one :func:`_integrate_phase` on the coordinates free in it (:class:`_PhaseState`);
    a phase ended by ``slips`` starts a slide against the friction force's direction, one ended by
    ``sticks`` sticks again (toe x velocity set to 0). ``system.phases`` records the switches.
    Raises RuntimeError after :data:`MAX_FRICTION_PHASES` phases (chatter) or a failed integration.
    """
    dense = _PiecewiseDense()
    steps = []
    t0, sign = t_start_s, 0
    for _ in range(MAX_FRICTION_PHASES):
        phase_events = events.for_phase(sign, system.mu is not None)
        phase = _PhaseState(sign, y.size, float(y[0]))
        sol = _integrate_phase(phase.rhs(system.rhs_for(sign)), (t0, t_max_s), phase.reduce(y),
                               [phase.wrap(e) for e in phase_events], rtol,
                               phase.reduce(atol) if isinstance(atol, np.ndarray) else atol)
        if sol.status == -1:
            raise RuntimeError(f"stance integration failed: {sol.message}")
        dense.append(float(sol.t[-1]), sol.sol, phase)
        steps.append(sol.t)
        t0, y = float(sol.t[-1]), phase.expand(sol.y[:, -1])
        if len(sol.t_events[2]) or len(sol.t_events[3]):
            return _PhasesRun(t0, "collapse", dense, steps)
        if len(sol.t_events[0]) or len(sol.t_events[1]):
            return _PhasesRun(t0, "take_off", dense, steps)
        if sol.status != 1:  # reached t_max
            return _PhasesRun(t0, "t_max", dense, steps)
        if sign == 0:  # slips: slide against the friction force's direction
            _, _, _, force, *_ = system.evaluate(t0, y, 0)
            sign = 1 if force[0] > 0 else -1
        else:  # stops sliding: stick again
            sign, y[6] = 0, 0.0
        system.phases.append((t0, sign))
    raise RuntimeError(f"stance integration: more than {MAX_FRICTION_PHASES} stick/slip phases")


def _report_times(steps: list, sample_times_s: np.ndarray | None, t_end_s: float,
                  t_start_s: float = 0.0) -> np.ndarray:
    """Times since touchdown to report: the solver's own steps, or ``sample_times_s`` within [t_start_s, t_end_s]."""
    if sample_times_s is None:
        return np.unique(np.concatenate(steps))
    times = np.asarray(sample_times_s, float)
    return times[(times >= t_start_s) & (times <= t_end_s)]


def _integrate_phase(rhs, span: tuple[float, float], y0: np.ndarray, events: list, rtol: float,
                     atol: float | np.ndarray):
    """``solve_ivp`` with LSODA; Radau if LSODA's event location fails.

    LSODA can return a zero-length step on which scipy's event root finder
    sees the same value at both ends and raises "f(a) and f(b) must have
    different signs" (met when a joint runs into the collapse limit under a
    badly identified law). That phase is then integrated with the implicit
    Radau method; if that fails too, a RuntimeError says why.
    """
    try:
        return solve_ivp(rhs, span, y0, method="LSODA", rtol=rtol, atol=atol, dense_output=True, events=events)
    except ValueError as lsoda_error:
        try:
            return solve_ivp(rhs, span, y0, method="Radau", rtol=rtol, atol=atol, dense_output=True, events=events)
        except ValueError as radau_error:
            raise RuntimeError(f"stance integration failed: event location ({lsoda_error}; "
                               f"Radau: {radau_error})") from radau_error


def resample_stance(chain: Chain, law: ImpedanceLaw, ground: Ground, touchdown: TouchdownState,
                    stance: StanceSimulation, t_since_td: np.ndarray) -> StanceSimulation:
    """``stance`` (integrated by :func:`simulate_stance` with these inputs) at other times since
    touchdown (s), from its dense output without re-integration; times are clipped to the stance."""
    system = _StanceSystem(chain, law, ground, touchdown, stance.friction_coefficient, stance.friction_phases,
                           stance.trunk_balance)
    t = np.clip(np.asarray(t_since_td, float), 0.0, stance.duration_s)
    return _collect(system, t, stance.dense(t).T, stance.end_reason, stance.dense)


def _collect(system: _StanceSystem, times: np.ndarray, ys: np.ndarray, end: str, dense,
             start_s: float = 0.0) -> StanceSimulation:
    n = len(times)
    out = {k: np.zeros((n, 6)) for k in ("g", "gd", "gdd")}
    grf, mom, rho, omg = (np.zeros((n, k)) for k in (2, 3, 3, 3))
    states = np.zeros((n, system.law.n_states))
    for i, (t, y) in enumerate(zip(times, ys)):
        g, gd, gdd, f, m, r, w, s, _ = system.evaluate(t, y)
        out["g"][i], out["gd"][i], out["gdd"][i] = g, gd, gdd
        grf[i], mom[i], rho[i], omg[i], states[i] = f, m, r, w, s
    trunk = None
    if system.trunk is not None:
        trunk = np.zeros((n, 3))
        trunk[:, 2] = system.trunk.hip_moment_nm(out["g"][:, 5], out["gd"][:, 5], system.q4_touchdown)
    return StanceSimulation(times, out["g"], out["gd"], out["gdd"], grf, mom, rho, omg, states, end, system.ref, dense,
                            tuple(system.phases), system.mu, system.trunk, trunk, start_s)


def stance_energy_j(chain: Chain, law: ImpedanceLaw, ground: Ground, stance: StanceSimulation) -> np.ndarray:
    """Total mechanical energy (J) at each sample: kinetic + gravity + joint springs + surface.

    Only defined for conservative laws (see :meth:`ImpedanceLaw.elastic_energy_j`). A trunk-balance
    moment is not conservative (it acts at the hip, so it also does work on the thigh): its work,
    ``int -M_balance omega_hip dt``, is not in this total.
    """
    kin_pot = np.array([sum(mechanical_energy_j(chain, g, gd)) for g, gd in zip(stance.g, stance.gd)])
    return kin_pot + law.elastic_energy_j(stance.rho_rad, stance.ref) + ground.stored_energy_j(stance.g[:, 1])


def take_off_com_velocity(chain: Chain, stance: StanceSimulation) -> np.ndarray:
    """COM velocity ``[vx, vz]`` (m/s) at the last sample of the stance."""
    return com_velocity(chain, stance.g[-1], stance.gd[-1])
