"""Where a simulated hop's energy goes: work of each law part, of the ground, and what flight keeps.

For one stance (a :class:`~hop_impedance.simulation.hopping_trial.StanceRecord`), with E = kinetic +
gravitational energy of the four segments (J, z = 0 datum) and joint power ``P = -M omega`` (extensor
moments, flexion-positive angles):

- ``push_off_j``       work of the active push-off part, ``int -M_push . omega dt``;
- ``eq3_work_j``       work of the Eq. 3 part (springs, damping, activation), ``int -M_eq3 . omega dt``;
- ``springs_left_j``   elastic energy left in the Eq. 3 springs at take-off about the touchdown
  reference (:meth:`Eq3Law.elastic_energy_j`; None for a non-conservative law): energy that the
  prescribed flight does not return;
- ``damping_j``        ``-(eq3_work_j + springs_left_j)``: what the law dissipated (>= 0; None with
  ``springs_left_j``);
- ``trunk_balance_j``  work of the trunk-balance moment at the hip (0 without one);
- ``biarticular_j``, ``biarticular_left_j`` (only with a
  :class:`~hop_impedance.simulation.impedance_laws.BiarticularSpring` part): its work and the energy left in it at
  take-off (conservative: the two add up to 0 but for the quadrature);
- ``ground_j``         work of the surface on the foot, ``int (Fz dz_toe/dt + Fx dx_toe/dt) dt``
  (surface damping and sliding friction; the surface spring is unloaded at take-off);
- ``e_touchdown_j``, ``e_takeoff_j`` and ``residual_j`` = E(take-off) - E(touchdown) - (sum of the
  works): the numerical error of the bookkeeping.

:func:`trial_energy_budget` adds ``flight_j`` = E(next touchdown) - E(take-off) + (springs returned in
flight, :func:`~hop_impedance.simulation.hopping_trial.returned_spring_energy_j`, energy-keeping flight
only): what flight discards (negative) or keeps (0). With the ``"trunk_held"`` flight it also adds
``flight_balance_loss_j``, the energy the trunk balance took out in that flight
(``HoppingTrial.flight_balance_loss_j``), and then ``flight_j`` = -``flight_balance_loss_j``.

Integrals are trapezoids on a ``dt_s`` grid of the stance's dense output (default 0.2 ms: residual
below 0.1 J on the default trials).
"""

from __future__ import annotations

import numpy as np

from hop_impedance.biomech.joint_angles import joint_angles
from hop_impedance.simulation.dynamics import mechanical_energy_j
from hop_impedance.simulation.impedance_laws import BiarticularSpring, Eq3Law, PushOff, law_part

DEFAULT_DT_S = 2e-4


def part_moments_nm(part, st) -> np.ndarray:
    """Moments (N m) of one law part along a stance; zeros if the part is absent."""
    if part is None:
        return np.zeros_like(st.moments_nm)
    states = st.law_states[:, : part.n_states] if isinstance(part, Eq3Law) else st.law_states[:, :0]
    return part.moments_nm(st.t_s, st.rho_rad, st.omega_rad_s, states, st.ref)


def _energy(chain, g, gd) -> float:
    return float(sum(mechanical_energy_j(chain, g, gd)))


def stance_energy_budget(chain, rec, dt_s: float = DEFAULT_DT_S) -> dict:
    """Energy terms (J) of one stance record (module docstring)."""
    from hop_impedance.simulation.hopping_trial import simulate_resample

    duration = rec.stance.duration_s
    t = np.append(np.arange(0.0, duration, dt_s), duration)
    st = simulate_resample(chain, rec, t)
    omega = st.omega_rad_s
    eq3, push = law_part(rec.law, Eq3Law), law_part(rec.law, PushOff)

    def work(moments: np.ndarray) -> float:
        return float(np.trapezoid(-(moments * omega).sum(axis=1), t))

    push_j = work(part_moments_nm(push, st))
    eq3_j = work(part_moments_nm(eq3, st))
    trunk_j = work(st.trunk_moments_nm) if st.trunk_moments_nm is not None else 0.0
    ground_j = float(np.trapezoid(st.grf_n[:, 1] * st.gd[:, 1] + st.grf_n[:, 0] * st.gd[:, 0], t))
    springs = None
    if eq3 is not None:
        try:
            springs = float(eq3.elastic_energy_j(st.rho_rad[-1], st.ref))
        except NotImplementedError:
            springs = None
    e_td, e_to = _energy(chain, st.g[0], st.gd[0]), _energy(chain, st.g[-1], st.gd[-1])
    biarticular = law_part(rec.law, BiarticularSpring)
    extra = {}
    if biarticular is not None:  # only then (older budgets stay the same)
        extra = {"biarticular_j": work(part_moments_nm(biarticular, st)),
                 "biarticular_left_j": float(biarticular.elastic_energy_j(st.rho_rad[-1], st.ref))}
    residual = e_to - e_td - (push_j + eq3_j + trunk_j + ground_j)
    return {
        "push_off_j": push_j,
        "eq3_work_j": eq3_j,
        "springs_left_j": springs,
        "damping_j": None if springs is None else -(eq3_j + springs),
        "trunk_balance_j": trunk_j,
        "ground_j": ground_j,
        "e_touchdown_j": e_td,
        "e_takeoff_j": e_to,
        "residual_j": residual - extra.get("biarticular_j", 0.0),
        **extra,
    }


def trial_energy_budget(trial, dt_s: float = DEFAULT_DT_S) -> list[dict]:
    """Per-stance budgets of a trial; ``flight_j`` for every stance followed by another (module docstring)."""
    from hop_impedance.simulation.hopping_trial import ENERGY_KEEPING_FLIGHTS, returned_spring_energy_j

    rows = [stance_energy_budget(trial.chain, rec, dt_s) for rec in trial.stances]
    for row, rec, nxt in zip(rows, trial.stances, trial.stances[1:]):
        returned = 0.0
        if trial.config.flight in ENERGY_KEEPING_FLIGHTS:
            rho_next = joint_angles(nxt.touchdown.g[2:][None], trial.chain.alpha_rad)[0]
            returned = returned_spring_energy_j(rec.law, rec.stance.ref, rec.stance.rho_rad[-1], rho_next)
        row["flight_j"] = _energy(trial.chain, nxt.touchdown.g, nxt.touchdown.gd) - row["e_takeoff_j"] - returned
    if trial.config.flight == "trunk_held":  # the balance's loss in flight, beside the push-off's work (session 24)
        for row, loss in zip(rows, trial.flight_balance_loss_j):
            row["flight_balance_loss_j"] = float(loss)
    return rows
