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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hop_impedance.simulation.dynamics import Chain, com_velocity
from hop_impedance.simulation.hopping_trial import (
    HopCalibration,
    HoppingConfig,
    _flight_to_next_touchdown,
    scale_push_off,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.stance import StanceSimulation, simulate_stance

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
    """

    state: np.ndarray
    residual: np.ndarray
    success: bool
    stance_s: float
    flight_s: float
    eigenvalues: np.ndarray
    jacobian: np.ndarray

    @property
    def spectral_radius(self) -> float:
        """Largest ``|lambda|``: above 1 the orbit is unstable (a small error grows by it per hop)."""
        return float(np.abs(self.eigenvalues).max())


def hop_map_jacobian(chain: Chain, config: HoppingConfig, cal: HopCalibration, x: np.ndarray) -> np.ndarray:
    """``dP/dx`` (7 x 7) at ``x`` by central differences (:data:`JACOBIAN_STEPS`)."""
    jac = np.zeros((7, 7))
    for k, h in enumerate(JACOBIAN_STEPS):
        step = np.zeros(7)
        step[k] = h
        jac[:, k] = (hop_step(chain, config, cal, x + step)[0] - hop_step(chain, config, cal, x - step)[0]) / (2 * h)
    return jac


def periodic_hop(chain: Chain, config: HoppingConfig, cal: HopCalibration, guess: np.ndarray,
                 max_iterations: int = 12, tolerance: float = 1e-6) -> PeriodicHop:
    """The periodic hop nearest ``guess``: a root of ``P(x) - x`` by damped Newton steps, and its eigenvalues.

    Each step solves ``(J - I) dx = -(P(x) - x)`` with ``J`` = :func:`hop_map_jacobian` (least squares:
    ``J - I`` is singular along a family of periodic hops of a conservative hopper) and halves the step
    until the residual falls (at most 6 times). Stops when ``max |P(x) - x| < tolerance``. The
    eigenvalues are those of the last Jacobian (at the returned state, or one step before it).
    """
    x = np.asarray(guess, float)
    res = hop_step(chain, config, cal, x)[0] - x
    jac = hop_map_jacobian(chain, config, cal, x)
    for _ in range(max_iterations):
        if np.abs(res).max() < tolerance:
            break
        dx = np.linalg.lstsq(jac - np.eye(7), -res, rcond=None)[0]
        lam = 1.0
        for _ in range(6):
            try:
                trial_res = hop_step(chain, config, cal, x + lam * dx)[0] - (x + lam * dx)
            except ValueError:
                lam /= 2
                continue
            if np.abs(trial_res).max() < np.abs(res).max():
                break
            lam /= 2
        else:
            break  # no step along dx lowers the residual
        x, res = x + lam * dx, trial_res
        jac = hop_map_jacobian(chain, config, cal, x)
    nxt, st = hop_step(chain, config, cal, x)
    speed_next = float(nxt[0])
    flight_s = (speed_next + float(com_velocity(chain, st.g[-1], st.gd[-1])[1])) / chain.gravity_m_s2
    eig = np.linalg.eigvals(jac)
    eig = eig[np.argsort(-np.abs(eig))]
    res = nxt - x
    return PeriodicHop(x, res, bool(np.abs(res).max() < tolerance), st.duration_s, flight_s, eig, jac)
