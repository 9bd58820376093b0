"""Runtime of ``discover`` on a 10-hop recording (goal: < 60 s on this machine, both cores).

Every candidate is identified leave-one-stance-out and simulated forward on every held-out stance
(issue 16); the held-out simulations run in a process pool (``--workers``, default 2).
Prints the total, the time per phase (body split searches, baseline, selection rounds, stiffness
searches with their evaluations of all stances), the mean time per candidate (a candidate's share of its
round's pool time), the CPU time of the run (this process and its worker processes: less dependent on
the machine's load than the wall time) and the load average before and after.

``--search``: the stiffness gate's search (:data:`hop_impedance.discovery.stiffness_gate.SEARCH`).

Usage: .venv/bin/python bench/bench_discovery.py [--workers N] [--recording REC.mcap]
       [--search nelder-mead|levenberg-marquardt] [--converge | --budget] [--effect-size] [--folds K]
"""

from __future__ import annotations

import argparse
import os
import resource
import time

from hop_impedance.discovery import stiffness_gate
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.stance_set import simulate_stance_set_recording


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--recording", default="", help="an MCAP recording instead of the simulated 10-hop one")
    ap.add_argument("--search", choices=("nelder-mead", "levenberg-marquardt"), default=stiffness_gate.SEARCH)
    ap.add_argument("--converge", action="store_true",
                    help="stiffness_gate.TO_CONVERGENCE (session 10; the default since session 12)")
    ap.add_argument("--budget", action="store_true",
                    help="stiffness_gate.SESSION9_BUDGET: the evaluation caps decide (the default of sessions 8-11)")
    ap.add_argument("--effect-size", action="store_true", help="stiffness_gate.SHOOT_EFFECT_SIZE (session 10)")
    ap.add_argument("--folds", type=int, default=stiffness_gate.FOLDS,
                    help="stiffness_gate.FOLDS: the held-out gate's folds (0: in-sample gate, sessions 8-10)")
    args = ap.parse_args()
    _configure(args)
    if args.recording:
        rec = load_recording(args.recording)
    else:
        eff = Effects(angle_dependent_stiffness=True, damping=False, push_off=False)
        rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 10, seed=1, effects=eff, rtol=1e-6)
    load0 = os.getloadavg()[0]
    cpu0, t0 = _cpu_s(), time.perf_counter()
    doc = discover(rec, workers=args.workers)
    total, cpu = time.perf_counter() - t0, _cpu_s() - cpu0
    tm = doc["timing"]
    after = [b["seconds"] for b in doc["nuisance"].get("body_mass_split_after_step", [])]
    searches = [[(name, g["evaluations"], g["converged"], *gate_gaps(g), g["effect_factors_shot"],
                  g.get("p_value"))
                 for name, g in [("current", st["current"]), *st["candidates"].items()]]
                for st in doc["selection"]["stiffness_through_simulation"]]
    print(f"recording: {args.recording or '10-hop simulated, angle-dependent stiffness'}; search {args.search}; "
          f"gate folds {args.folds}; "
          f"stances used {len(doc['stances']['used'])}; effects found: {doc['effects_found']}")
    print(f"discover total: {total:.1f} s (body split search {tm['body_s']:.1f} s, again after each step "
          + (", ".join(f"{b:.1f}" for b in after) or "-") + f" s; baseline held-out runs "
          f"{tm['baseline_s']:.1f} s; rounds " + ", ".join(f"{r:.1f}" for r in tm["rounds"]) + " s; stiffness gate "
          + (", ".join(f"{r:.1f}" for r in tm["stiffness_s"]) or "not needed") + " s)")
    print("stiffness searches per gate (model, evaluations (of all stances, or of a fold's training stances), "
          "converged, gap (held out, or in-sample with --folds 0) with the regression's coefficients and shot, "
          "the effect's shot size, the gate's p-value; a current "
          "model named in the round before reuses that search): " + str(searches))
    print(f"CPU time (this process and its workers): {cpu:.1f} s; load average (1 min) before {load0:.2f}, "
          f"after {os.getloadavg()[0]:.2f}")
    print("mean time per candidate (s): " + ", ".join(f"{k} {v:.1f}" for k, v in tm["per_candidate_s"].items()))


def _configure(args: argparse.Namespace) -> None:
    """The gate's search and its other options (:func:`configure_gate`)."""
    stiffness_gate.SEARCH = args.search
    configure_gate(args)


def configure_gate(args: argparse.Namespace) -> None:
    """The gate options this bench and discovery_gate_search.py share: ``--budget`` / ``--converge``
    (stiffness_gate.SESSION9_BUDGET / TO_CONVERGENCE), ``--effect-size``, ``--folds``."""
    if args.budget:
        for name, value in stiffness_gate.SESSION9_BUDGET.items():
            setattr(stiffness_gate, name, value)
    if args.converge:
        for name, value in stiffness_gate.TO_CONVERGENCE.items():
            setattr(stiffness_gate, name, value)
    stiffness_gate.SHOOT_EFFECT_SIZE = args.effect_size
    stiffness_gate.FOLDS = args.folds


def gate_gaps(g: dict) -> list[float]:
    """A gate search's gaps with the regression's and the shot parameters (held out, or in-sample when FOLDS = 0)."""
    return g.get("held_out_gap_regression_shot") or g["in_sample_gap_regression_shot"]


def _cpu_s() -> float:
    """User + system CPU time of this process and of its ended child processes (the pool's workers) (s)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    main()
