"""Hit rate per hidden effect and false-discovery rate on null recordings (issue 8).

Generates recordings with :func:`hop_impedance.simulation.stance_set.simulate_stance_set_recording`
(10 hops, seed 001 / Table 2 laws at the seed's frequencies, default sensor noise:
force 2 N, markers 1 mm), one hidden effect each (simulator default magnitudes),
plus null (baseline truth) and two-effect cases, and runs
:func:`hop_impedance.discovery.workflow.discover` (selection only, no forward gaps).

Usage: .venv/bin/python bench/discovery_hit_rates.py [--seeds N] [--hops N] [--cases a,b,...]
Prints one line per run and the table (markdown) at the end.
"""

from __future__ import annotations

import argparse
import time

from hop_impedance.discovery.workflow import discover
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import simulate_stance_set_recording

BASE = dict(angle_dependent_stiffness=False, damping=False, push_off=False)
FREQS = (1.53, 1.87, 2.2)
#: case -> (law switches, surfaces, sensors, expected effects)
CASES = {
    "null": ({}, ("rigid",), {}, set()),
    "angle_dependent_stiffness": ({"angle_dependent_stiffness": True}, ("rigid",), {}, {"angle_dependent_stiffness"}),
    "rate_dependent_stiffness": ({"rate_dependent_stiffness": True}, ("rigid",), {}, {"rate_dependent_stiffness"}),
    "joint_damping": ({"damping": True}, ("rigid",), {}, {"joint_damping"}),
    "surface_compliance": ({}, ("hard",), {}, {"surface_compliance"}),
    "time_dependent_activation": ({"time_activation": True}, ("hard", "soft"), {},
                                  {"time_dependent_activation", "surface_compliance"}),
    "stream_latency": ({}, ("rigid",), {"marker_time_offset_s": 0.01}, {"stream_latency"}),
    "force_plate_offset": ({}, ("rigid",), {"force_offset_n": 10.0}, {"force_plate_offset"}),
    "active_push_off": ({"push_off": True}, ("rigid",), {}, {"active_push_off"}),
    "two:angle+offset": ({"angle_dependent_stiffness": True}, ("rigid",), {"force_offset_n": 10.0},
                         {"angle_dependent_stiffness", "force_plate_offset"}),
    "two:push+soft": ({"push_off": True}, ("soft",), {}, {"active_push_off", "surface_compliance"}),
}


def run_case(name: str, seed: int, hops: int) -> tuple[set, set, float]:
    """(expected, found, seconds) of one generated recording."""
    law, surfaces, sensors, expected = CASES[name]
    freq = FREQS[seed % len(FREQS)]
    rec, _ = simulate_stance_set_recording(freq, surfaces, hops, seed=seed, effects=Effects(**{**BASE, **law}),
                                           sensors=SensorConfig(**sensors), rtol=1e-6)
    t0 = time.perf_counter()
    doc = discover(rec, forward=False)
    return expected, set(doc["effects_found"]), time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--hops", type=int, default=10)
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args()
    rows = []
    for name in args.cases.split(","):
        hits = false = nulls_flagged = 0
        for seed in range(args.seeds):
            try:
                expected, found, sec = run_case(name, seed, args.hops)
            except ValueError as exc:
                print(f"{name} seed {seed}: generation/discovery error: {exc}", flush=True)
                continue
            hit = expected <= found if expected else not found
            extra = found - expected
            hits += hit
            false += bool(extra)
            print(f"{name:28s} seed {seed} f={FREQS[seed % 3]} found={sorted(found)} "
                  f"{'HIT' if hit else 'MISS'} extra={sorted(extra)} {sec:.1f}s", flush=True)
        rows.append((name, hits, false, args.seeds))
    print("\n| case | all hidden effects named | recordings with a wrong extra name | runs |")
    print("|---|---|---|---|")
    for name, hits, false, n in rows:
        print(f"| {name} | {hits}/{n} ({100 * hits / n:.0f} %) | {false}/{n} ({100 * false / n:.0f} %) | {n} |")


if __name__ == "__main__":
    main()
