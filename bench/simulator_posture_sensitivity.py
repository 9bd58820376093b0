"""How one hop's touchdown posture steers the next hop (issue 17, session 25): the 1.53 Hz fragility's measure.

The variant of bench/simulator_issue17.py's flags is run without hop-to-hop variability (so its calibrated hop, with
nothing drawn), once as it is and once per case with hop 1's touchdown joint angle moved by D rad at one joint
(``simulate_hopping(posture_offsets=...)``). Printed per run: hop 1's knee angle at take-off, its COM height at
take-off minus touchdown, and the next (hop 2's) touchdown speed, the quantity the push-off controller then corrects.
Session 25 (helper) found the 1.53 Hz trunk-held law's next touchdown speed moved by -0.17 / +0.13 m/s by 0.01 rad
of knee flexion (its probe, which this bench replaces).

Usage::

    .venv/bin/python bench/simulator_posture_sensitivity.py --hopper seed-like --surface rigid [--freq 1.53]
    .venv/bin/python bench/simulator_posture_sensitivity.py --hopper seed-like --surface rigid --flight trunk_held \\
        --landing prescribed --push-weights 1,-0.1,0.3 --push-off-gain 0.5 --passive-landing 0.08 --law-scale-file LAW

About 10-20 s a run on this machine.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (a bench next to this one)

from hop_impedance.simulation.dynamics import body_com, com_velocity  # noqa: E402
from hop_impedance.simulation.hopping_trial import simulate_hopping  # noqa: E402
from hop_impedance.simulation.scenarios import hopping_config  # noqa: E402

JOINTS = ("ankle", "knee", "hip")


def hop_figures(chain, trial) -> str:
    """Hop 1's knee angle at take-off (rad), its COM rise from touchdown to take-off (mm) and hop 2's touchdown speed."""
    if len(trial.stances) < 3:
        return f"stopped after {len(trial.stances)} stances ({trial.stop_reason})"
    st, nxt = trial.stances[1].stance, trial.stances[2].stance
    rise = body_com(chain, st.g[-1])[1] - body_com(chain, st.g[0])[1]
    speed = -com_velocity(chain, nxt.g[0], nxt.gd[0])[1]
    return f"knee at take-off {st.rho_rad[-1, 1]:.3f} rad, COM rise {rise * 1000:+.1f} mm, next touchdown {speed:.3f} m/s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--freq", type=float, default=1.53)
    parser.add_argument("--cases", default="knee:0.01,knee:-0.01",
                        help="JOINT:D[,...]: hop 1's touchdown angle at JOINT (ankle, knee, hip) moved by D rad")
    args = parser.parse_args()
    options, setup = s17.variant_options(args)
    chain, config = hopping_config(args.freq, args.surface, 4, **{**options, "variability": False})
    print(f"{setup}; {args.freq:g} Hz, no variability")
    t0 = time.perf_counter()
    print(f"as calibrated: {hop_figures(chain, simulate_hopping(chain, config))}")
    for case in args.cases.split(","):
        joint, delta = case.split(":")
        offset = np.zeros(3)
        offset[JOINTS.index(joint)] = float(delta)
        trial = simulate_hopping(chain, config, posture_offsets={1: offset})
        print(f"{joint} {float(delta):+g} rad: {hop_figures(chain, trial)}")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
