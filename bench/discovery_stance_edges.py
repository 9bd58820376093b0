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

The true law's ``M_td``: ``--touchdown-moment`` (``discovery_truth_gap.TOUCHDOWN_MOMENTS``; default ``estimated``,
from the stance's ID moments against the identification's reference, as for a candidate; session 14 used the
truth's moment at the true contact, ``contact``, which starts the law 1-2 ms of flexion too low). ``--strict SEEDS``:
strict nulls of the second generator instead of the outside files (``--own-body``: its own segment parameters given
to the analysis); ``--only-simulator``: our simulator's noise-free null alone.

Session 15's touchdown-state option, measured and not adopted: ``--kink-fit`` (``measurement.TOUCHDOWN_KINK_FIT``: a
fit per marker coordinate with a velocity jump at the touchdown, ``--kink-window``/``--kink-degree``).
Session 14's touchdown-state options, measured and not adopted: ``--flight-touchdown`` (``measurement.
TOUCHDOWN_FROM_FLIGHT``: the state extrapolated from the flight's markers, a polynomial of ``--fit-degree`` over the
last ``--fit-window`` s) and ``--touchdown-cutoff HZ`` (``measurement.TOUCHDOWN_CUTOFF_HZ``: the low-passed
kinematics at another cut-off for the state only).

Usage: .venv/bin/python bench/discovery_stance_edges.py [FILE.mcap ...] [--simulator] [--freq 2.2] [--seed 1]
[--flight-touchdown [--fit-window 0.08] [--fit-degree 2]] [--touchdown-cutoff HZ] [--touchdown-moment estimated]
[--strict 3,15 [--own-body]] [--only-simulator] [--kink-fit [--kink-window 0.1,0.1] [--kink-degree 3]] (default: every
outside file of ../shared/foreign; ``--simulator``: also a noise-free null of our simulator).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from hop_impedance.biomech.joint_angles import joint_angles, joint_rates
from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import measurement
from hop_impedance.discovery.identify import touchdown_moments
from hop_impedance.discovery.measurement import MeasuredTrial, measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE, _stance_set_law, simulate_stance_set_recording

sys.path.insert(0, str(Path(__file__).resolve().parent))
from discovery_truth_gap import (  # noqa: E402  (a sibling bench script)
    STRICT_GROUND,
    TOUCHDOWN_MOMENTS,
    first_sample_truth,
    fitted_law,
    outside_truth,
    truth_hop,
)


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


def joint_state(trial: MeasuredTrial) -> tuple[np.ndarray, np.ndarray]:
    """Per stance, the touchdown state's joint angles and rates (rad, rad/s; ours: flexion positive), (n, 3) each."""
    q = np.array([s.touchdown.g[2:] for s in trial.stances])
    qd = np.array([s.touchdown.gd[2:] for s in trial.stances])
    return joint_angles(q, trial.chain.alpha_rad), joint_rates(qd)


def state_line(label: str, d_rho: np.ndarray, d_omega: np.ndarray) -> None:
    """Print the per-joint mean and SD over stances of angle (mrad) and rate (rad/s) differences."""
    print(f"  touchdown state, {label}: angles (ankle, knee, hip) {np.round(1e3 * d_rho.mean(0), 1).tolist()} mrad "
          f"(SD {np.round(1e3 * d_rho.std(0), 1).tolist()}), rates {np.round(d_omega.mean(0), 2).tolist()} rad/s "
          f"(SD {np.round(d_omega.std(0), 2).tolist()})")


def truth_state(truth: dict, clock_ns: int, trial: MeasuredTrial) -> tuple[np.ndarray, np.ndarray]:
    """Per stance, the outside truth's joint angles and flexion rates at the stance's first plate sample
    (``stance_truth``, 5 ms rows, interpolated), in our convention. The truth's ``rho_t`` falls with flexion:
    ``rho_t1 = alpha_t - (q1 - q2)``, ``rho_t2 = pi - (q3 - q2)``, ``rho_t3 = pi - (q3 - q4)``; its ``w`` is our rate."""
    rho, omega = [], []
    for s in trial.stances:
        hop = truth_hop(truth, clock_ns, s)
        rho_t = first_sample_truth(truth, hop, clock_ns, s, "rho")
        # our rho1 = q1 - q2 + alpha: from the truth's, q1 - q2 = alpha_t - rho_t1
        rho.append(np.array([truth["subject"]["alpha"] - rho_t[0] + trial.chain.alpha_rad, 2 * np.pi - rho_t[1],
                             2 * np.pi - rho_t[2]]))
        omega.append(first_sample_truth(truth, hop, clock_ns, s, "w"))
    return np.array(rho), np.array(omega)


def outside(path: Path, touchdown_moment: str = TOUCHDOWN_MOMENTS[0]) -> None:
    _, truth, trial, hops, laws, grounds, clock_ns = outside_truth(path, touchdown_moment)
    contacts = [((h["t_td_ns"] - clock_ns) * 1e-9, (h["t_to_ns"] - clock_ns) * 1e-9) for h in hops]
    report(path.stem, trial, contacts, laws, grounds)
    (rho, omega), (rho_t, omega_t) = joint_state(trial), truth_state(truth, clock_ns, trial)
    state_line("minus the truth's at the first sample", rho - rho_t, omega - omega_t)


