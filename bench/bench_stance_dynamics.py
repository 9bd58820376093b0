"""Cost of the forward stance simulation, the inner loop of ``discover`` and of every simulated trial.

Prints, on the seed subject's de Leva chain:
1. one evaluation of the equations of motion, ``dynamics.equations_of_motion`` (closed form compiled by numba,
   ``EomConstants``) against the same M, h, Q assembled from the COM Jacobians
   (``sum m J^T J``, the formulation it replaced; test_sim_dynamics checks they agree to 1e-12);
2. ``dynamics.accelerations`` (one solve of the stance's 5 free coordinates);
3. ``stance.simulate_stance`` of one stance (Table 2 law at 2.2 Hz with b0, hard surface, LSODA,
   300 samples), with the number of right-hand-side evaluations;
4. the same stance as ``discover`` simulates a held-out one: the reduced law k0 + k1 (rho - rho0) as the identified
   law (``discovery.model.FittedLaw``) at ``forward_selection``'s tolerances, with its number of law states (none since
   session 35; 21 before, which LSODA's finite-difference Jacobian paid for at every evaluation).
Each figure is the median of ``--repeat`` timing runs; the load average is printed beside them.

Usage: .venv/bin/python bench/bench_stance_dynamics.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation import dynamics, stance
from hop_impedance.simulation.ground import HARD
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT

CHAIN = dynamics.chain_from_body_model(body_model_from_stature(SEED_SUBJECT))


def jacobian_sums(chain: dynamics.Chain, g: np.ndarray, gd: np.ndarray):
    """M, h, Q as sums over the segments' COM Jacobians (the formulation before the closed form)."""
    jac = dynamics.com_jacobians(chain, g[2:])
    weighted = chain.mass_kg[:, None, None] * jac
    mass = np.einsum("iak,ial->kl", weighted, jac)
    mass[2:, 2:] += np.diag(chain.inertia_kgm2)
    bias = np.einsum("iak,ia->k", weighted, dynamics._velocity_products(chain, g[2:], gd[2:]))
    return mass, bias, -chain.gravity_m_s2 * weighted[:, 1, :].sum(axis=0)


def per_call_us(fun, calls: int, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(calls):
            fun()
        times.append((time.perf_counter() - t0) / calls)
    return 1e6 * float(np.median(times))


def counted_run(run):
    """``run()``'s result and how many right-hand sides (calls of ``stance.accelerations``) it evaluated."""
    calls = [0]
    original = stance.accelerations

    def counted(*a, **k):
        calls[0] += 1
        return original(*a, **k)

    stance.accelerations = counted
    try:
        return run(), calls[0]
    finally:
        stance.accelerations = original


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    rng = np.random.default_rng(0)
    g, gd = np.r_[0.0, 0.0, touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))], rng.normal(0, 2, 6)
    gd[0] = 0.0
    closed = per_call_us(lambda: dynamics.equations_of_motion(CHAIN, g, gd), 20000, args.repeat)
    summed = per_call_us(lambda: jacobian_sums(CHAIN, g, gd), 20000, args.repeat)
    acc = per_call_us(lambda: dynamics.accelerations(CHAIN, g, gd, np.ones(3), np.zeros(2), stance.STANCE_FREE),
                      20000, args.repeat)
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8], b0=0.5)
    td = touchdown_state(CHAIN, touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO)), np.array([0.05, -1.0]), 0.0)
    st, calls = counted_run(lambda: stance.simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6,
                                                           sample_times_s=np.linspace(0, 0.3, 300)))
    per_stance = per_call_us(lambda: stance.simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6,
                                                            sample_times_s=np.linspace(0, 0.3, 300)), 10, args.repeat)
    print(f"equations of motion: closed form {closed:.1f} us, Jacobian sums {summed:.1f} us ({summed / closed:.1f}x); "
          f"accelerations (5 free coordinates) {acc:.1f} us")
    print(f"one stance ({st.duration_s * 1e3:.0f} ms, {st.end_reason}): {per_stance / 1e3:.1f} ms, "
          f"{calls} right-hand-side evaluations ({per_stance / calls:.0f} us each incl. the solver)")
    held_out_stance(td, args.repeat)
    print(f"load average (1 min) before {load0:.2f}, after {os.getloadavg()[0]:.2f}; median of {args.repeat} runs")


def held_out_stance(td: stance.TouchdownState, repeat: int) -> None:
    """Item 4 of the module docstring: one stance with the identified law, as forward_selection runs it."""
    from hop_impedance.discovery import forward_selection as fs
    from hop_impedance.discovery.model import FittedLaw, ModelSpec

    law = FittedLaw(ModelSpec(effects=("angle_dependent_stiffness",)),
                    np.array([[301.4, 948.2], [230.9, 884.8], [175.4, 894.8]]))

    def run():
        return stance.simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6, rtol=fs.RTOL, atol=fs.atol_of(law),
                                      sample_times_s=np.linspace(0, 0.3, 300))

    st, calls = counted_run(run)
    ms = per_call_us(run, 10, repeat) / 1e3
    print(f"held-out stance as discover runs it (FittedLaw k0 + k1, {law.n_states} law states, rtol {fs.RTOL:g}, "
          f"atol {fs.ATOL:g} / toe {fs.TOE_ATOL:g}; {st.duration_s * 1e3:.0f} ms, {st.end_reason}): {ms:.1f} ms, "
          f"{calls} right-hand-side evaluations")


if __name__ == "__main__":
    main()
