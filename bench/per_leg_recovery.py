"""Per-leg k0/k1 recovery on simulated asymmetric bilateral recordings (issue 21), next to the lumped analysis.

Each recording: the left leg = a seed Table 2 trial at ``--left`` Hz, the right
leg = one at ``--right`` Hz (same subject, same seed), each plate half its
trial's ground wrench (construction and limits:
:mod:`hop_impedance.validation.bilateral_recovery`). Per leg and joint it
prints the number of compared stances and the median k0/k1 error over the
stances pooled across seeds, for the per-leg analysis (against half the law)
and for the lumped analysis of that leg's whole trial (against the law): the
lumped targets of ``bench/recovery_errors.py`` (2 % noise-free) apply to both.

With each median its 95 % bootstrap interval (2000 resamples of the pooled
stances, fixed generator), and per leg and joint the paired difference
per-leg - lumped, stance by stance (same trial, same stance; a trial whose two
analyses compared different numbers of stances is left out of the pairing and
counted): how far a difference between the two medians is the method and how
far which stances the seeds drew.

``--first-once``: a trial's first stance lands from the simulator's lead-in,
which is the same for every seed (only the later hops vary), so pooling N
seeds counts that one hop N times; with this flag it is compared for the first
seed only. The test (test/bilateral/test_per_leg_recovery.py) pools seeds
11-14 as the lumped recovery test does, first stances included.

    .venv/bin/python bench/per_leg_recovery.py
    .venv/bin/python bench/per_leg_recovery.py --seeds $(seq 11 30) --first-once
    .venv/bin/python bench/per_leg_recovery.py --seeds 11 12 13 14 --left 2.20 --right 1.53 --measured

``--edge S`` leaves S seconds at each stance edge out of both analyses' fits.
``--pass-through HZ`` replaces the per-leg analysis' marker filter on the
rebuilt rigid markers (:data:`hop_impedance.biomech.per_leg.PASS_THROUGH_HZ`).
At the end, for the first seed, per leg and stance the hip moment against the
simulator's truth samples (RMS and max |error| as % of the true peak), of the
lumped analysis and of 2 x the per-leg one, and the largest |2 x per-leg -
lumped| with the leg's markers as measured (the construction's exactness).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hop_impedance.validation.bilateral_recovery import recover_legs
from hop_impedance.validation.coefficient_recovery import JOINTS, RecoveryResult, median_interval

HIP = 2


def hip_moment_check(freq_hz: dict[str, float], seed: int, hops: int) -> None:
    """Per leg and stance: hip moment errors against the truth samples (see the module docstring)."""
    from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
    from hop_impedance.biomech.per_leg import analyze_leg
    from hop_impedance.validation.bilateral_recovery import SHARE, bilateral_from_trials
    from hop_impedance.validation.coefficient_recovery import simulate_law_trial

    trials = {side: simulate_law_trial(f, seed, hops) for side, f in freq_hz.items()}
    bilateral, truths, whole = bilateral_from_trials(trials["left"], trials["right"], seed)
    options = AnalysisOptions(marker_cutoff_hz=40.0, force_cutoff_hz=40.0)
    for side in ("left", "right"):
        lumped = analyze_recording(whole[side], options)
        legs = {"rigid": analyze_leg(bilateral, side, options, True), "measured": analyze_leg(bilateral, side, options, False)}
        for k, stance in enumerate(lumped.stances):
            match = {name: [s for s in leg.stances if s.joints is not None and abs(s.touchdown_s - stance.touchdown_s) < 0.005]
                     for name, leg in legs.items()}
            if stance.joints is None or not all(match.values()):
                continue
            rigid, measured = match["rigid"][0], match["measured"][0]
            true = min(truths[side]["stances"], key=lambda s: abs(s["touchdown_s"] - stance.touchdown_s))
            t_true = np.asarray(true["samples"]["t_s"])
            m_true = np.asarray(true["samples"]["moments_nm"])[:, HIP]
            peak = np.max(np.abs(m_true))
            line = f"seed {seed} {side:5s} stance {k} hip vs truth (% of peak, RMS / max):"
            for name, s, scale in (("lumped", stance, 1.0), ("2 x per-leg rigid", rigid, 1 / SHARE)):
                e = np.interp(t_true, s.joints.time_s + s.touchdown_s, scale * s.joints.moment_nm[:, HIP],
                              left=np.nan, right=np.nan) - m_true
                line += f" {name} {100 * np.sqrt(np.nanmean(e ** 2)) / peak:.2f} / {100 * np.nanmax(np.abs(e)) / peak:.1f}"
            t = stance.joints.time_s + stance.touchdown_s
            diff = np.interp(t, measured.joints.time_s + measured.touchdown_s, measured.joints.moment_nm[:, HIP] / SHARE,
                             left=np.nan, right=np.nan) - stance.joints.moment_nm[:, HIP]
            lumped_peak = np.max(np.abs(stance.joints.moment_nm[:, HIP]))
            print(f"{line}; |2 x per-leg (measured) - lumped| max {100 * np.nanmax(np.abs(diff)) / lumped_peak:.3f} %"
                  f" (take-off {1000 * (measured.takeoff_s - stance.takeoff_s):+.1f} ms)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--left", type=float, default=2.20, help="the left leg's trial frequency (Hz, seed Table 2 law)")
    parser.add_argument("--right", type=float, default=1.87, help="the right leg's trial frequency (Hz)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13, 14])
    parser.add_argument("--hops", type=int, default=4)
    parser.add_argument("--measured", action="store_true", help="per-leg kinematics from the markers as measured (rigid=False)")
    parser.add_argument("--first-once", action="store_true", help="compare each trial's first stance for the first seed only")
    parser.add_argument("--edge", type=float, default=0.0, help="s left out of the fits at each stance edge (both analyses)")
    parser.add_argument("--pass-through", type=float, default=None, help="the per-leg marker filter on rigid markers (Hz)")
    args = parser.parse_args()
    if args.pass_through is not None:
        import hop_impedance.biomech.per_leg as per_leg

        per_leg.PASS_THROUGH_HZ = args.pass_through
    start = time.process_time()
    rng = np.random.default_rng(0)
    pooled = {(kind, side): RecoveryResult() for kind in ("per-leg", "lumped") for side in ("left", "right")}
    paired = {(side, joint): [] for side in ("left", "right") for joint in JOINTS}
    unpaired = {(side, joint): 0 for side in ("left", "right") for joint in JOINTS}
    for k, seed in enumerate(args.seeds):
        legs, _, _, lumped = recover_legs({"left": args.left, "right": args.right}, seed, n_hops=args.hops, lumped=True,
                                          rigid=not args.measured, skip_first=1 if args.first_once and k else 0,
                                          edge_s=args.edge)
        for side in ("left", "right"):
            pooled["per-leg", side].extend(legs[side])
            pooled["lumped", side].extend(lumped[side])
            for joint in JOINTS:
                a, b = legs[side].error_array(joint), lumped[side].error_array(joint)
                if len(a) == len(b):
                    paired[side, joint].extend(a - b)
                else:
                    unpaired[side, joint] += 1
    print(f"seeds {args.seeds}, {'measured markers' if args.measured else 'rigid-segment fit'}"
          f"{', first stance once' if args.first_once else ''}, fit edges {1000 * args.edge:g} ms;"
          " medians (%) with 95 % bootstrap interval")
    for (kind, side), result in pooled.items():
        freq = args.left if side == "left" else args.right
        for joint in JOINTS:
            e = 100 * result.error_array(joint)
            med, lo, hi = median_interval(e, rng) if len(e) else (np.full(2, np.nan),) * 3
            print(f"{kind:7s} {side:5s} ({freq:.2f} Hz law) {joint:5s} n={len(e):3d} infeasible={result.infeasible[joint]} "
                  f"| median k0 {med[0]:+6.2f} [{lo[0]:+6.2f}, {hi[0]:+6.2f}] k1 {med[1]:+6.2f} [{lo[1]:+6.2f}, {hi[1]:+6.2f}]")
    for (side, joint), diffs in paired.items():
        d = 100 * np.asarray(diffs, float).reshape(-1, 2)
        med, lo, hi = median_interval(d, rng) if len(d) else (np.full(2, np.nan),) * 3
        print(f"per-leg - lumped {side:5s} {joint:5s} paired n={len(d):3d} (trials unpaired {unpaired[side, joint]}) | "
              f"median k0 {med[0]:+6.2f} [{lo[0]:+6.2f}, {hi[0]:+6.2f}] k1 {med[1]:+6.2f} [{lo[1]:+6.2f}, {hi[1]:+6.2f}] "
              f"SD k1 {np.std(d[:, 1]) if len(d) else np.nan:.2f}")
    hip_moment_check({"left": args.left, "right": args.right}, args.seeds[0], args.hops)
    print(f"CPU {time.process_time() - start:.0f} s")


if __name__ == "__main__":
    main()
