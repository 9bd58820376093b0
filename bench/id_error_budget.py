"""Where the end-to-end k0/k1 error of test/impedance/test_simulated_recordings.py comes from.

Simulates the push-off-free hard-surface trial of that test (seed 11, 4 hops),
samples it noise-free and with realistic noise, runs ``analyze_recording`` and
compares, per stance and joint:

- the inverse-dynamics moment minus the simulator's true moment, RMS in three
  phases of the true stance (first 10 %, middle 80 %, last 10 %), in % of the
  joint's true peak |moment|;
- the k0/k1 relative error (%) of the test's fit (k0, k1, b0 given, 10 ms
  left out at each edge) on:
  ``id``   the analysis as it is (what the test measures),
  ``kin``  the analysis' angles/rates with the *true* moment (error of the
           kinematics alone),
  ``td``/``mid``/``to``  the true moment with the ID error added only in the
           first 10 % / middle 80 % / last 10 % of the stance (which part of
           the moment error moves the coefficients).

Usage::

    .venv/bin/python bench/id_error_budget.py --frequency 1.87 --noise clean --cutoff 20
    .venv/bin/python bench/id_error_budget.py --frequency 2.2 --noise markers --cutoff 12
    .venv/bin/python bench/id_error_budget.py --frequency 1.87 --noise clean --marker-rate 1000 --cutoff 20

Prints one line per stance and the medians; CPU time at the end.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.impedance.recording_fits import default_fit_options
from hop_impedance.impedance.stance_fit import fit_joint_stance
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.hopping_trial import simulate_hopping
from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects, hopping_config
from hop_impedance.simulation.sensors import SensorConfig, noise_free, sample_recording
from hop_impedance.simulation.simulate import write_simulated_recording
from hop_impedance.simulation.truth import trial_truth

JOINTS = ("ankle", "knee", "hip")
PHASES = {"td": (0.0, 0.1), "mid": (0.1, 0.9), "to": (0.9, 1.01)}
SEED = 11
EDGE_S = 0.010


def sensor_config(noise: str, marker_rate_hz: float) -> SensorConfig:
    """The test's sensors: ``clean`` (no noise), ``noisy`` (1 mm, 2 N, 0.5 N m) or one source only."""
    realistic = replace(SensorConfig(), marker_rate_hz=marker_rate_hz)
    quiet = noise_free(realistic)
    return {
        "clean": quiet,
        "noisy": realistic,
        "markers": replace(quiet, marker_noise_m=realistic.marker_noise_m),
        "force": replace(quiet, force_noise_n=realistic.force_noise_n, torque_noise_nm=realistic.torque_noise_nm),
    }[noise]


def simulated_recording(freq_hz: float, noise: str, folder: Path, marker_rate_hz: float = 100.0) -> tuple[Path, dict]:
    """The test's trial written as MCAP; returns the path and the truth dict."""
    effects = Effects(push_off=False)
    chain, config = hopping_config(freq_hz, "hard", 4, effects)
    trial = simulate_hopping(chain, config, seed=SEED)
    sensors = sensor_config(noise, marker_rate_hz)
    rec, sensor_truth = sample_recording(trial, sensors, SEED_SUBJECT, np.random.default_rng([SEED, 1]))
    truth = trial_truth(trial, sensors, SEED_SUBJECT, body_model_from_stature(SEED_SUBJECT), effects.to_dict(), sensor_truth, {})
    path = folder / f"{noise}.mcap"
    write_simulated_recording(path, rec, truth)
    return path, truth


def k_errors(t, rho, omega, moment, true_impedance, options) -> list[float]:
    """Relative errors of k0 and k1 (fraction) of one joint-stance fit."""
    fit = fit_joint_stance(t, rho, omega, moment, options)
    if not fit.ok:
        return [np.nan, np.nan]
    return [fit.coefficients[k] / true_impedance[k] - 1.0 for k in ("k0", "k1")]


def edge_steps(true_stance: dict) -> str:
    """The simulator's loads at the stance edges: what a low-pass has to follow there.

    Fz 1 ms after touchdown (the surface law's damping step), Fx and the hip
    moment at the last sample before take-off (hip as % of its peak |moment|).
    """
    s = true_stance["samples"]
    grf = np.asarray(s["grf_n"], float)
    hip = np.asarray(s["moments_nm"], float)[:, 2]
    return (f"truth: Fz {grf[1, 1]:.0f} N at touchdown + 1 ms, at take-off Fx {grf[-1, 0]:.0f} N, Fz {grf[-1, 1]:.0f} N, "
            f"hip {hip[-1]:.1f} N m ({100 * abs(hip[-1]) / np.max(np.abs(hip)):.0f} % of peak)")


