"""Does the stiffness gate's outcome depend on its search? ``discover`` with each search, side by side.

The gate (:mod:`hop_impedance.discovery.stiffness_gate`) shoots k0 and the effect's own terms of the current
model and of each passing candidate through the simulation; both searches run to the same stated tolerance
(``STEP_TOL``, ``GAP_TOL``; a search that reaches its safety cap says ``converged False``). If the gate
is budget-independent, both name the same effects. Per recording and search: the effects named, the wall
and CPU time, and per gate and model the evaluations, whether it converged, the in-sample gap with the
regression's and the shot coefficients, the effect's shot size and the gate's p-value.

Usage: .venv/bin/python bench/discovery_gate_search.py [--searches levenberg-marquardt,nelder-mead]
       [--converge | --budget] [--effect-size] [--folds K] [--strict-null-seeds 3,47 [--hops 8]] [REC.mcap ...]
       (no recording: bench_discovery.py's simulated 10-hop angle recording)
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from pathlib import Path

from bench_discovery import configure_gate, gate_gaps

from hop_impedance.discovery import stiffness_gate
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.stance_set import simulate_stance_set_recording


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recordings", nargs="*")
    ap.add_argument("--searches", default="levenberg-marquardt,nelder-mead")
    ap.add_argument("--converge", action="store_true",
                    help="stiffness_gate.TO_CONVERGENCE (session 10; the default since session 12)")
    ap.add_argument("--budget", action="store_true",
                    help="stiffness_gate.SESSION9_BUDGET: the evaluation caps decide (the default of sessions 8-11)")
    ap.add_argument("--effect-size", action="store_true", help="stiffness_gate.SHOOT_EFFECT_SIZE (session 10)")
    ap.add_argument("--strict-null-seeds", default="", help="strict nulls of the second generator instead, e.g. 3,47")
    ap.add_argument("--hops", type=int, default=8, help="hops of a strict null")
    ap.add_argument("--folds", type=int, default=stiffness_gate.FOLDS,
                    help="stiffness_gate.FOLDS: the held-out gate's folds (0: in-sample gate, sessions 8-10)")
    args = ap.parse_args()
    configure_gate(args)
    for name, rec in _recordings(args):
        for search in args.searches.split(","):
            stiffness_gate.SEARCH = search
            print(_row(name, search, rec), flush=True)


def _recordings(args: argparse.Namespace):
    """(name, recording): the strict nulls asked for, else the files, else bench_discovery's recording."""
    if args.strict_null_seeds:
        from hop_impedance.validation.strict_generator import StrictConfig, strict_recording

        for seed in (int(x) for x in args.strict_null_seeds.split(",")):
            yield f"strict null seed {seed} ({args.hops} hops)", strict_recording(StrictConfig(seed=seed, hops=args.hops))[0]
        return
    for path in args.recordings:
        yield Path(path).stem, load_recording(path)
    if not args.recordings:
        eff = Effects(angle_dependent_stiffness=True, damping=False, push_off=False)
        yield "bench_discovery 10-hop angle", simulate_stance_set_recording(2.2, ("rigid",), 10, seed=1, effects=eff,
                                                                            rtol=1e-6)[0]


def _row(name: str, search: str, rec) -> str:
    load0, cpu0, t0 = os.getloadavg()[0], _cpu_s(), time.perf_counter()
    doc = discover(rec)
    wall, cpu = time.perf_counter() - t0, _cpu_s() - cpu0
    gates = [[(model, g["evaluations"], g["converged"], *gate_gaps(g), g["effect_factors_shot"],
               None if g.get("p_value") is None else round(g["p_value"], 5))
              for model, g in [("current", st["current"]), *st["candidates"].items()]]
             for st in doc["selection"]["stiffness_through_simulation"]]
    return (f"{name} | {search}: named {doc['effects_found']}; {wall:.1f} s, CPU {cpu:.1f} s, load "
            f"{load0:.2f} -> {os.getloadavg()[0]:.2f}, folds {stiffness_gate.FOLDS}\n  gates (model, evaluations, "
            f"converged, gap regression, gap shot, effect size, p): {gates}")


def _cpu_s() -> float:
    """User + system CPU time of this process and of its ended child processes (the pool's workers) (s)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    main()
