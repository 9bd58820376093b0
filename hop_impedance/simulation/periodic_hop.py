"""The hop-to-hop map of a noise-free trial, its periodic orbit (fixed point) and that orbit's stability.

Issue 17: with lossless laws and the energy-keeping flight, the push-off-free hop drifts over 30
hops. Whether that is a wrong start or an unstable orbit is a property of the return map

    x_{n+1} = P(x_n),   x = [touchdown speed (m/s, down), COM vx (m/s), COM ahead of the toe (m),
                             segment rates q1..q4 (rad/s)]

at touchdown, defined exactly as :func:`~hop_impedance.simulation.hopping_trial.simulate_hopping`
steps a noise-free hop: the stance from that touchdown, the Raibert foot placement for the next
touchdown posture (the joint angles stay ``touchdown_rho_rad``), and the flight
(``HoppingConfig.flight``) to the next touchdown. A periodic hop is a root of ``P(x) - x``
(``scipy.optimize.root``, :func:`periodic_hop`); the eigenvalues of the Jacobian ``dP/dx`` there
(central differences) say whether a small error grows (some ``|lambda| > 1``) or dies out. One
eigenvalue is 0 by construction: the touchdown rates' part that would slide the toe is removed
(:func:`~hop_impedance.simulation.hopping_trial.touchdown_state`), so ``P`` ignores it.

A conservative hopper keeps its energy, so its periodic hops come in a family (one eigenvalue 1) and nothing but
the landing can steer it: :func:`landing_feedback` chooses the landing rates and the foot placement from the hop's
touchdown state (:class:`~hop_impedance.simulation.hopping_trial.LandingFeedback`, a linear-quadratic regulator on
``P``), which keeps the energy and makes the periodic hop attract (issue 17, session 15).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hop_impedance.simulation.dynamics import Chain, com_velocity
from hop_impedance.simulation.hopping_trial import (
    HopCalibration,
    HoppingConfig,
    LandingFeedback,
    _flight_to_next_touchdown,
    landing_for_hop,
    scale_push_off,
    touchdown_posture,
    touchdown_state,
    touchdown_state_vector,
)
from hop_impedance.simulation.stance import StanceSimulation, StanceStart, TouchdownState, simulate_stance

#: Names of the touchdown-state vector's entries (units in the module docstring).
STATE_NAMES = ("speed_m_s", "com_vx_m_s", "com_ahead_m", "rate_q1", "rate_q2", "rate_q3", "rate_q4")
#: Central-difference steps of the Jacobian per entry: well above the stance integration's noise
#: (rtol 1e-8) and small against the state (m/s, m/s, m, rad/s).
JACOBIAN_STEPS = np.array([1e-5, 1e-5, 1e-6, 1e-4, 1e-4, 1e-4, 1e-4])


def touchdown_vector(speed_m_s: float, com_vx_m_s: float, com_ahead_m: float, rates_rad_s) -> np.ndarray:
    """The map's state vector (module docstring) from its parts."""
    return np.r_[speed_m_s, com_vx_m_s, com_ahead_m, np.asarray(rates_rad_s, float)]


