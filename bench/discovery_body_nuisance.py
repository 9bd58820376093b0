"""The body-mass-split nuisance of discovery (issue 16): table vs true vs chosen segment parameters.

For strict nulls of the second generator (Winter's segment table, perturbed +-5 %), prints the strict
baseline's in-sample forward gap (identified on all stances, every stance simulated from its measured
touchdown state) with three bodies: the analysis' de Leva table, the generator's own segment parameters
(its truth, given to the analysis as overrides) and the thigh/HAT split
:func:`hop_impedance.discovery.body_nuisance.choose_body` picks; then the chosen thigh and HAT masses
against the generator's. With ``--foreign DIR`` the same for the outside generator's files (de Leva +-5 %),
against their truth's segment masses.

    .venv/bin/python bench/discovery_body_nuisance.py [--seeds 10,11,12] [--hops 8] [--foreign ../shared/foreign]
                                                      [--simulator null,angle]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from hop_impedance.biomech.analysis import AnalysisOptions
from hop_impedance.discovery.body_nuisance import choose_body, in_sample_gap
from hop_impedance.discovery.forward_selection import gap_scales
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.io.recording_io import load_recording
from hop_impedance.validation.strict_generator import StrictConfig, strict_recording
from hop_impedance.validation.strict_generator import generator as gen

SEGMENTS = ("foot", "shank", "thigh", "hat")


def generator_overrides(cfg: StrictConfig) -> dict:
    """The strict generator's segment parameters as analysis overrides (its body is its seed's first draw)."""
    body = gen.perturbed_body(cfg.mass_kg, cfg.height_m, np.random.default_rng(cfg.seed))
    a0 = np.arctan2(body.ankle_height, -gen.ANKLE_ALONG * body.sole)
    # the foot's centre of mass, written in the frame toe -> ankle (the analysis' foot frame)
    v = np.array([-body.com[0] * body.sole, 0.35 * body.ankle_height])
    e1, e2 = np.array([np.cos(a0), np.sin(a0)]), np.array([-np.sin(a0), np.cos(a0)])
    out = {"foot": {"mass_kg": body.mass[0], "com_along_m": float(v @ e1), "com_perp_m": float(v @ e2),
                    "inertia_kgm2": body.inertia[0]}}
    for i, name in enumerate(SEGMENTS[1:], start=1):
        out[name] = {"mass_kg": body.mass[i], "com_along_m": body.com[i] * body.length[i], "com_perp_m": 0.0,
                     "inertia_kgm2": body.inertia[i]}
    return out


def strict_row(seed: int, hops: int) -> None:
    cfg = StrictConfig(seed=seed, hops=hops)
    rec, _ = strict_recording(cfg)
    table = measure_trial(rec)
    scales = gap_scales(table)
    truth = generator_overrides(cfg)
    gap_true = in_sample_gap(measure_trial(rec, options=AnalysisOptions(overrides=truth)), scales)
    t0 = time.perf_counter()
    _, choice = choose_body(rec, table)
    print(f"strict null seed {seed}: in-sample baseline gap table {choice.gap_table:.4f}, generator's own body "
          f"{gap_true:.4f}, chosen split {choice.gap_chosen:.4f} (fraction {choice.fraction:+.3f}, "
          f"{choice.evaluations} evaluations, {time.perf_counter() - t0:.1f} s); thigh mass table/chosen/true "
          f"{choice.thigh_mass_kg[0]:.2f}/{choice.thigh_mass_kg[1]:.2f}/{truth['thigh']['mass_kg']:.2f} kg, HAT "
          f"{choice.hat_mass_kg[0]:.2f}/{choice.hat_mass_kg[1]:.2f}/{truth['hat']['mass_kg']:.2f} kg", flush=True)


def foreign_row(path: Path) -> None:
    truth = json.loads(path.with_suffix(".truth.json").read_text())
    rec = load_recording(str(path))
    t0 = time.perf_counter()
    try:
        _, choice = choose_body(rec, measure_trial(rec))
    except ValueError as exc:
        print(f"{path.stem}: {exc}")
        return
    seg = truth["subject"]["seg_mass"]
    print(f"{path.stem}: gap table {choice.gap_table:.4f} chosen {choice.gap_chosen:.4f} (fraction "
          f"{choice.fraction:+.3f}, {time.perf_counter() - t0:.1f} s); thigh table/chosen/true "
          f"{choice.thigh_mass_kg[0]:.2f}/{choice.thigh_mass_kg[1]:.2f}/{seg[2]:.2f} kg, HAT "
          f"{choice.hat_mass_kg[0]:.2f}/{choice.hat_mass_kg[1]:.2f}/{seg[3]:.2f} kg", flush=True)


def simulator_row(name: str) -> None:
    """Our simulator's 10-hop 2.2 Hz recording of ``name`` (test/discovery/test_discovery.py's, seed 2)."""
    from hop_impedance.simulation.scenarios import Effects
    from hop_impedance.simulation.stance_set import simulate_stance_set_recording

    law = {"angle_dependent_stiffness": name == "angle", "damping": False, "push_off": False}
    rec = simulate_stance_set_recording(2.2, ("rigid",), 10, seed=2, effects=Effects(**law), rtol=1e-6)[0]
    t0 = time.perf_counter()
    _, choice = choose_body(rec, measure_trial(rec))
    print(f"our simulator {name} (de Leva body, 2.2 Hz, seed 2): in-sample baseline gap table {choice.gap_table:.4f}, "
          f"chosen {choice.gap_chosen:.4f} (fraction {choice.fraction:+.3f}; best searched {choice.searched[0]:+.3f} with gap "
          f"{choice.searched[1]:.4f}; {time.perf_counter() - t0:.1f} s)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="10,11,12,13,14,15")
    ap.add_argument("--hops", type=int, default=8)
    ap.add_argument("--foreign", default="", help="also the outside generator's files in this folder")
    ap.add_argument("--simulator", default="", help="also our simulator's recordings: null,angle")
    args = ap.parse_args()
    for name in (n for n in args.simulator.split(",") if n):
        simulator_row(name)
    for seed in (int(s) for s in args.seeds.split(",") if s):
        strict_row(seed, args.hops)
    if args.foreign:
        for path in sorted(Path(args.foreign).glob("*.mcap")):
            foreign_row(path)


if __name__ == "__main__":
    main()
