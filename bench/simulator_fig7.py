"""Seed Fig. 7 (maximal against initial stiffness, one line across joints and frequencies, r^2 >= 0.9; issue 17, session 13).

Two questions:

1. Is r^2 0.9 reachable by Table 2's own law? Seed Table 2's reduced law K = k0 + k1 (rho - rho0) driven through
   seed Table 1's ranges of flexion (maximal flexion minus the touchdown angle) has its initial stiffness k0 and,
   with k1 > 0, its maximal k0 + k1 x range: nine points (3 joints x 3 frequencies), whose line and r^2 this prints
   (``impedance.seed_findings.fig7_line``, the demo's and bench/simulator_issue17.py's line). The seed's own
   Fig. 7 reports r^2 0.95 for its measured means.
2. Which point pulls a simulated r^2 down? With the variant flags of bench/simulator_issue17.py (``--bell``,
   ``--law-scale``, ...) and ``--simulate``, its nine points (mean initial and mean maximal K of the per-stance
   fits k0, k1, b0 after the first stance, noise-free 10-hop trials, as simulator_issue17's Fig. 7 row) are
   printed beside the law's, with the r^2 without each point and the ratio max / initial and range of each.

Usage::

    .venv/bin/python bench/simulator_fig7.py
    nice -n 19 .venv/bin/python bench/simulator_fig7.py --simulate --bell 0.9 \\
        --law-scale bell09_rigid_pad15_3_push06_08_trunk500_60 --surface rigid --pad 15,3 --push-timing 0.6,0.8 --trunk 500,60
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (benches next to this one)
from simulator_realism import SEED_TABLE1  # noqa: E402

from hop_impedance.impedance.seed_findings import fig7_line  # noqa: E402
from hop_impedance.simulation.fit_calibration import table2_k  # noqa: E402

JOINTS = ("ankle", "knee", "hip")


def law_points() -> dict[tuple[float, str], tuple[float, float, float]]:
    """(frequency, joint) -> (initial k0, maximal k0 + max(k1, 0) x range, range rad) of Table 2's law over Table 1's range."""
    points = {}
    for f, row in SEED_TABLE1.items():
        k = table2_k(f)
        for j, joint in enumerate(JOINTS):
            rom = row["rom"][j]
            points[(f, joint)] = (k[0, j], k[0, j] + max(k[1, j], 0.0) * rom, rom)
    return points


def leave_one_out(points: dict) -> dict:
    """Point -> r^2 of the line through the other points."""
    keys = list(points)
    return {key: fig7_line([points[k][:2] for k in keys if k != key])[2] for key in keys}


def print_points(label: str, points: dict, law: dict | None = None) -> None:
    """The points, the line, and r^2 without each point."""
    slope, intercept, r2 = fig7_line([p[:2] for p in points.values()])
    print(f"{label}: maximal = {slope:.2f} x initial {intercept:+.0f} N m/rad, r^2 {r2:.3f}")
    without = leave_one_out(points)
    for key, p in points.items():
        extra = "" if law is None else f" | law {law[key][0]:.0f} -> {law[key][1]:.0f} (ratio {law[key][1] / law[key][0]:.2f})"
        rom = f", range {p[2]:.2f} rad" if len(p) > 2 else ""
        print(f"  {key[0]:4.2f} Hz {key[1]:5s}: initial {p[0]:6.0f}, maximal {p[1]:6.0f} (ratio {p[1] / p[0]:.2f}{rom}); "
              f"r^2 without it {without[key]:.3f}{extra}")
    for joint in JOINTS:
        rest = [p[:2] for k, p in points.items() if k[1] != joint]
        print(f"  without the {joint}'s three points: r^2 {fig7_line(rest)[2]:.3f}")


def simulated_points(options: dict, surface: str, seed: int) -> dict:
    """simulator_issue17's measure_frequency at each seed frequency: (mean initial K, mean maximal K, analysed range)."""
    points = {}
    for f in SEED_TABLE1:
        m = s17.measure_frequency(f, options, seed=seed, surface=surface)
        for j, joint in enumerate(JOINTS):
            points[(f, joint)] = (*m.k_initial_max[joint], m.realism["rom"][j])
    return points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--simulate", action="store_true", help="also the variant's simulated points")
    parser.add_argument("--seed", type=int, default=1)
    s17.add_variant_arguments(parser)
    args = parser.parse_args()
    law = law_points()
    print_points("Table 2's law through Table 1's ranges", law)
    if args.simulate:
        options, said = s17.variant_options(s17.VariantArgs(**vars(args)))
        t0 = time.perf_counter()
        print_points(f"simulated ({said}; seed {args.seed})", simulated_points(options, args.surface, args.seed), law)
        print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
