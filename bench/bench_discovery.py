"""Runtime of ``discover`` (with forward-simulation gaps) on a 10-hop recording (goal: < 60 s on 2 cores).

Usage: .venv/bin/python bench/bench_discovery.py
"""

from __future__ import annotations

import time

from hop_impedance.discovery.workflow import discover
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.stance_set import simulate_stance_set_recording


def main() -> None:
    eff = Effects(angle_dependent_stiffness=True, damping=False, push_off=False)
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 10, seed=1, effects=eff, rtol=1e-6)
    t0 = time.perf_counter()
    doc = discover(rec, forward=True)
    t1 = time.perf_counter()
    discover(rec, forward=False)
    t2 = time.perf_counter()
    print(f"10-hop recording, effects found: {doc['effects_found']}")
    print(f"discover with forward-simulation gaps: {t1 - t0:.1f} s")
    print(f"discover, selection only:              {t2 - t1:.1f} s")


if __name__ == "__main__":
    main()
