"""Physics of an angle law in the measured stances: each stance's moment-angle curve, nothing simulated.

Per stance and joint, on the inverse-dynamics moment against the flexion ``dr = rho - rho0`` (the stance's core
samples, ``identify.core``): the secant stiffness of a straight line ``M = a + b dr`` and the curvature ``c`` of
``M = a + b dr + c dr^2`` (an angle law ``K = k0 + k1 dr`` integrated gives ``c = k1 / 2``; a constant K gives
0), with the stance's flexion amplitude. Per joint across stances: the mean curvature, its t over stances, and the
slope of the secant stiffness on the amplitude (an angle law makes the secant rise with amplitude by ``k1 / 2``
per rad for a stance whose curve is sampled from 0 to its peak). The table body (``measure_trial``), no body split.

Usage: PYTHONPATH=. .venv/bin/python bench/discovery_moment_angle_shape.py [REC.mcap ...] [--strict-null-seeds 0-59]
       [--strict-cases angle_dependent_stiffness --strict-seeds 3] [--hops 8]
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import stats

from hop_impedance.discovery.identify import core
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.io.recording_io import load_recording

JOINTS = ("ankle", "knee", "hip")


def stance_shape(s) -> np.ndarray:
    """(3, 4): per joint amplitude (rad), secant stiffness b (N m/rad), curvature c (N m/rad^2), and c's t."""
    keep = core(len(s.t_s))
    out = []
    for j in range(3):
        dr = (s.rho_rad[:, j] - s.rho_rad[0, j])[keep]
        m = s.moment_nm[keep, j]
        b = np.polyfit(dr, m, 1)[0]
        x = np.c_[np.ones_like(dr), dr, dr**2]
        coef, res, *_ = np.linalg.lstsq(x, m, rcond=None)
        sigma2 = float(np.sum((m - x @ coef) ** 2) / max(len(m) - 3, 1))
        cov = sigma2 * np.linalg.inv(x.T @ x)
        out.append([np.ptp(dr), b, coef[2], coef[2] / np.sqrt(cov[2, 2])])
    return np.array(out)


def summary(name: str, trial) -> dict:
    sh = np.array([stance_shape(s) for s in trial.stances])  # (n, 3, 4)
    row = {}
    for j, jn in enumerate(JOINTS):
        amp, b, c = sh[:, j, 0], sh[:, j, 1], sh[:, j, 2]
        t_c = stats.ttest_1samp(c, 0.0)
        slope = stats.linregress(amp, b) if np.ptp(amp) > 0 else None
        row[jn] = dict(amp=amp.mean(), amp_range=np.ptp(amp), c_mean=c.mean(), c_sd=c.std(ddof=1), t=t_c.statistic,
                       p=t_c.pvalue, slope=slope.slope if slope else np.nan, slope_p=slope.pvalue if slope else np.nan)
    print(f"{name} ({len(trial.stances)} stances): " + "; ".join(
        f"{jn} amp {r['amp']:.3f} (range {r['amp_range']:.3f}) c {r['c_mean']:.1f}+-{r['c_sd']:.1f} t {r['t']:.1f} "
        f"p {r['p']:.1e} | secant-on-amp slope {r['slope']:.0f} p {r['slope_p']:.2f}" for jn, r in row.items()),
        flush=True)
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recordings", nargs="*")
    ap.add_argument("--strict-null-seeds", default="")
    ap.add_argument("--strict-cases", default="")
    ap.add_argument("--strict-seeds", type=int, default=3)
    ap.add_argument("--hops", type=int, default=8)
    args = ap.parse_args()
    for p in args.recordings:
        summary(Path(p).stem, measure_trial(load_recording(p)))
    if args.strict_null_seeds or args.strict_cases:
        from hop_impedance.validation.strict_generator import StrictConfig, strict_recording
    if args.strict_null_seeds:
        a, _, b = args.strict_null_seeds.partition("-")
        for seed in range(int(a), int(b or a) + 1):
            rec = strict_recording(StrictConfig(seed=seed, hops=args.hops))[0]
            summary(f"strict null {seed}", measure_trial(rec))
    for case in filter(None, args.strict_cases.split(",")):
        for seed in range(args.strict_seeds):
            cfg = {"angle_dependent_stiffness": StrictConfig(angle_k1=0.8)}[case]  # bench/discovery_hit_rates.py's
            rec = strict_recording(replace(cfg, seed=seed, hops=args.hops))[0]
            summary(f"strict {case} {seed}", measure_trial(rec))


if __name__ == "__main__":
    main()