def hop_step(chain: Chain, config: HoppingConfig, cal: HopCalibration,
             x: np.ndarray) -> tuple[np.ndarray, StanceSimulation]:
    """One noise-free hop from touchdown state ``x``: (next touchdown state, the stance).

    Raises ValueError when the stance does not take off or the take-off is too weak to fly.
    """
    rho = np.asarray(config.touchdown_rho_rad, float)
    speed, vx, ahead, rates = float(x[0]), float(x[1]), float(x[2]), np.asarray(x[3:7], float)
    law = scale_push_off(config.law, cal.push_scale)
    td = touchdown_state(chain, touchdown_posture(chain, rho, ahead), np.array([vx, -speed]), 0.0, rates)
    st = simulate_stance(chain, law, config.surface, td, t_max_s=2.0 / config.freq_hz, rtol=config.rtol,
                         atol=config.atol, friction_coefficient=config.friction_coefficient,
                         trunk_balance=config.trunk_balance)
    if st.end_reason != "take_off":
        raise ValueError(f"stance ended by {st.end_reason}")
    vx_to = float(com_velocity(chain, st.g[-1], st.gd[-1])[0])
    config, cal = landing_for_hop(chain, config, cal, td)
    ahead_next = cal.com_ahead_m - vx_to * (0.5 * st.duration_s + config.placement_gain_s)
    nxt = _flight_to_next_touchdown(chain, config, law, st, touchdown_posture(chain, rho, ahead_next), 0.0,
                                    last=False)
    rates_next = np.zeros(4) if nxt.rates is None else nxt.rates
    # the rates actually used at that touchdown (toe-sliding part removed), as the trial uses them
    used = touchdown_state(chain, touchdown_posture(chain, rho, ahead_next),
                           np.array([nxt.com_vx_m_s, -nxt.speed_m_s]), 0.0, rates_next).gd[2:]
    return touchdown_vector(nxt.speed_m_s, nxt.com_vx_m_s, ahead_next, used), st


@dataclass(frozen=True)
class PeriodicHop:
    """A fixed point of the hop map and its stability (all SI).

    Attributes
    ----------
    state : ndarray, shape (7,)
        Touchdown state (:data:`STATE_NAMES`).
    residual : ndarray, shape (7,)
        ``P(state) - state``.
    success : bool
        The root finder converged and ``max |residual| < 1e-6``.
    stance_s, flight_s : float
        Stance and flight time of the periodic hop (s).
    eigenvalues : ndarray, shape (7,), complex
        Of ``dP/dx`` at the fixed point, largest modulus first (one is ~0, module docstring).
    jacobian : ndarray, shape (7, 7)
        ``dP/dx`` they are computed from.
    com_ahead_m : float
        The foot placement's reference offset it was found with (``HopCalibration.com_ahead_m``, m).
    """

    state: np.ndarray
    residual: np.ndarray
    success: bool
    stance_s: float
    flight_s: float
    eigenvalues: np.ndarray
    jacobian: np.ndarray
    com_ahead_m: float

    @property
    def spectral_radius(self) -> float:
        """Largest ``|lambda|``: above 1 the orbit is unstable (a small error grows by it per hop)."""
        return float(np.abs(self.eigenvalues).max())


def hop_map_jacobian(chain: Chain, config: HoppingConfig, cal: HopCalibration, x: np.ndarray) -> np.ndarray:
    """``dP/dx`` (7 x 7) at ``x`` by central differences (:data:`JACOBIAN_STEPS`)."""
    return _central_differences(lambda v: hop_step(chain, config, cal, v)[0], np.asarray(x, float), JACOBIAN_STEPS)


