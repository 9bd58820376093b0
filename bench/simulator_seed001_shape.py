"""Seed 001 with the push-off lasting to take-off: what the soft and hard stances are made of (issue 17, session 13).

Session 12's variant reverses seed 001 at 1.53 Hz (leg stiffness +1 % on the unexpected hard surface) and finds no
2.2 Hz hop on the soft law. For each frequency and push-off timing (``--timings``, ONSET,DURATION as fractions of the
passive stance, on top of the variant flags of bench/simulator_issue17.py) this prints
``simulation.surface_surprise.unexpected_hard_vs_soft``'s stance pair: stance time, the GRF's peak and where it sits
in the stance, the leg's compression and stiffness, midstance (the COM's lowest point, where the joint stiffness is
read) and the joints' maximal flexion times, the factor on the springs prepared for the soft surface, the soft hop's
calibrated push-off scale, and seed 001's three directions. ``--no-anticipate --no-preprogrammed``: sessions 12-19's
experiment (surface_surprise's module docstring), apart from the joint stiffness read to midstance.

Usage::

    nice -n 19 .venv/bin/python bench/simulator_seed001_shape.py --bell 0.9 \\
        --law-scale bell09_rigid_pad15_3_push06_08_trunk500_60 --surface rigid --pad 15,3 --trunk 500,60 \\
        --timings 0.6,0.8 0.5,0.5 --freqs 1.53,2.2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (a bench next to this one: the variant flags)

from hop_impedance.simulation.scenarios import hopping_config  # noqa: E402
from hop_impedance.simulation.surface_surprise import (  # noqa: E402
    midstance_index,
    seed001_options,
    unexpected_hard_vs_soft,
)


def stance_line(name: str, st, leg: tuple[float, float, float], mid: int) -> str:
    """One surface's stance: time, GRF peak and place, compression, stiffness, midstance, maximal flexion times."""
    fz, t = st.grf_n[:, 1], st.t_s
    i = int(np.argmax(fz))
    flex = t[np.argmax(st.rho_rad, axis=0)] / t[-1]
    return (f"    {name}: stance {1000 * t[-1]:.0f} ms, peak GRF {fz[i]:.0f} N at {t[i] / t[-1]:.0%} of it, compression "
            f"{1000 * leg[2]:.1f} mm, leg {leg[0]:.0f} N/m; midstance (COM lowest) at {t[mid] / t[-1]:.0%}; maximal "
            "flexion ankle / knee / hip at " + " / ".join(f"{v:.0%}" for v in flex))


def to_maximal_flexion(st) -> np.ndarray:
    """Net moment change over angle change from touchdown to each joint's maximal flexion (N m/rad): sessions 12-19's
    joint stiffness, not seed 001's (surface_surprise.joint_stiffness_nm_rad reads it to midstance)."""
    peak = np.argmax(st.rho_rad, axis=0)
    joints = np.arange(3)
    return (st.moments_nm[peak, joints] - st.moments_nm[0]) / (st.rho_rad[peak, joints] - st.rho_rad[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--timings", nargs="+", default=["0.6,0.8", "0.5,0.5"], metavar="ONSET,DURATION")
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    parser.add_argument("--no-anticipate", action="store_true",
                        help="the law not scaled for the soft surface (surface_surprise.anticipated_stiffening)")
    parser.add_argument("--no-preprogrammed", action="store_true",
                        help="the hard stance's k1 by angle (Eq. 3), not along the soft stance's time course")
    parser.add_argument("--stiffening", type=float, default=None, metavar="F",
                        help="this factor on the springs for the soft surface instead of the rule's (a robustness check)")
    parser.add_argument("--expected", choices=("soft", "hard"), default="soft",
                        help="the surface the hopper prepares for (hard: seed 001's unexpected soft surface)")
    args = parser.parse_args()
    prepared = {"anticipate": not args.no_anticipate, "preprogrammed": not args.no_preprogrammed,
                "stiffening": args.stiffening, "expected": args.expected}
    for f in s17.floats(args.freqs):
        for timing in args.timings:
            options, _ = s17.variant_options(s17.VariantArgs(**{**vars(args), "push_timing": timing}))
            try:
                s = unexpected_hard_vs_soft(f, **prepared, **options)
            except ValueError as exc:
                print(f"{f:4.2f} Hz, push-off {timing}: {exc}", flush=True)
                continue
            chain, _ = hopping_config(f, args.expected, 1, variability=False, **seed001_options(options))  # the body
            held = [k for k, v in s.directions().items() if v]
            print(f"{f:4.2f} Hz, push-off {timing} (springs x {s.stiffening:.3f} for {args.expected}; "
                  f"{args.expected} hop's push-off scale {s.push_scale:.2f}): leg stiffness "
                  f"{100 * s.leg_change:+.1f} % on hard; extra flexion ankle / knee / hip "
                  + " / ".join(f"{v:+.3f}" for v in s.extra_flexion_rad) + " rad; joint stiffness "
                  + " / ".join(f"{100 * v:+.1f}" for v in s.joint_change) + f" %; directions held: {held or 'none'}")
            to_max = to_maximal_flexion(s.hard) / to_maximal_flexion(s.soft) - 1.0
            print("    joint stiffness read to each joint's maximal flexion instead of midstance (sessions 12-19's "
                  "reading): " + " / ".join(f"{100 * v:+.1f}" for v in to_max) + " %")
            print(stance_line("soft", s.soft, s.leg_soft, midstance_index(chain, s.soft)))
            print(stance_line("hard", s.hard, s.leg_hard, midstance_index(chain, s.hard)), flush=True)


if __name__ == "__main__":
    main()
