"""Stance edges: the detector's bias against the truth and the gap's duration term of the TRUE law (issue 16, session 14).

Session 14's two-sided duration term (``forward_selection.TWO_SIDED_DURATION``) compares the simulated take-off with
the measured one (:func:`hop_impedance.discovery.forward_selection.simulated_take_off_s`: the simulated plate force
read at the detector's take-off level, on the clock of the measured touchdown). A model that is right should then
show about no duration error. Per recording this prints, over its stances (mean and range, ms):

1. the detector's touchdown and take-off minus the truth's contact times (outside files: ``per_hop`` ``t_td_ns`` /
   ``t_to_ns``; our simulator: the truth's ``stances``), and the first plate sample after the detected touchdown
   (where the simulation's clock starts);
2. the true law simulated from each measured touchdown state exactly like a candidate
   (``forward_selection.simulate_for_gap``; outside files: ``discovery_truth_gap.truth_law`` and the truth's
   surfaces; our simulator: the generating law on its rigid ground): its simulated minus measured take-off,
   the same with the simulation's own end (force zero) instead of the detector's level, and the term as it was
   before session 14 (the simulation sampled at the measured times only: 0 for any stance simulated too long).

Session 14's touchdown-state options, measured and not adopted: ``--flight-touchdown`` (``measurement.
TOUCHDOWN_FROM_FLIGHT``: the state extrapolated from the flight's markers, a polynomial of ``--fit-degree`` over the
last ``--fit-window`` s) and ``--touchdown-cutoff HZ`` (``measurement.TOUCHDOWN_CUTOFF_HZ``: the low-passed
kinematics at another cut-off for the state only).

Usage: .venv/bin/python bench/discovery_stance_edges.py [FILE.mcap ...] [--simulator] [--freq 2.2] [--seed 1]
[--flight-touchdown [--fit-window 0.08] [--fit-degree 2]] [--touchdown-cutoff HZ] (default: every outside file of
../shared/foreign; ``--simulator``: also a noise-free null of our simulator).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import measurement
from hop_impedance.discovery.measurement import MeasuredTrial, measure_trial
from hop_impedance.discovery.model import FittedLaw
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.ground import SURFACES
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE, _stance_set_law, simulate_stance_set_recording

sys.path.insert(0, str(Path(__file__).resolve().parent))
from discovery_truth_gap import STRICT_GROUND, truth_law  # noqa: E402  (a sibling bench script)


def ms(x) -> str:
    """Mean [min, max] in ms."""
    x = 1e3 * np.asarray(x, float)
    return f"{x.mean():+.2f} [{x.min():+.2f}, {x.max():+.2f}] ms"


def report(name: str, trial: MeasuredTrial, contacts: list[tuple[float, float]], laws: list, grounds: list) -> None:
    """Print the edges' bias and the true law's duration terms (module docstring)."""
    level = fs.take_off_level_n(trial)
    td = [s.touchdown_s - c[0] for s, c in zip(trial.stances, contacts)]
    to = [s.takeoff_s - c[1] for s, c in zip(trial.stances, contacts)]
    new, own_end, old = [], [], []
    for s, law, ground in zip(trial.stances, laws, grounds):
        sim = fs.simulate_for_gap(trial.chain, law, ground, s)
        measured = float(s.takeoff_s - s.touchdown_s)
        new.append(fs.simulated_take_off_s(sim, s, level) - measured)
        own_end.append(float(s.t_s[0] + sim.t_s[-1]) - measured)
        old.append(min(float(sim.t_s[-1]), float(s.t_s[-1])) - float(s.t_s[-1]))
    print(f"{name}: {len(trial.stances)} stances, take-off level {level:.1f} N")
    print(f"  detected minus true: touchdown {ms(td)}, take-off {ms(to)}; first sample after the touchdown "
          f"{ms([s.t_s[0] for s in trial.stances])}")
    print(f"  true law, simulated minus measured take-off: {ms(new)}; with the simulation's own end (force zero) "
          f"{ms(own_end)}; the term before session 14 {ms(old)}", flush=True)


def outside(path: Path) -> None:
    rec = load_recording(path)
    truth = json.loads(path.with_suffix(".truth.json").read_text())
    latency = 0.0
    if "stream_latency" in truth["effects"]:
        latency = 1e-3 * float(truth["effect_details"]["stream_latency"].split()[-2])
    trial = measure_trial(rec, marker_latency_s=latency)
    contacts, laws, grounds = [], [], []
    for s in trial.stances:
        hop = min(truth["per_hop"], key=lambda h: abs((h["t_td_ns"] - rec.start_ns) * 1e-9 - s.touchdown_s))
        contacts.append(((hop["t_td_ns"] - rec.start_ns) * 1e-9, (hop["t_to_ns"] - rec.start_ns) * 1e-9))
        spec, coefs = truth_law(hop)
        laws.append(FittedLaw(spec, coefs, np.asarray(hop["law"]["M_td"], float)))
        grounds.append(SURFACES[hop["surface"]] if "surface_compliance" in truth["effects"] else STRICT_GROUND)
    report(path.stem, trial, contacts, laws, grounds)


def simulator(freq_hz: float, seed: int) -> None:
    effects = Effects(angle_dependent_stiffness=False, damping=False, push_off=False)
    sensors = noise_free(SensorConfig())
    rec, truth = simulate_stance_set_recording(freq_hz, ("rigid",), 8, seed, effects, sensors)
    trial = measure_trial(rec)
    law, _, _ = _stance_set_law(trial.chain, freq_hz, effects, None, RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    t0 = (rec.start_ns - sensors.start_ns) * 1e-9
    contacts = []
    for s in trial.stances:
        st = min(truth["stances"], key=lambda x: abs(x["touchdown_s"] - t0 - s.touchdown_s))
        contacts.append((st["touchdown_s"] - t0, st["takeoff_s"] - t0))
    n = len(trial.stances)
    report(f"our simulator, noise-free null, {freq_hz} Hz, seed {seed}", trial, contacts, [law] * n, [RIGID_NO_BOUNCE] * n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--simulator", action="store_true", help="also a noise-free null of our simulator")
    ap.add_argument("--freq", type=float, default=2.2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--flight-touchdown", action="store_true", help="the touchdown state extrapolated from the flight")
    ap.add_argument("--fit-window", type=float, default=measurement.TOUCHDOWN_FIT_S)
    ap.add_argument("--fit-degree", type=int, default=measurement.TOUCHDOWN_FIT_DEGREE)
    ap.add_argument("--touchdown-cutoff", type=float, default=None, help="cut-off (Hz) of the touchdown state's kinematics")
    args = ap.parse_args()
    measurement.TOUCHDOWN_FROM_FLIGHT = args.flight_touchdown
    measurement.TOUCHDOWN_FIT_S, measurement.TOUCHDOWN_FIT_DEGREE = args.fit_window, args.fit_degree
    measurement.TOUCHDOWN_CUTOFF_HZ = args.touchdown_cutoff
    fs.TWO_SIDED_DURATION = True  # the simulation sampled past the measured end (both definitions are printed)
    files = [Path(f) for f in args.files] or sorted(Path("../shared/foreign").glob("*.mcap"))
    for path in files:
        outside(path)
    if args.simulator:
        simulator(args.freq, args.seed)


if __name__ == "__main__":
    main()