def stance_budget(stance, true_stance, options) -> dict:
    """Phase RMS errors (% of peak) and k0/k1 errors (%) per joint of one analysed stance."""
    s = true_stance["samples"]
    tt = np.asarray(s["t_s"], float)
    true_m = np.asarray(s["moments_nm"], float)
    t = stance.joints.time_s + stance.touchdown_s
    inside = (t >= tt[0]) & (t <= tt[-1])
    t_rel = stance.joints.time_s[inside]
    phase = (t[inside] - true_stance["touchdown_s"]) / (true_stance["takeoff_s"] - true_stance["touchdown_s"])
    out = {}
    for j, joint in enumerate(JOINTS):
        rho = stance.joints.angle_rad[inside, j]
        omega = stance.joints.angular_velocity_rad_s[inside, j]
        m_id = stance.joints.moment_nm[inside, j]
        m_true = np.interp(t[inside], tt, true_m[:, j])
        err = m_id - m_true
        peak = np.max(np.abs(true_m[:, j]))
        imp = true_stance["impedance"][joint]
        row = {"rms": {}, "k": {}}
        for name, (a, b) in PHASES.items():
            sel = (phase >= a) & (phase < b)
            row["rms"][name] = 100 * np.sqrt(np.mean(err[sel] ** 2)) / peak
            row["k"][name] = k_errors(t_rel, rho, omega, m_true + np.where(sel, err, 0.0), imp, options)
        row["k"]["id"] = k_errors(t_rel, rho, omega, m_id, imp, options)
        truth_fit = fit_joint_stance(tt - tt[0], np.asarray(s["rho_rad"], float)[:, j],
                                     np.asarray(s["omega_rad_s"], float)[:, j], true_m[:, j], options)
        row["k"]["truth"] = [truth_fit.coefficients[k] / imp[k] - 1.0 for k in ("k0", "k1")]
        row["active"] = truth_fit.active_constraints
        # Local stiffness of the simulated law, K = k0 + k1 (rho - rho0) (Eq. 3 without k2, k3), at its lowest.
        d = np.asarray(s["rho_rad"], float)[:, j] - imp["rho0_rad"]
        row["k_min"] = float(np.min(imp["k0"] + imp["k1"] * d))
        row["k"]["kin"] = k_errors(t_rel, rho, omega, m_true, imp, options)
        out[joint] = row
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frequency", type=float, default=1.87)
    parser.add_argument("--noise", choices=("clean", "noisy", "markers", "force"), default="clean",
                        help="sensor noise: none, realistic, or the realistic noise of one stream only")
    parser.add_argument("--marker-rate", type=float, default=100.0, help="marker sampling rate (Hz), 100 in the test")
    parser.add_argument("--cutoff", type=float, default=20.0, help="marker and force cut-off (Hz)")
    parser.add_argument("--edge", type=float, default=EDGE_S, help="time left out of the fit at each stance edge (s)")
    parser.add_argument("--force-cutoff", type=float, default=None, help="force cut-off if different (Hz)")
    args = parser.parse_args()
    cpu0 = time.process_time()
    with tempfile.TemporaryDirectory() as folder:
        path, truth = simulated_recording(args.frequency, args.noise, Path(folder), args.marker_rate)
        cpu_sim = time.process_time() - cpu0
        options = AnalysisOptions(marker_cutoff_hz=args.cutoff, force_cutoff_hz=args.force_cutoff or args.cutoff)
        analysis = analyze_recording(load_recording(path), options)
    fit_options = replace(
        default_fit_options(options), reduce=False, terms=("k0", "k1", "b0"), exclude_touchdown_s=args.edge,
        exclude_takeoff_s=args.edge,
    )
    by_touchdown = {round(s["touchdown_s"], 2): s for s in truth["stances"]}
    budgets = []
    print(f"{args.frequency} Hz {args.noise}, markers at {args.marker_rate:g} Hz, cut-off {args.cutoff:g} Hz "
          f"(force {args.force_cutoff or args.cutoff:g} Hz), "
          f"{1e3 * args.edge:g} ms left out of the fit at each edge")
    print("joint: ID error RMS % of peak td/mid/to | k0,k1 error % for id, kin, td, mid, to, truth (active constraints)")
    for stance in analysis.stances:
        true_stance = by_touchdown.get(round(stance.touchdown_s, 2))
        if true_stance is None or stance.rejection_reason is not None:
            continue
        b = stance_budget(stance, true_stance, fit_options)
        budgets.append(b)
        print(f"stance {stance.index} (touchdown {1e3 * (stance.touchdown_s - true_stance['touchdown_s']):+.1f} ms, "
              f"take-off {1e3 * (stance.takeoff_s - true_stance['takeoff_s']):+.1f} ms vs truth); {edge_steps(true_stance)}")
        for joint, row in b.items():
            rms = "/".join(f"{row['rms'][p]:.1f}" for p in PHASES)
            ks = "  ".join(f"{n} {100 * row['k'][n][0]:+5.1f},{100 * row['k'][n][1]:+5.1f}"
                           for n in ("id", "kin", "td", "mid", "to", "truth"))
            print(f"  {joint:5s} {rms:15s} | {ks} ({row['active']} active; law's min K {row['k_min']:.0f} N m/rad)")
    print("median over stances")
    for joint in JOINTS:
        rms = "/".join(f"{np.median([b[joint]['rms'][p] for b in budgets]):.1f}" for p in PHASES)
        ks = "  ".join(
            f"{n} " + ",".join(f"{100 * v:+5.1f}" for v in np.median([b[joint]["k"][n] for b in budgets], axis=0))
            for n in ("id", "kin", "td", "mid", "to", "truth")
        )
        print(f"  {joint:5s} {rms:15s} | {ks}")
    print(f"CPU {time.process_time() - cpu0:.1f} s (simulation {cpu_sim:.1f} s)")


if __name__ == "__main__":
    main()