def simulator(freq_hz: float, seed: int, touchdown_moment: str = TOUCHDOWN_MOMENTS[0]) -> None:
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
    laws = [law] * n  # its moment is 0 at the contact, and about 0 at the first sample (the impact is instant)
    if touchdown_moment == "estimated":
        k0 = np.array(law.parts[0].k0, float)[:, None]
        laws = [fitted_law("estimated", ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), s) for s in trial.stances]
    report(f"our simulator, noise-free null, {freq_hz} Hz, seed {seed}", trial, contacts, laws, [RIGID_NO_BOUNCE] * n)
    kink = measurement.TOUCHDOWN_KINK_FIT
    measurement.TOUCHDOWN_KINK_FIT = not kink
    other = measure_trial(rec)
    measurement.TOUCHDOWN_KINK_FIT = kink
    (rho, omega), (rho_o, omega_o) = joint_state(trial), joint_state(other)
    state_line(f"{'kinked fit' if kink else 'default'} minus {'default' if kink else 'kinked fit'}", rho - rho_o,
               omega - omega_o)
    print(f"  joint rates at the touchdown, default {np.round((omega_o if kink else omega).mean(0), 2).tolist()}, kinked "
          f"fit (the stance side) {np.round((omega if kink else omega_o).mean(0), 2).tolist()} rad/s")


def strict(seed: int, hops: int, touchdown_moment: str, own_body: bool) -> None:
    """A strict null of the second generator (its lossless 1e7 |y|^1.5 ground, Winter's body; ``own_body``: its own
    segment parameters given to the analysis, else the table's)."""
    from discovery_body_nuisance import generator_overrides

    from hop_impedance.biomech.analysis import AnalysisOptions
    from hop_impedance.validation.strict_generator import StrictConfig, strict_recording

    cfg = StrictConfig(seed=seed, hops=hops)
    rec, truth = strict_recording(cfg)
    trial = measure_trial(rec, options=AnalysisOptions(overrides=generator_overrides(cfg)) if own_body else None)
    hops_ = [min(truth["per_hop"], key=lambda h: abs(h["t_td"] - s.touchdown_s)) for s in trial.stances]
    contacts = [(h["t_td"], h["t_to"]) for h in hops_]
    laws = []
    for s, h in zip(trial.stances, hops_):
        k0 = np.array(h["k0"], float)[:, None]
        m_td = touchdown_moments(ModelSpec(), k0, s) if touchdown_moment == "estimated" else np.asarray(h["M_td"], float)
        laws.append(fitted_law(touchdown_moment, ModelSpec(), k0, m_td, s))
    report(f"second generator, strict null seed {seed} ({'its own body' if own_body else 'table body'})", trial, contacts,
           laws, [STRICT_GROUND] * len(laws))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--simulator", action="store_true", help="also a noise-free null of our simulator")
    ap.add_argument("--only-simulator", action="store_true", help="that null only (no outside file)")
    ap.add_argument("--strict", default="", help="comma-separated strict null seeds of the second generator (no outside file)")
    ap.add_argument("--own-body", action="store_true", help="the second generator's own segment parameters")
    ap.add_argument("--freq", type=float, default=2.2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--flight-touchdown", action="store_true", help="the touchdown state extrapolated from the flight")
    ap.add_argument("--fit-window", type=float, default=measurement.TOUCHDOWN_FIT_S)
    ap.add_argument("--fit-degree", type=int, default=measurement.TOUCHDOWN_FIT_DEGREE)
    ap.add_argument("--touchdown-moment", choices=TOUCHDOWN_MOMENTS, default=TOUCHDOWN_MOMENTS[0],
                    help="the true law's M_td (discovery_truth_gap.TOUCHDOWN_MOMENTS; session 14: contact)")
    ap.add_argument("--touchdown-cutoff", type=float, default=None, help="cut-off (Hz) of the touchdown state's kinematics")
    ap.add_argument("--kink-fit", action="store_true", help="the touchdown state fitted with a kink (session 15)")
    ap.add_argument("--kink-window", default=",".join(map(str, measurement.TOUCHDOWN_KINK_WINDOW_S)),
                    help="seconds before,after the touchdown")
    ap.add_argument("--kink-degree", type=int, default=measurement.TOUCHDOWN_KINK_DEGREE)
    args = ap.parse_args()
    measurement.TOUCHDOWN_KINK_FIT = args.kink_fit
    measurement.TOUCHDOWN_KINK_WINDOW_S = tuple(float(x) for x in args.kink_window.split(","))
    measurement.TOUCHDOWN_KINK_DEGREE = args.kink_degree
    measurement.TOUCHDOWN_FROM_FLIGHT = args.flight_touchdown
    measurement.TOUCHDOWN_FIT_S, measurement.TOUCHDOWN_FIT_DEGREE = args.fit_window, args.fit_degree
    measurement.TOUCHDOWN_CUTOFF_HZ = args.touchdown_cutoff
    fs.TWO_SIDED_DURATION = True  # the simulation sampled past the measured end (both definitions are printed)
    outside_files = [] if args.only_simulator or args.strict else sorted(Path("../shared/foreign").glob("*.mcap"))
    files = [Path(f) for f in args.files] or outside_files
    for path in files:
        outside(path, args.touchdown_moment)
    for seed in [int(x) for x in args.strict.split(",") if x]:
        strict(seed, 8, args.touchdown_moment, args.own_body)
    if args.simulator or args.only_simulator:
        simulator(args.freq, args.seed, args.touchdown_moment)


if __name__ == "__main__":
    main()
