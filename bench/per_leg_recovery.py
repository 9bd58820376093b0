"""Per-leg k0/k1 recovery on simulated asymmetric bilateral recordings (issue 21), next to the lumped analysis.

Each recording: the left leg = a seed Table 2 trial at ``--left`` Hz, the right
leg = one at ``--right`` Hz (same subject, same seed), each plate half its
trial's ground wrench (construction and limits:
:mod:`hop_impedance.validation.bilateral_recovery`). Per leg and joint it
prints the number of compared stances and the median k0/k1 error over the
stances pooled across seeds, for the per-leg analysis (against half the law)
and for the lumped analysis of that leg's whole trial (against the law): the
lumped targets of ``bench/recovery_errors.py`` (2 % noise-free) apply to both.

    .venv/bin/python bench/per_leg_recovery.py
    .venv/bin/python bench/per_leg_recovery.py --seeds 11 12 13 14 --left 2.20 --right 1.53
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hop_impedance.validation.bilateral_recovery import recover_legs
from hop_impedance.validation.coefficient_recovery import JOINTS, RecoveryResult


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--left", type=float, default=2.20, help="the left leg's trial frequency (Hz, seed Table 2 law)")
    parser.add_argument("--right", type=float, default=1.87, help="the right leg's trial frequency (Hz)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13, 14])
    parser.add_argument("--hops", type=int, default=4)
    args = parser.parse_args()
    start = time.process_time()
    pooled = {(kind, side): RecoveryResult() for kind in ("per-leg", "lumped") for side in ("left", "right")}
    for seed in args.seeds:
        legs, _, _, lumped = recover_legs({"left": args.left, "right": args.right}, seed, n_hops=args.hops, lumped=True)
        for side in ("left", "right"):
            pooled["per-leg", side].extend(legs[side])
            pooled["lumped", side].extend(lumped[side])
    for (kind, side), result in pooled.items():
        freq = args.left if side == "left" else args.right
        for joint in JOINTS:
            e = 100 * result.error_array(joint)
            med = np.median(e, axis=0) if len(e) else np.full(2, np.nan)
            print(f"{kind:7s} {side:5s} ({freq:.2f} Hz law) {joint:5s} n={len(e):2d} infeasible={result.infeasible[joint]} "
                  f"| median k0 {med[0]:+6.2f} % k1 {med[1]:+6.2f} %")
    print(f"CPU {time.process_time() - start:.0f} s")


if __name__ == "__main__":
    main()
