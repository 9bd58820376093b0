"""Issue 17's criteria over several trial seeds: how much of a row's verdict is the one trial it reads (session 34).

bench/simulator_issue17.py measures every row on one noise-free 10-hop trial per frequency (trial seed 1; the seed's
hop-to-hop variability). The seed's figures are means over 8 subjects, each a 20 s trial (~37 hops, the first five
discarded). This bench runs the same trials on seeds 1..N (default 8, the seed's n) and prints a line per trial:
first the nominal hopper's (the same trial without hop-to-hop variability, the hop the seeds scatter around), then
each seed's, with the rows the issue 17 bench prints for it (Table 1, fits, bells, Table 3, Fig. 7; not seed 001's),
its binding cells out, Fig. 7's r^2 and the cells that decide its verdict; then the criteria on the seeds' means:
Table 1's cells on the mean over the trials, Fig. 7 on the mean points (the seed's "average maximal ... versus the
average initial stiffness").

Nothing here is written into a table: it says how far one trial's verdict carries.

Usage::

    nice -n 10 .venv/bin/python bench/simulator_trial_seeds.py              # the preset, seeds 1-8, embedded cluster
    nice -n 10 .venv/bin/python bench/simulator_trial_seeds.py --seeds 4 --scheduler serial
    nice -n 10 .venv/bin/python bench/simulator_trial_seeds.py --seeds 1 --stances 1.53   # stance by stance
    nice -n 10 .venv/bin/python bench/simulator_trial_seeds.py --law-scale-file law.json   # a variant (issue 17's flags)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (benches next to this one)
from simulator_realism import SEED_TABLE1, TABLE1_TRIAL_HOPS, binding_cells  # noqa: E402

from hop_impedance.batch.runner import cluster_map  # noqa: E402
from hop_impedance.impedance.seed_findings import fig7_line  # noqa: E402
from hop_impedance.simulation.fit_calibration import table2_k  # noqa: E402

#: The seed's subjects (seed 000: "Eight female subjects").
SEED_SUBJECTS = 8


#: The trial "seed" of the nominal hopper: no hop-to-hop variability at all (``variability=False``), the hop the
#: variability scatters around.
NOMINAL = 0


def trial_options(options: dict, seed: int) -> dict:
    """``simulate_recording`` options of trial ``seed``: :data:`NOMINAL` without hop-to-hop variability."""
    return dict(options, variability=False) if seed == NOMINAL else options


def _measure(options: dict, surface: str, freq: float, seed: int) -> s17.FrequencyMeasure:
    """One noise-free trial (bench/simulator_issue17.py's measure_frequency) of ``options`` on ``surface``."""
    return s17.measure_frequency(freq, trial_options(options, seed), TABLE1_TRIAL_HOPS, seed, surface)


def measure_seeds(options: dict, surface: str, seeds: list[int], scheduler: str) -> dict[int, dict[float, s17.FrequencyMeasure]]:
    """{trial seed: {frequency: measure}}, one task per trial (``cluster_map``: 'serial', 'local' or an address)."""
    jobs = [(options, surface, f, s) for s in seeds for f in s17.FREQS]
    done = dict(zip(((f, s) for _, _, f, s in jobs), cluster_map(_measure, jobs, mode=scheduler)))
    return {s: {f: done[(f, s)] for f in s17.FREQS} for s in seeds}


def stance_lines(options: dict, surface: str, freq: float, seed: int) -> list[str]:
    """``--stances F``: each analysed stance's ranges of flexion (ankle / knee / hip, rad) and the ankle's fitted k0,
    k1 (the per-stance fit of the issue 17 bench) in the trial ``seed`` at ``freq`` (:data:`NOMINAL`: no variability)."""
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.simulation.fit_calibration import seed_model_fits
    from hop_impedance.simulation.sensors import SensorConfig, noise_free
    from hop_impedance.simulation.simulate import simulate_recording

    rec, _ = simulate_recording(freq, surface, TABLE1_TRIAL_HOPS, seed=seed, sensors=noise_free(SensorConfig()),
                                **trial_options(options, seed))
    analysis = analyze_recording(rec)
    stances = [s for s in analysis.stances if s.joints is not None][1:]  # the fits' stances: after the first
    lines = [f"{freq:g} Hz, trial {'nominal' if seed == NOMINAL else f'seed {seed}'}: stance, ranges of flexion "
             "ankle / knee / hip (rad), ankle k0 / k1 (N m/rad)"]
    for stance, fit in zip(stances, seed_model_fits(analysis)):
        angle = stance.joints.angle_rad
        rom = angle.max(axis=0) - angle[0]
        k = fit["ankle"].coefficients
        lines.append(f"  {stance.index}: {rom[0]:.3f} / {rom[1]:.3f} / {rom[2]:.3f}, {k.get('k0', 0.0):.0f} / "
                     f"{k.get('k1', 0.0):.0f}")
    return lines


def seed_line(seed: str, measures: dict) -> str:
    """A trial seed's verdicts: the rows the issue 17 bench prints for it (less seed 001's), cells out, Fig. 7."""
    table1, out = s17.realism_rows(measures)
    rows = table1 + s17.fit_rows(measures)
    failing = [r.criterion for r in rows if not r.passed]
    r2 = fig7_line([m.k_initial_max[j] for m in measures.values() for j in s17.JOINTS])[2]
    ankle_k1 = {f: m.fitted[1, 0] / table2_k(f)[1, 0] - 1.0 for f, m in measures.items()}
    hip_rom = measures[1.53].realism["rom"][2] / SEED_TABLE1[1.53]["rom"][2] - 1.0
    return (f"| {seed} | {sum(r.passed for r in rows)} / {len(rows)} | {len(out)} | {r2:.3f} | {hip_rom:+.0%} | "
            f"{', '.join(f'{d:+.0%}' for d in ankle_k1.values())} | {'; '.join(failing) or '-'} |")


def mean_realism(per_seed: dict) -> dict:
    """{frequency: Table 1 figures averaged over the trial seeds} (the seed's means over subjects)."""
    keys = ("stance_ms", "grf_bw", "hip_exc_m", "rom", "mmax", "com_drop_m")
    return {f: {k: np.mean([np.asarray(m[f].realism[k], float) for m in per_seed.values()], axis=0) for k in keys}
            for f in s17.FREQS}


def pooled_lines(per_seed: dict) -> list[str]:
    """Table 1's binding cells on the means over the trial seeds, and Fig. 7 on the mean points."""
    cells = binding_cells(mean_realism(per_seed))
    out = [f"{name} at {f:g} Hz {sim / seed - 1:+.0%}" for name, f, sim, seed, band in cells if abs(sim / seed - 1) > band]
    points = [tuple(np.mean([m[f].k_initial_max[j] for m in per_seed.values()], axis=0))
              for f in s17.FREQS for j in s17.JOINTS]
    slope, intercept, r2 = fig7_line(points)
    return [f"Table 1 on the means over {len(per_seed)} trials: {len(out)} binding cells out: {'; '.join(out) or 'none'}",
            f"Fig. 7 on the mean points of {len(per_seed)} trials: r^2 {r2:.3f} (slope {slope:.2f}, intercept "
            f"{intercept:.0f} N m/rad; criterion >= {s17.FIG7_R2})"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)  # a variant of the preset, as bench/simulator_issue17.py takes it
    parser.set_defaults(hopper="seed-like", surface="rigid")
    parser.add_argument("--seeds", type=int, default=SEED_SUBJECTS, help=f"trial seeds 1..N (default {SEED_SUBJECTS})")
    parser.add_argument("--stances", type=float, default=None, metavar="F",
                        help="also each stance's ranges of flexion and ankle fit at F Hz, nominal trial and seed 1")
    parser.add_argument("--scheduler", metavar="ADDRESS", default="local",
                        help="one Dask task per trial: 'local' (embedded cluster, default), tcp://HOST:8786, or 'serial' "
                             "(this process)")
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error("--seeds: at least 1")
    try:
        options, setup = s17.variant_options(args)
    except (argparse.ArgumentTypeError, ValueError) as exc:
        parser.error(str(exc))
    t0 = time.perf_counter()
    per_seed = measure_seeds(options, args.surface, [NOMINAL, *range(1, args.seeds + 1)], args.scheduler)
    nominal = per_seed.pop(NOMINAL)
    print(f"{setup}, surface {args.surface}; noise-free {TABLE1_TRIAL_HOPS}-hop trials:")
    print("| trial seed | rows passed (less seed 001's) | binding cells out | Fig. 7 r^2 | 1.53 Hz hip range "
          "| ankle k1 vs Table 2, 1.53 / 1.87 / 2.2 Hz | rows failing |")
    print("|---|---|---|---|---|---|---|")
    print(seed_line("nominal (no variability)", nominal))
    for seed, measures in per_seed.items():
        print(seed_line(str(seed), measures))
    print("\n".join(pooled_lines(per_seed)))
    if args.stances is not None:
        for seed in (NOMINAL, 1):
            print("\n".join(stance_lines(options, args.surface, args.stances, seed)))
    print(f"(the nominal trial and {args.seeds} trial seeds x {len(s17.FREQS)} frequencies, scheduler {args.scheduler}: "
          f"{time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