def _central_differences(fun, x: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Jacobian of ``fun`` at ``x`` by central differences with one step per entry of ``x``."""
    columns = []
    for k, h in enumerate(steps):
        step = np.zeros(len(x))
        step[k] = h
        columns.append((fun(x + step) - fun(x - step)) / (2 * h))
    return np.array(columns).T


#: Central-difference step of the foot placement's reference offset (m) when :func:`periodic_hop` solves for it.
PLACEMENT_STEP_M = 1e-6


@dataclass(frozen=True)
class _OrbitConditions:
    """What :func:`periodic_hop` solves for besides ``P(x) = x``: with ``in_place`` also the foot placement's
    reference offset (``HopCalibration.com_ahead_m``, unknown ``z[7]``) so that the hop stays in place (COM vx 0 at
    touchdown); with ``period_s`` the periodic hop of that period (stance + flight), chosen along the family of
    periodic hops of a conservative hopper; with ``own_landing`` the energy-keeping flight's landing rule
    (``HoppingConfig.landing_rates_rad_s``) lands along the hop's own touchdown rates, so the rule's direction is an
    unknown too (its fixed point is then a fixed point of the trial that lands along them)."""

    chain: Chain
    config: HoppingConfig
    cal: HopCalibration
    in_place: bool
    period_s: float | None
    own_landing: bool

    def calibration(self, z: np.ndarray) -> HopCalibration:
        return replace(self.cal, com_ahead_m=float(z[7])) if self.in_place else self.cal

    def landing_config(self, x: np.ndarray) -> HoppingConfig:
        """The configuration whose landing rule lands along the state's own touchdown rates (``own_landing``)."""
        return replace(self.config, landing_rates_rad_s=tuple(float(v) for v in x[3:7])) if self.own_landing else self.config

    def residual(self, z: np.ndarray) -> np.ndarray:
        x = z[:7]
        nxt, st = hop_step(self.chain, self.landing_config(x), self.calibration(z), x)
        out = [nxt - x]
        if self.in_place:
            out.append([x[1]])
        if self.period_s is not None:
            out.append([st.duration_s + _flight_s(self.chain, st, float(nxt[0])) - self.period_s])
        return np.concatenate(out)

    def steps(self) -> np.ndarray:
        return np.r_[JACOBIAN_STEPS, [PLACEMENT_STEP_M] if self.in_place else []]


def _flight_s(chain: Chain, st: StanceSimulation, next_speed_m_s: float) -> float:
    """Flight time (s) after stance ``st`` to a touchdown at ``next_speed_m_s`` (ballistic COM)."""
    return (next_speed_m_s + float(com_velocity(chain, st.g[-1], st.gd[-1])[1])) / chain.gravity_m_s2


def periodic_hop(chain: Chain, config: HoppingConfig, cal: HopCalibration, guess: np.ndarray,
                 max_iterations: int = 12, tolerance: float = 1e-6, in_place: bool = False,
                 period_s: float | None = None, own_landing: bool = False) -> PeriodicHop:
    """The periodic hop nearest ``guess``: a root of ``P(x) - x`` by damped Newton steps, and its eigenvalues.

    Each step solves ``(J - I) dx = -(P(x) - x)`` with ``J`` = ``dP/dx`` (:func:`hop_map_jacobian`; least squares:
    ``J - I`` is singular along a family of periodic hops of a conservative hopper) and halves the step
    until the residual falls (at most 6 times). Stops when ``max |P(x) - x| < tolerance``. The
    eigenvalues are those of the last Jacobian (at the returned state, or one step before it).
    ``in_place``: also solve for the foot placement's reference offset that keeps the hop in place (COM vx 0;
    returned in ``PeriodicHop.com_ahead_m``); ``period_s``: the periodic hop of that period; ``own_landing``: land along
    the hop's own touchdown rates (:class:`_OrbitConditions`; the eigenvalues are then those of the trial landing along
    the found rates, a fixed rule).
    """
    cond = _OrbitConditions(chain, config, cal, in_place, period_s, own_landing)
    z = np.r_[np.asarray(guess, float), [cal.com_ahead_m] if in_place else []]
    res = cond.residual(z)
    jac = _central_differences(cond.residual, z, cond.steps())
    for _ in range(max_iterations):
        if np.abs(res).max() < tolerance:
            break
        dz = np.linalg.lstsq(jac, -res, rcond=None)[0]  # jac: of the residual, i.e. [J - I, ...]
        lam = 1.0
        for _ in range(6):
            try:
                trial_res = cond.residual(z + lam * dz)
            except ValueError:
                lam /= 2
                continue
            if np.abs(trial_res).max() < np.abs(res).max():
                break
            lam /= 2
        else:
            break  # no step along dz lowers the residual
        z, res = z + lam * dz, trial_res
        jac = _central_differences(cond.residual, z, cond.steps())
    x = z[:7]
    nxt, st = hop_step(chain, cond.landing_config(x), cond.calibration(z), x)
    hop_jac = jac[:7, :7] + np.eye(7)  # dP/dx
    if own_landing:  # the trial's map lands along the found rates, held fixed
        hop_jac = hop_map_jacobian(chain, cond.landing_config(x), cond.calibration(z), x)
    eig = np.linalg.eigvals(hop_jac)
    eig = eig[np.argsort(-np.abs(eig))]
    res = cond.residual(z)
    return PeriodicHop(x, res, bool(np.abs(res).max() < tolerance), st.duration_s, _flight_s(chain, st, float(nxt[0])),
                       eig, hop_jac, cond.calibration(z).com_ahead_m)


#: Central-difference steps of the landing controls (:func:`landing_feedback`): landing rates (rad/s) and the foot
#: placement's reference offset (m).
CONTROL_STEPS = np.array([1e-4, 1e-4, 1e-4, 1e-4, 1e-6])


def landing_feedback(chain: Chain, config: HoppingConfig, cal: HopCalibration, state: np.ndarray,
                     discount: float = 1.02, control_weight: float = 1.0) -> tuple[LandingFeedback, np.ndarray]:
    """A :class:`~hop_impedance.simulation.hopping_trial.LandingFeedback` about the touchdown state ``state`` (a periodic
    hop found landing along ``config.landing_rates_rad_s`` with the placement reference ``cal.com_ahead_m``, which it
    makes attract nearby hops), and the closed loop's eigenvalues there (largest modulus first).

    Linear-quadratic regulator on the hop map linearised there, ``dx' = A dx + B du`` (central differences;
    ``u`` = landing rates and placement reference, :data:`CONTROL_STEPS`), with unit weights on the state and
    ``control_weight`` on the controls. The hop's energy is an invariant no landing changes (``A`` has the eigenvalue
    1 along it, out of ``B``'s reach), so the regulator is solved for ``A / discount`` (``discount`` > 1 moves that
    eigenvalue inside the unit circle); the closed loop keeps it at 1 and damps the rest. About a state that is not
    periodic the same feedback holds the hop near it: its closed loop's periodic hop is a start for the open loop's.
    """
    from scipy.linalg import solve_discrete_are

    if config.landing_rates_rad_s is None:
        raise ValueError("landing_feedback needs the landing rule the periodic hop was found with (landing_rates_rad_s)")
    landing0 = np.asarray(config.landing_rates_rad_s, float)
    x0 = np.asarray(state, float)

    def controlled(u: np.ndarray) -> np.ndarray:
        cfg = replace(config, landing_rates_rad_s=tuple(float(v) for v in landing0 + u[:4]))
        return hop_step(chain, cfg, replace(cal, com_ahead_m=cal.com_ahead_m + float(u[4])), x0)[0]

    a = hop_map_jacobian(chain, config, cal, x0)
    b = _central_differences(controlled, np.zeros(5), CONTROL_STEPS)
    q, r = np.eye(7), control_weight * np.eye(5)
    a_s, b_s = a / discount, b / discount
    p = solve_discrete_are(a_s, b_s, q, r)
    gain = np.linalg.solve(r + b_s.T @ p @ b_s, b_s.T @ p @ a_s)
    eig = np.linalg.eigvals(a - b @ gain)
    feedback = LandingFeedback(tuple(float(v) for v in x0), tuple(float(v) for v in landing0), float(cal.com_ahead_m),
                               tuple(tuple(float(v) for v in row) for row in gain))
    return feedback, eig[np.argsort(-np.abs(eig))]


#: Scales of the unknowns of :func:`symmetric_hop` (joint flexions rad, COM ahead m) for the solver.
SYMMETRIC_SCALES = np.array([0.1, 0.1, 0.1, 0.01])
#: Finite-difference step of :func:`symmetric_hop`'s solver (relative): above the take-off event's timing noise.
SYMMETRIC_DIFF_STEP = 1e-4
#: :func:`symmetric_hop` stops below this residual (rad, m/s); else it restarts the solver, at most SYMMETRIC_RESTARTS times.
SYMMETRIC_TOLERANCE = 1e-8
SYMMETRIC_RESTARTS = 4


def symmetric_stance(chain: Chain, config: HoppingConfig, mid: np.ndarray) -> StanceSimulation:
    """The second half of a time-symmetric stance of a conservative hopper, from its turning point ``mid``.

    ``mid`` = [joint flexions from the touchdown posture (rad, 3), COM ahead of the toe (m), toe height (m, < 0: the
    surface compressed)], every velocity zero. The law is referenced to ``config.touchdown_rho_rad`` (the trial's
    touchdown posture). A conservative system that passes a state of zero velocity retraces its path backwards in
    time from it, so this half, mirrored, is the stance's first half.
    """
    rho_td = np.asarray(config.touchdown_rho_rad, float)
    mid = np.asarray(mid, float)
    reference = TouchdownState(np.r_[0.0, 0.0, touchdown_posture(chain, rho_td, 0.0)], np.zeros(6))
    turning = TouchdownState(np.r_[0.0, mid[4], touchdown_posture(chain, rho_td + mid[:3], mid[3])], np.zeros(6))
    return simulate_stance(chain, config.law, config.surface, reference, t_max_s=1.0, rtol=config.rtol,
                           atol=config.atol, friction_coefficient=config.friction_coefficient,
                           trunk_balance=config.trunk_balance, start=StanceStart(0.0, turning))


def symmetric_hop(chain: Chain, config: HoppingConfig, guess: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """A periodic hop in place of a conservative hopper, built from a time-symmetric stance (session 31).

    Why: Newton steps on the hop map (:func:`periodic_hop`) from the calibrated hop found no periodic hop of the
    seed-like hopper's lossless counterpart at 1.87 and 1.53 Hz's laws (session 15). A hop whose stance passes a
    turning point (every velocity zero, :func:`symmetric_stance`) takes off in the mirror image of its touchdown:
    the same posture, every velocity reversed. If at take-off the joint angles are the touchdown posture's and the
    COM moves straight up, the ballistic flight and the energy-keeping flight's landing (the take-off's segment rates
    reversed, the take-off's posture and COM offset) close the hop exactly: a fixed point of the hop map.
    Solved for the turning point's joint flexions and COM offset (``guess[:4]``; ``scipy.optimize.least_squares``):
    take-off joint angles = the touchdown posture's (3) and COM vx 0 (1). The toe height there (``guess[4]``, the
    surface's compression) is held: it picks the hop's energy in the family of periodic hops of a conservative hopper.

    Returns (the turning point, the touchdown state vector (:data:`STATE_NAMES`), max |residual|). Raises ValueError
    when the stance from ``guess`` does not take off.
    """
    from scipy.optimize import least_squares

    rho_td = np.asarray(config.touchdown_rho_rad, float)
    guess = np.asarray(guess, float)

    def residual(u: np.ndarray) -> np.ndarray:
        try:
            st = symmetric_stance(chain, config, np.r_[u, guess[4]])
        except ValueError:  # no posture with that COM offset (touchdown_posture)
            return np.full(4, 1.0)
        if st.end_reason != "take_off":
            return np.full(4, 1.0)  # flat: the solver stays where the stance takes off
        return np.r_[st.rho_rad[-1] - rho_td, com_velocity(chain, st.g[-1], st.gd[-1])[0]]

    if symmetric_stance(chain, config, guess).end_reason != "take_off":
        raise ValueError("the stance from the guessed turning point does not take off")
    u = guess[:4]
    for _ in range(SYMMETRIC_RESTARTS):
        sol = least_squares(residual, u, diff_step=SYMMETRIC_DIFF_STEP, x_scale=SYMMETRIC_SCALES, max_nfev=100)
        u = sol.x
        if np.abs(sol.fun).max() < SYMMETRIC_TOLERANCE:
            break
    mid = np.r_[u, guess[4]]
    st = symmetric_stance(chain, config, mid)
    take_off = TouchdownState(st.g[-1], -st.gd[-1])  # its mirror image: the touchdown
    return mid, touchdown_state_vector(chain, take_off), float(np.abs(sol.fun).max())
