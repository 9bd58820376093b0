"""How the simulated hop depends on the touchdown posture (issue 4 realism search).

For each touchdown posture (ankle rho1 in rad; knee and hip flexion in rad
beyond the straight joint, i.e. rho2 - pi, rho3 - pi), simulate a short
noise-free hard-surface trial at one frequency with the default law and print
the last hop's stance time, peak GRF (body weights), range of flexion and
maximal moment per joint, or why the trial stopped (e.g. a take-off too weak
to fly). The default posture is scenarios.DEFAULT_TOUCHDOWN_RHO
(1.45, 0.50, 0.20).

Usage: .venv/bin/python bench/simulator_posture_sweep.py [--freq 1.53] [--hops 3] [--trunk]
       [--postures 1.45,0.5,0.2 1.45,0.42,0.1 ...]
Without --postures a small grid around the default is run (~5 s per posture).
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np

from hop_impedance.simulation.hopping_trial import simulate_hopping
from hop_impedance.simulation.scenarios import TRUNK_BALANCE, hopping_config

GRID = [(a, k, h) for a, k, h in itertools.product((1.45, 1.6), (0.35, 0.42, 0.5, 0.6), (0.0, 0.1, 0.2))]


def last_hop(posture: tuple[float, float, float], freq_hz: float, hops: int, trunk: bool = False) -> str:
    """One table row for ``posture`` = (ankle rho1, knee flexion, hip flexion) in rad."""
    rho = (posture[0], np.pi + posture[1], np.pi + posture[2])
    try:
        chain, config = hopping_config(freq_hz, "hard", hops, touchdown_rho_rad=rho,
                                       trunk_balance=TRUNK_BALANCE if trunk else None)
        trial = simulate_hopping(chain, config, seed=1)
    except ValueError as exc:
        return f"| {posture} | {exc} |"
    st = trial.stances[-1].stance
    weight = chain.total_mass_kg * chain.gravity_m_s2
    rom = st.rho_rad.max(axis=0) - st.rho_rad[0]
    mmax = st.moments_nm.max(axis=0)
    stop = f" (stopped: {trial.stop_reason})" if trial.stop_reason else ""
    return (f"| {posture} | {1000 * st.duration_s:.0f} ms, {st.grf_n[:, 1].max() / weight:.2f} BW, "
            f"range {np.round(rom, 2).tolist()} rad, max moment {np.round(mmax).tolist()} N m{stop} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--freq", type=float, default=1.53)
    parser.add_argument("--hops", type=int, default=3)
    parser.add_argument("--postures", nargs="*", default=None, help="ankle,knee,hip (rad) each")
    parser.add_argument("--trunk", action="store_true", help="with the trunk-balance moment (scenarios.TRUNK_BALANCE)")
    args = parser.parse_args()
    postures = [tuple(float(v) for v in p.split(",")) for p in args.postures] if args.postures else GRID
    print(f"| touchdown posture (ankle rho1, knee flexion, hip flexion) rad | last hop at {args.freq} Hz |")
    print("|---|---|")
    for posture in postures:
        print(last_hop(posture, args.freq, args.hops, args.trunk), flush=True)


if __name__ == "__main__":
    main()
