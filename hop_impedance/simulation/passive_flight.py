"""The flight's first and last phases as a free chain: segments that leave and land unforced (issue 17).

Why
---
The simulator's flight prescribes the segment angles as a quintic from take-off to the next touchdown
(:mod:`~hop_impedance.simulation.hopping_trial`). When the segments land moving (the energy-keeping flights), the
quintic must turn the take-off's rates into the landing rates and does much of that in the flight's last tens of
ms; inverse dynamics of those kinematics (what ``analyze`` does, bottom-up with no ground force) reads a joint
moment there (session 24: -25..-130 N m at the 1.53 Hz hip 10-60 ms before touchdown), and the analysis' 12 Hz
low-pass carries it into the first samples of the stance, where it lowers the fitted initial stiffness (seed Fig. 7).
The same holds after take-off for the stance's last samples. A real leg needs no such moment at the instants it
meets and leaves the ground.

What
----
With ``HoppingConfig.passive_landing_s = T > 0`` the flight's last ``T`` seconds (``passive_takeoff_s``: its first;
each at most :data:`MAX_FLIGHT_FRACTION` of the flight) are the free four-segment chain under gravity with **zero joint
moments**: integrated forward from the take-off state and *backward* from the touchdown state. Both states are
unchanged, so the stances, the energy at touchdown and every figure of the simulator's own are the same to the bit;
the quintic runs between the two phases (angles, rates and accelerations matched, so the angles stay C2). In the
phases the whole body's angular momentum about its COM is conserved and its COM is exactly ballistic (what
:class:`~hop_impedance.simulation.hopping_trial.Flight` puts it on), so inverse dynamics reads zero joint moments
there; the segments are repositioned in the flight's middle, away from the contacts. A phase is shorter where the
free chain's toe would pass through the ground (:func:`passive_knots`).

Measured (docs/simulator.md, "Session 25"): the landing phase takes the flight's moment out of the analysis' 1.53 Hz
hip at touchdown (-0.7..-29.8 -> +0.4..+7.9 N m with the trunk held); a take-off phase as well leaves the short
1.53 Hz flight's quintic 40 ms, whose moment the 12 Hz filter then carries into the stance's start: landing only.

Choice (documented, not from the seed): zero moments, the muscles neither braking nor driving the segments right
after take-off and before contact. The seed does not report pre-landing activity; a net moment near zero at contact is
what a spring that starts from its touchdown angle (seed Eq. 3, Fig. 4's K(t) from touchdown) implies. At take-off
the joint moments step from the stance law's to zero.

:func:`passive_knots` returns a phase as knots (time from the contact, angles, rates, accelerations) every
:data:`KNOT_STEP_S`; the flight's :class:`scipy.interpolate.BPoly` interpolates them with quintic Hermite pieces.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from hop_impedance.simulation.dynamics import N_COORDS, Chain, accelerations

#: Spacing of the passive phase's knots (s).
KNOT_STEP_S = 0.005
#: Each passive phase (after take-off, before touchdown) may take at most this fraction of the flight; the quintic keeps
#: the rest (a shorter flight keeps proportionally shorter passive phases).
MAX_FLIGHT_FRACTION = 0.4

_ALL_FREE = np.ones(N_COORDS, bool)
_NO_MOMENTS = np.zeros(3)
_NO_FORCE = np.zeros(2)


def free_chain_rhs(chain: Chain, y: np.ndarray) -> np.ndarray:
    """d/dt [g, g'] of the free chain (no ground force, zero joint moments), shape (12,)."""
    gdd, _ = accelerations(chain, y[:N_COORDS], y[N_COORDS:], _NO_MOMENTS, _NO_FORCE, _ALL_FREE)
    return np.r_[y[N_COORDS:], gdd]


def passive_duration_s(asked_s: float, flight_s: float) -> float:
    """A passive phase's length in a flight of ``flight_s``: the asked one, at most :data:`MAX_FLIGHT_FRACTION` of the
    flight, rounded down to whole knots (0: none)."""
    length = min(float(asked_s), MAX_FLIGHT_FRACTION * float(flight_s))
    return float(np.floor(length / KNOT_STEP_S + 1e-9) * KNOT_STEP_S) if length > 0 else 0.0


def passive_knots(chain: Chain, g: np.ndarray, gd: np.ndarray, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The free chain integrated from the contact state ``(g, gd)`` (a touchdown or a take-off) for ``duration_s``:
    backward (< 0, the phase before a touchdown) or forward (> 0, the phase after a take-off).

    Returns
    -------
    tau : ndarray, shape (K,)
        Knot times from the contact, ascending, every :data:`KNOT_STEP_S`: ``duration_s .. 0`` backward,
        ``0 .. duration_s`` forward.
    knots : ndarray, shape (K, 3, 4)
        Segment angles, rates and accelerations (rad, rad/s, rad/s^2) at each knot; the contact's is the free chain's
        (its accelerations those of zero joint moments).

    The phase ends (going away from the contact) at the last knot before one where the toe (the contact point) would be
    below its height at the contact: a free chain whose toe would pass through the ground there cannot be the flight,
    so the quintic takes over from that knot (a shorter phase; only the contact's knot left: none).
    """
    n = int(round(abs(duration_s) / KNOT_STEP_S))
    tau = np.sign(duration_s) * KNOT_STEP_S * np.arange(n + 1)
    y0 = np.r_[np.asarray(g, float), np.asarray(gd, float)]
    sol = solve_ivp(lambda _t, y: free_chain_rhs(chain, y), (0.0, float(tau[-1])), y0, t_eval=tau,
                    rtol=1e-11, atol=1e-12, method="DOP853")
    if not sol.success:  # pragma: no cover - a smooth ODE over < 0.2 s
        raise ValueError(f"passive flight phase: integration failed ({sol.message})")
    states = sol.y.T
    knots = np.empty((n + 1, 3, 4))
    for k, y in enumerate(states):
        knots[k, 0], knots[k, 1] = y[2:N_COORDS], y[N_COORDS + 2:]
        knots[k, 2] = free_chain_rhs(chain, y)[N_COORDS + 2:]
    below = np.flatnonzero(states[:, 1] < g[1] - 1e-9)  # the contact point's height; the contact itself is at it
    keep = int(below[0]) if len(below) else n + 1
    tau, knots = tau[:keep], knots[:keep]
    order = np.argsort(tau)
    return tau[order], knots[order]
