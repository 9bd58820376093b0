"""Seed 001 with the push-off lasting to take-off: what the soft and hard stances are made of (issue 17, session 13).

Session 12's variant reverses seed 001 at 1.53 Hz (leg stiffness +1 % on the unexpected hard surface) and finds no
2.2 Hz hop on the soft law. For each frequency and push-off timing (``--timings``, ONSET,DURATION as fractions of the
passive stance, on top of the variant flags of bench/simulator_issue17.py) this prints
``simulation.surface_surprise.unexpected_hard_vs_soft``'s stance pair: stance time, the GRF's peak and where it sits
in the stance, the leg's compression and stiffness, the joints' maximal flexion times, the soft hop's calibrated
push-off scale, and seed 001's three directions.

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

from hop_impedance.simulation.surface_surprise import unexpected_hard_vs_soft  # noqa: E402


def stance_line(name: str, st, leg: tuple[float, float, float]) -> str:
    """One surface's stance: time, GRF peak and place, compression, stiffness, maximal flexion times."""
    fz, t = st.grf_n[:, 1], st.t_s
    i = int(np.argmax(fz))
    flex = t[np.argmax(st.rho_rad, axis=0)] / t[-1]
    return (f"    {name}: stance {1000 * t[-1]:.0f} ms, peak GRF {fz[i]:.0f} N at {t[i] / t[-1]:.0%} of it, compression "
            f"{1000 * leg[2]:.1f} mm, leg {leg[0]:.0f} N/m; maximal flexion ankle / knee / hip at "
            + " / ".join(f"{v:.0%}" for v in flex))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--timings", nargs="+", default=["0.6,0.8", "0.5,0.5"], metavar="ONSET,DURATION")
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    args = parser.parse_args()
    for f in s17.floats(args.freqs):
        for timing in args.timings:
            options, _ = s17.variant_options(s17.VariantArgs(**{**vars(args), "push_timing": timing}))
            try:
                s = unexpected_hard_vs_soft(f, **options)
            except ValueError as exc:
                print(f"{f:4.2f} Hz, push-off {timing}: {exc}", flush=True)
                continue
            held = [k for k, v in s.directions().items() if v]
            print(f"{f:4.2f} Hz, push-off {timing} (soft hop's push-off scale {s.push_scale:.2f}): leg stiffness "
                  f"{100 * s.leg_change:+.1f} % on hard; extra flexion ankle / knee / hip "
                  + " / ".join(f"{v:+.3f}" for v in s.extra_flexion_rad) + " rad; joint stiffness "
                  + " / ".join(f"{100 * v:+.1f}" for v in s.joint_change) + f" %; directions held: {held or 'none'}")
            print(stance_line("soft", s.soft, s.leg_soft))
            print(stance_line("hard", s.hard, s.leg_hard), flush=True)


if __name__ == "__main__":
    main()
