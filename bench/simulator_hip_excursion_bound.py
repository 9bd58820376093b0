"""Issue 17: how far the hip can fall relative to the centre of mass, against the seed's Table 1 hip excursion.

Usage::

    nice -n 19 .venv/bin/python bench/simulator_hip_excursion_bound.py

Prints (1) ``dynamics.hip_over_com_drop_bound`` for the seed's mean subject (de Leva's female segments): the
largest hip-drop / COM-drop ratio of a sink with the trunk upright and translating with the hip and knee, shank
and foot not falling at all; (2) the seed's ratio, its Table 1 hip excursion over the COM drop Newton gives for its
own peak GRF and stance (``simulator_realism.newton_com_drop``: a sin^n force with the seed's peak; a less peaked
force of the same impulse drops the COM less, so this is the seed's smallest ratio); (3) in one simulated stance
per frequency (the third, noise-free, ``seed_like_options()`` with a_min 0.9 and its calibrated law on the hard
surface) the drop from touchdown to the lowest point of the hip, the body's COM and each segment's COM.
The bound is on drops from the touchdown height; a stance *range* of the hip can be larger when the hip stands
higher at take-off than at touchdown, so the table also prints how much higher the seed's hip would have to be
at take-off (seed excursion minus bound x its COM drop) and our hip's take-off minus touchdown height.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from simulator_issue17 import LAW_SCALES  # noqa: E402  (benches next to this one)
from simulator_realism import SEED_TABLE1, newton_com_drop  # noqa: E402

from hop_impedance.simulation.dynamics import (  # noqa: E402
    body_com,
    hip_over_com_drop_bound,
    joint_positions,
    segment_com_positions,
)
from hop_impedance.simulation.hopping_trial import simulate_hopping  # noqa: E402
from hop_impedance.simulation.scenarios import hopping_config, seed_like_options  # noqa: E402


def main() -> None:
    options = {**seed_like_options(), "bell_activation_min": 0.9, "law_scale": LAW_SCALES["bell09"]}
    chain, _ = hopping_config(2.2, "hard", 1, variability=False, **options)
    bound = hip_over_com_drop_bound(chain)
    print(f"bound, trunk upright, knee still: hip drop / COM drop <= {bound:.3f} (masses foot/shank/thigh/HAT "
          f"{', '.join(f'{m:.1f}' for m in chain.mass_kg)} kg; thigh COM {chain.com_along_m[2] / chain.length_m[2]:.3f} "
          f"of its length from the knee)")
    print("| f (Hz) | seed hip excursion (m) | Newton COM drop for the seed's peak GRF and stance (m) | seed ratio | "
          "vs bound | seed hip at take-off above touchdown needed (m) | sim drops (m): hip / body COM / HAT / thigh / "
          "shank / foot COM, toe | sim ratio | sim hip take-off minus touchdown height (m) | trunk pitch change at the "
          "COM's lowest (rad) |\n|---|---|---|---|---|---|---|---|---|---|")
    for f, seed in SEED_TABLE1.items():
        _, drop = newton_com_drop(f, seed["stance_ms"] / 1000.0, seed["grf_bw"])
        ratio = seed["hip_exc_m"] / drop
        chain, cfg = hopping_config(f, "hard", 5, variability=False, **options)
        st = simulate_hopping(chain, cfg, seed=1).stances[2].stance
        hip = joint_positions(chain, st.g)[:, 3, 1]
        com = body_com(chain, st.g)[:, 1]
        segments = segment_com_positions(chain, st.g)[:, :, 1]
        drops = [z[0] - z.min() for z in (hip, com, segments[:, 3], segments[:, 2], segments[:, 1], segments[:, 0],
                                          st.g[:, 1])]
        low = int(np.argmin(com))
        needed = max(seed["hip_exc_m"] - bound * drop, 0.0)
        print(f"| {f:g} | {seed['hip_exc_m']:.2f} | {drop:.3f} | {ratio:.2f} | {'above' if ratio > bound else 'below'} | "
              f"{needed:.4f} | {' / '.join(f'{d:.3f}' for d in drops[:6])}, {drops[6]:.3f} | {drops[0] / drops[1]:.2f} | "
              f"{hip[-1] - hip[0]:+.4f} | {st.g[low, 5] - st.g[0, 5]:+.3f} |", flush=True)


if __name__ == "__main__":
    main()
