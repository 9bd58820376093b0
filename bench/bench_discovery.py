"""Runtime of ``discover`` on a 10-hop recording (goal: < 60 s on this machine, both cores).

Every candidate is identified leave-one-stance-out and simulated forward on every held-out stance
(issue 16); the held-out simulations run in a process pool (``--workers``, default 2).
Prints the total, the time per selection round and the mean time per candidate (a candidate's share
of its round's pool time).

Usage: .venv/bin/python bench/bench_discovery.py [--workers N] [--recording REC.mcap]
"""

from __future__ import annotations

import argparse
import time

from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.stance_set import simulate_stance_set_recording


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--recording", default="", help="an MCAP recording instead of the simulated 10-hop one")
    args = ap.parse_args()
    if args.recording:
        rec = load_recording(args.recording)
    else:
        eff = Effects(angle_dependent_stiffness=True, damping=False, push_off=False)
        rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 10, seed=1, effects=eff, rtol=1e-6)
    t0 = time.perf_counter()
    doc = discover(rec, workers=args.workers)
    total = time.perf_counter() - t0
    tm = doc["timing"]
    print(f"recording: {args.recording or '10-hop simulated, angle-dependent stiffness'}; "
          f"stances used {len(doc['stances']['used'])}; effects found: {doc['effects_found']}")
    print(f"discover total: {total:.1f} s (body split search {tm['body_s']:.1f} s; baseline held-out runs "
          f"{tm['baseline_s']:.1f} s; rounds " + ", ".join(f"{r:.1f}" for r in tm["rounds"]) + " s; stiffness gate "
          + (", ".join(f"{r:.1f}" for r in tm["stiffness_s"]) or "not needed") + " s)")
    print("mean time per candidate (s): " + ", ".join(f"{k} {v:.1f}" for k, v in tm["per_candidate_s"].items()))


if __name__ == "__main__":
    main()
