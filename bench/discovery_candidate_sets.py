"""Held-out forward gaps of chosen effect sets on one of the hit-rate bench's simulator cases, and the true law's.

For a case and seed of ``bench/discovery_hit_rates.py`` (our simulator) each effect set is identified on all stances
but one and the held-out stance simulated from its measured touchdown state (as a discovery candidate in its first
round, leave-one-out, the toe fit's surface), per stance and pooled, with the one-sided t-test of the capped log gap
ratios against the baseline that the selection uses, and the simulated net joint work beside the measured. Then the
generating law (the joint law the case was simulated with, on the case's own surface and on the rigid ground)
simulated the same way: a true law no better than the baseline means the forward gap cannot show that effect in this
recording, whatever the selection does. The true law is the case's nominal one: a push-off's per-hop scatter
(``stance_set``'s ``push_sd``) is not reproduced, so with a push-off its gap is an upper bound of the truth's.

Why (session 19): our simulator's push-off on the soft surface at 1.53 Hz is named by nothing one effect at a time,
while the two together shrink the gap by 95 % (``forward_selection.ENERGY_PAIRS``); its hard surface at 1.53 Hz is
named by nothing because its true law is barely better than the rigid ground's.

Usage: .venv/bin/python bench/discovery_candidate_sets.py CASE SEED [SET ...] [--hops 8] [--touchdown-velocity-fit W]
  SET: effects joined by "+", e.g. surface_compliance active_push_off surface_compliance+active_push_off
Run with ``PYTHONPATH=<this checkout>`` from a worktree.
"""

from __future__ import annotations

import argparse

import numpy as np
from discovery_hit_rates import BASE, CASES, generate

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec, members
from hop_impedance.simulation.ground import SURFACES
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE, EffectSizes, _stance_set_law


def line(name: str, gaps: np.ndarray, base: np.ndarray | None, work: np.ndarray | None = None) -> str:
    text = f"{name:<48} mean {np.mean(gaps):.4f}"
    if base is not None:
        d, shrink, p = fs.compare_gaps(base, gaps)
        text += f"  shrink {100 * shrink:+.0f} %  p {p:.2g}"
    text += "  per stance " + " ".join(f"{g:.4f}" for g in gaps)
    if work is not None:
        text += "  net work J " + " ".join(f"{w:.0f}" for w in work)
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("seed", type=int)
    ap.add_argument("sets", nargs="*", help="effect sets, each joined by +")
    ap.add_argument("--hops", type=int, default=8)
    ap.add_argument("--touchdown-velocity-fit", type=float, default=None, metavar="W",
                    help="forward_selection.TOUCHDOWN_VELOCITY_FIT_S (default: the package's)")
    args = ap.parse_args()
    if args.touchdown_velocity_fit is not None:
        fs.TOUCHDOWN_VELOCITY_FIT_S = args.touchdown_velocity_fit
    rec, freq = generate(args.case, args.seed, args.hops)
    trial = measure_trial(rec)
    print(f"{args.case} seed {args.seed}: {freq} Hz, {len(trial.stances)} stances, touchdown-velocity fit "
          f"{fs.TOUCHDOWN_VELOCITY_FIT_S}")
    measured = fs.measured_net_works_j(trial)
    print(f"{'measured net joint work (J)':<48} " + " ".join(f"{w:.0f}" for w in measured))
    for effect in args.sets:
        for one in members(effect):
            assert one in fs.EFFECT_NAMES, f"unknown effect {one}"
    with fs.HeldOutEvaluator(rec, trial) as ev:  # discovery's own leave-one-out runs, on both cores
        runs = ev.run(ModelSpec(), [None, *args.sets])
    base = runs[0].gaps
    print(line("baseline (held out)", base, None, runs[0].net_work_j), flush=True)
    for effect, r in zip(args.sets, runs[1:]):
        print(line(effect + " (held out)", r.gaps, base, r.net_work_j), flush=True)
    law_switches, surfaces, _, _ = CASES[args.case]
    effects = Effects(**{**BASE, **law_switches})
    for names in (surfaces, ("rigid",)):
        grounds = [RIGID_NO_BOUNCE if n == "rigid" else SURFACES[n] for n in names]
        laws = [_stance_set_law(trial.chain, freq, effects, EffectSizes(), g, DEFAULT_TOUCHDOWN_RHO)[0] for g in grounds]
        k = [s.index % len(names) for s in trial.stances]  # the generator cycles its surfaces hop by hop
        gaps = fs.law_gaps(trial, [laws[i] for i in k], [grounds[i] for i in k])
        print(line(f"true joint law on the {'/'.join(names)} ground", gaps, base), flush=True)


if __name__ == "__main__":
    main()
