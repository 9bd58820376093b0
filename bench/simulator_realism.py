"""Simulator realism: simulated hopping next to the seed's Table 1 and the HopExo 2.4 Hz means.

Usage::

    .venv/bin/python bench/simulator_realism.py                    # print the tables
    .venv/bin/python bench/simulator_realism.py --write            # also write docs/simulator_realism.md
    .venv/bin/python bench/simulator_realism.py --trunk            # with the trunk-balance moment
    .venv/bin/python bench/simulator_realism.py --flight energy_keeping
    .venv/bin/python bench/simulator_realism.py --seed-like       # issue 17 candidate (scenarios.seed_like_options)
    .venv/bin/python bench/simulator_realism.py --seed-like --write   # its tables into docs/simulator.md
    .venv/bin/python bench/simulator_realism.py --seed-like --bell 1 --fits --freqs 1.53,1.87,2.2  # without the bell, with fits
    .venv/bin/python bench/simulator_realism.py --seed-like --fit-law --fits  # the law whose fit returns Table 2
    .venv/bin/python bench/simulator_realism.py --hopper seed-like    # the package's preset (the bundled recordings')
    .venv/bin/python bench/simulator_realism.py --hopper seed-like --write   # its table into the README and docs
    .venv/bin/python bench/simulator_realism.py --hopper seed-like --push-weights 1,-0.2,0.3 --law-scale-file F.json
    .venv/bin/python bench/simulator_realism.py --hopper seed-like --trunk-gains 300,40 --law-scale-file F.json

Every simulated figure is measured by the analysis (``hop-impedance analyze``:
``analyze_recording`` + ``io.analyze_json.analysis_to_json``, stance detection and 2D inverse
dynamics from the recorded markers and force plate, 12 Hz low-pass), not read
from the simulator: a noise-free recording of a hard-surface trial with the
default law (seed Table 2 k0, k1; b0 = 0.5 N m s/rad; push-off) and the seed's
mean subject (54.8 kg, 1.63 m) is simulated, analysed, and the complete stances
after the first are averaged. Only the HopExo hop-cycle ranges use the recorded
markers outside stance (joint angles from the marker positions). Takes a few minutes.

Reading of the seed's "vertical excursion of hip" (Table 1; issue 17 leaves it open)
------------------------------------------------------------------------------------
Binding: the range of the hip marker's height *during the stance* (``analyze``'s
``hip_excursion_m``). The seed's text puts it there (Table 1 is "the kinematic and kinetic
results during the stance phase"; "During the stance phase the range of flexion of the joints
and the vertical excursion of the hip were found to significantly decrease"; Fig. 3 plots GRF
against "the vertical excursion of the hip during the ground-contact phase"). The seed's Table 2
leg stiffness is its peak GRF over *half* that excursion (54.8 kg: 2.5 x 537.6 N / 0.135 m =
9.96 kN/m against 9.8; 3.0 x 537.6 / 0.110 = 14.66 against 14.6; 3.5 x 537.6 / 0.090 = 20.9
against 20.9), which would make the excursion twice the leg's compression (down and up again).
Newton rules that reading out: the seed's own peak GRF, stance time and frequency fix how far
its centre of mass falls in stance (impulse = weight x period; a force sin^n(pi t / Tc) whose
n gives the seed's peak, :func:`newton_com_drop`): 0.233 / 0.163 / 0.130 m at 1.53 / 1.87 /
2.20 Hz. Half the excursion, 0.135 / 0.110 / 0.090 m, is 0.58-0.69 x that, so the hip would
fall far less than the centre of mass although the trunk, most of the mass, stays upright on
it; the whole excursion is 1.16-1.39 x it. So the factor of 2 sits in the seed's leg-stiffness
arithmetic, not in its excursion. The other readings are reported, not binding: the hip's drop
in stance against half the seed's excursion, and the hip's range over the whole hop cycle
(touchdown to touchdown, flight included).
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.biomech.joint_angles import JOINT_NAMES, joint_angles
from hop_impedance.biomech.kinematics import sagittal_markers, segment_angles_from_points
from hop_impedance.io.analyze_json import analysis_to_json
from hop_impedance.recording import MARKER_NAMES
from hop_impedance.simulation.fit_calibration import table2_k
from hop_impedance.simulation.hopping_trial import FLIGHT_MODELS, LANDINGS
from hop_impedance.simulation.scenarios import (
    DEFAULT_TOUCHDOWN_RHO,
    PUSH_OFF_TIMING,
    SEED_LIKE_HOPPER_SURFACE,
    SEED_LIKE_LAW_SCALE,
    TRUNK_BALANCE,
    Effects,
    seed_like_hopper_options,
    seed_like_options,
    toe_tip_ahead_m,
)
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.simulate import simulate_recording

ROOT = Path(__file__).resolve().parents[1]
HOPEXO = Path("/work/shared/data_candidates/hopexo_2p4hz")

#: Seed paper Table 1 (means) at 1.53 / 1.87 / 2.20 Hz.
SEED_TABLE1 = {
    1.53: {"grf_bw": 2.5, "stance_ms": 458, "hip_exc_m": 0.27, "rom": (0.85, 0.70, 0.37), "mmax": (233.4, 96.8, 26.4),
           "brake_j": (51.8, 15.2, 0.7)},
    1.87: {"grf_bw": 3.0, "stance_ms": 333, "hip_exc_m": 0.22, "rom": (0.69, 0.42, 0.18), "mmax": (281.3, 115.3, 28.9),
           "brake_j": (30.0, 6.9, 0.6)},
    2.20: {"grf_bw": 3.5, "stance_ms": 282, "hip_exc_m": 0.18, "rom": (0.59, 0.27, 0.11), "mmax": (359.2, 123.8, 36.1),
           "brake_j": (21.1, 2.2, 0.4)},
}


#: Issue 17's binding bands (relative to seed Table 1); the hip's maximal moment and the energies are
#: reported, not binding (the seed's own tables disagree there).
BANDS = {"stance": 0.15, "grf": 0.15, "hip_exc": 0.15, "rom": 0.20, "mmax": 0.25}

#: The trial every simulated Table 1 figure is measured on: a noise-free trial of this many hops, the complete stances
#: after the first averaged. Ten, as the bundled recordings (recordings/regenerate.sh) and issue 17's fit rows ("noise-free
#: 10-hop trials"), so that this table and bench/simulator_issue17.py's Table 1 rows read the same recording (session 34:
#: until then 6 hops here and 10 there, and the two disagreed on a cell, the 1.53 Hz hip range -20 % against -19 %).
#: ``--hops`` prints the table on a longer trial (the seed's trials had ~37 hops), not written.
TABLE1_TRIAL_HOPS = 10


def hopexo_means() -> dict:
    """Means over the 14 subjects, no-exoskeleton condition: tc (s), fz (N), joint ROM (deg, whole hop cycle)."""
    out = {}
    with open(HOPEXO / "kin_data.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["con"] == "nh"]
    for var in ("hz", "tc", "fz", "hop_height"):
        out[var] = float(np.mean([float(r["value"]) for r in rows if r["var"] == var]))
    with open(HOPEXO / "ang_data.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["con"] == "nh" and r["peak"] == "rom"]
    out["rom_deg"] = tuple(float(np.mean([float(r["value"]) for r in rows if r["joint"] == j])) for j in ("ank", "kne", "hip"))
    with open(HOPEXO / "pow_data.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["con"] == "nh" and r["cont"] == "net"]
    for kind in ("pos", "neg"):
        out[f"power_{kind}_w_kg"] = tuple(
            float(np.mean([float(r["value"]) for r in rows if r["joint"] == j and r["pow"] == kind]))
            for j in ("ank", "kne", "hip"))
    with open(HOPEXO / "mom_data.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["con"] == "nh" and r["cont"] == "net"]
    out["moment_nm_kg"] = tuple(float(np.mean([float(r["value"]) for r in rows if r["joint"] == j]))
                                for j in ("ank", "kne", "hip"))
    return out


#: Points toe, ankle, knee, hip, head in MARKER_NAMES order (the segment chain of the analysis).
CHAIN_POINTS = [MARKER_NAMES.index(n) for n in ("toe", "ankle", "knee", "hip", "head")]


def measure(freq_hz: float, hops: int = TABLE1_TRIAL_HOPS, seed: int = 1, trunk: bool = False, flight: str = "prescribed",
            posture=DEFAULT_TOUCHDOWN_RHO, contact_ahead_m: float = 0.0, push_timing=PUSH_OFF_TIMING,
            effects: Effects = Effects(), bell_activation_min: float | None = None, fits: bool = False,
            law_scale: dict | None = None) -> dict:
    """Mean per-hop figures that the analysis measures on a noise-free simulated recording (hard surface)."""
    rec, truth = simulate_recording(freq_hz, "hard", hops, seed=seed, sensors=noise_free(SensorConfig()), effects=effects,
                                    touchdown_rho_rad=posture, trunk_balance=TRUNK_BALANCE if trunk else None,
                                    flight=flight, contact_ahead_m=contact_ahead_m, push_timing=push_timing,
                                    bell_activation_min=bell_activation_min, law_scale=law_scale)
    return summarise(freq_hz, rec, truth, fits)


def measure_hopper(freq_hz: float, options: dict, surface: str, hops: int = TABLE1_TRIAL_HOPS, seed: int = 1,
                   fits: bool = False) -> dict:
    """:func:`measure`'s figures for a hopper given as ``simulate_recording`` options on ``surface`` (``--hopper``)."""
    rec, truth = simulate_recording(freq_hz, surface, hops, seed=seed, sensors=noise_free(SensorConfig()), **options)
    return summarise(freq_hz, rec, truth, fits)


def summarise(freq_hz: float, rec, truth: dict, fits: bool = False, analysis=None) -> dict:
    """:func:`measure`'s figures of a simulated recording and its truth (``analysis``: its analysis, if made)."""
    analysis = analyze_recording(rec) if analysis is None else analysis
    doc = analysis_to_json(analysis)
    if fits:  # the per-stance Eq. 3 fit that `hop-impedance analyze` adds, with k0, k1, b0 for every joint
        from hop_impedance.cli.analyze_cmd import add_fits_to_json

        add_fits_to_json(doc, analysis, ["k0", "k1", "b0"])
    mass = doc["subject"]["body_mass_kg"]
    stances = [s for s in doc["stances"] if s["complete"] and s["joints"]][1:]  # the first lands from the lead-in
    if not stances:
        raise ValueError(f"{freq_hz} Hz: no complete analysed stance after the first ({truth['stop_reason']})")
    rows = []
    for s in stances:
        joints = [s["joints"][j] for j in ("ankle", "knee", "hip")]
        angle = np.array([j["angle_rad"] for j in joints], float).T
        moment = np.array([j["moment_nm"] for j in joints], float).T
        t = np.asarray(joints[0]["time_s"], float)
        rows.append({
            "stance_ms": 1000 * s["contact_time_s"],
            "grf_bw": s["peak_grf_bw"],
            "grf_n": s["peak_grf_N"],
            "hip_exc_m": s["hip_excursion_m"],
            "com_drop_m": s["peak_grf_N"] / s["leg_stiffness_n_per_m"],  # the analysis' COM drop (from the plate)
            "rom": angle.max(axis=0) - angle[0],
            "mmax": moment.max(axis=0),
            "k_leg": s["leg_stiffness_n_per_m"],
            "brake_j": np.array([j["brake_work_j"] for j in joints]),
            "push_j": np.array([j["push_work_j"] for j in joints]),
            "moment_integral_nm_s": np.trapezoid(moment, t, axis=0),
            "freq_hz": s["hop_frequency_hz"],
            **({f"fit_{c}": np.array([j["fit"]["coefficients"][c] for j in joints]) for c in ("k0", "k1")} if fits else {}),
        })
    mean = {k: (np.median if k.startswith("fit_") else np.mean)([r[k] for r in rows], axis=0) for k in rows[0]}
    # Joint angles over whole hop cycles (touchdown of the first averaged stance to that of the last), from markers.
    start, end = stances[0]["touchdown_s"], stances[-1]["touchdown_s"]
    t_m = (rec.markers.stamp_ns - doc["recording"]["start_ns"]) * 1e-9
    sel = (t_m >= start) & (t_m < end)
    points = sagittal_markers(rec.markers)[sel][:, CHAIN_POINTS, :]
    alpha = truth["body_model"]["alpha_rad"]
    rho_cycle = joint_angles(segment_angles_from_points(points), alpha) if sel.sum() > 2 else np.full((2, 3), np.nan)
    # HopExo convention: averages over the whole hop cycle, per leg (our moments are both legs), per kg.
    per_leg_kg_cycle = mean["freq_hz"] / (2.0 * mass)
    mean["power_pos_w_kg"] = mean["push_j"] * per_leg_kg_cycle
    mean["power_neg_w_kg"] = -mean["brake_j"] * per_leg_kg_cycle
    mean["moment_nm_kg"] = mean["moment_integral_nm_s"] * per_leg_kg_cycle
    mean["rom_cycle_deg"] = np.degrees(np.ptp(rho_cycle, axis=0))
    # Hip marker's vertical range over each whole hop cycle (touchdown to next touchdown), from the markers.
    hip_z = sagittal_markers(rec.markers)[:, MARKER_NAMES.index("hip"), 1]
    tds = [s["touchdown_s"] for s in stances]
    ranges = [np.ptp(hip_z[(t_m >= a) & (t_m < b)]) for a, b in zip(tds[:-1], tds[1:])]
    mean["hip_range_cycle_m"] = float(np.mean(ranges)) if ranges else np.nan
    mean["notes"] = list(truth["notes"]) + ([f"stopped: {truth['stop_reason']}"] if truth["stop_reason"] else [])
    mean["n_stances"] = len(rows)
    return mean


def binding_cells(results: dict) -> list[tuple[str, float, float, float, float]]:
    """Issue 17's binding Table 1 cells: (quantity, frequency, simulated, seed, band) for each seed frequency in
    ``results`` (:func:`measure`'s dicts by frequency); a cell is out when |simulated / seed - 1| > band."""
    cells = []
    for f in (f for f in SEED_TABLE1 if f in results):
        r, seed = results[f], SEED_TABLE1[f]
        cells += [("stance time (ms)", f, r["stance_ms"], seed["stance_ms"], BANDS["stance"]),
                  ("peak GRF (BW)", f, r["grf_bw"], seed["grf_bw"], BANDS["grf"]),
                  ("hip vertical excursion (m)", f, r["hip_exc_m"], seed["hip_exc_m"], BANDS["hip_exc"])]
        cells += [(f"{name} range of flexion (rad)", f, r["rom"][j], seed["rom"][j], BANDS["rom"])
                  for j, name in enumerate(("ankle", "knee", "hip"))]
        cells += [(f"{name} max moment (N m)", f, r["mmax"][j], seed["mmax"][j], BANDS["mmax"])
                  for j, name in enumerate(("ankle", "knee"))]
    return cells


def table(results: dict, hopexo: dict) -> str:
    """Markdown tables of simulated vs published figures."""
    lines = ["| quantity | " + " | ".join(f"{f:.2f} Hz sim / seed" for f in SEED_TABLE1) + " |",
             "|---|" + "---|" * len(SEED_TABLE1)]

    def row(name, sim, pub, fmt, band=None):
        """Cells 'sim / seed (deviation)'; with a binding band, a cell outside it is marked OUT."""
        cells = []
        for s, p in zip(sim, pub):
            dev = s / p - 1.0
            mark = "" if band is None else (" OUT" if abs(dev) > band else "")
            cells.append(f"{fmt.format(s)} / {fmt.format(p)} ({dev:+.0%}){mark}")
        lines.append(f"| {name}{'' if band is None else f' [band {band:.0%}]'} | " + " | ".join(cells) + " |")

    fs = list(SEED_TABLE1)
    row("achieved hop frequency (Hz)", [results[f]["freq_hz"] for f in fs], fs, "{:.2f}")
    row("stance time (ms)", [results[f]["stance_ms"] for f in fs], [SEED_TABLE1[f]["stance_ms"] for f in fs], "{:.0f}",
        BANDS["stance"])
    row("peak GRF (BW)", [results[f]["grf_bw"] for f in fs], [SEED_TABLE1[f]["grf_bw"] for f in fs], "{:.2f}",
        BANDS["grf"])
    row("peak / mean vertical force in stance (mean = BW / (f Tc); half-sine 1.57, linear spring-mass <= 2)",
        [results[f]["grf_bw"] * results[f]["freq_hz"] * results[f]["stance_ms"] / 1000.0 for f in fs],
        [SEED_TABLE1[f]["grf_bw"] * f * SEED_TABLE1[f]["stance_ms"] / 1000.0 for f in fs], "{:.2f}")
    row("hip vertical excursion (m)", [results[f]["hip_exc_m"] for f in fs], [SEED_TABLE1[f]["hip_exc_m"] for f in fs],
        "{:.3f}", BANDS["hip_exc"])
    row("hip drop in stance against half the seed's excursion (m; Table 2's leg-stiffness reading, not binding)",
        [results[f]["hip_exc_m"] for f in fs], [SEED_TABLE1[f]["hip_exc_m"] / 2.0 for f in fs], "{:.3f}")
    row("hip vertical range over the hop cycle (m; touchdown to touchdown, not binding)",
        [results[f]["hip_range_cycle_m"] for f in fs], [SEED_TABLE1[f]["hip_exc_m"] for f in fs], "{:.3f}")
    newton = {f: newton_com_drop(f, SEED_TABLE1[f]["stance_ms"] / 1000.0, SEED_TABLE1[f]["grf_bw"])[1] for f in fs}
    row("COM drop in stance (m; sim: the analysis' from the plate; seed: Newton for its peak GRF and stance)",
        [results[f]["com_drop_m"] for f in fs], [newton[f] for f in fs], "{:.3f}")
    row("hip excursion / COM drop (sim / seed's excursion over its Newton drop)",
        [results[f]["hip_exc_m"] / results[f]["com_drop_m"] for f in fs],
        [SEED_TABLE1[f]["hip_exc_m"] / newton[f] for f in fs], "{:.2f}")
    for j, name in enumerate(("ankle", "knee", "hip")):
        row(f"{name} range of flexion (rad)", [results[f]["rom"][j] for f in fs], [SEED_TABLE1[f]["rom"][j] for f in fs],
            "{:.2f}", BANDS["rom"])
    for j, name in enumerate(("ankle", "knee", "hip")):
        row(f"{name} max moment (N m)", [results[f]["mmax"][j] for f in fs], [SEED_TABLE1[f]["mmax"][j] for f in fs],
            "{:.0f}", BANDS["mmax"] if name != "hip" else None)
    for j, name in enumerate(("ankle", "knee", "hip")):
        row(f"{name} brake-phase energy (J)", [results[f]["brake_j"][j] for f in fs],
            [SEED_TABLE1[f]["brake_j"][j] for f in fs], "{:.1f}")
    for j, name in enumerate(("ankle", "knee", "hip")):
        row(f"{name} push-phase energy (J) / seed brake (seed: push = brake)",
            [results[f]["push_j"][j] for f in fs], [SEED_TABLE1[f]["brake_j"][j] for f in fs], "{:.1f}")
    if any("fit_k0" in results[f] for f in fs):
        from hop_impedance.simulation.scenarios import SEED_TABLE2

        for c in ("k0", "k1"):
            for j, name in enumerate(("ankle", "knee", "hip")):
                row(f"{name} fitted {c} (per-stance Eq. 3 fit k0+k1+b0, median; seed Table 2)",
                    [results[f].get(f"fit_{c}", np.full(3, np.nan))[j] for f in fs],
                    [SEED_TABLE2[min(SEED_TABLE2, key=lambda t: abs(t - f))][c][j] for f in fs], "{:.0f}")
    row("leg stiffness, peak F / COM-toe compression (kN/m)", [results[f]["k_leg"] / 1000 for f in fs],
        [9.8, 14.6, 20.9], "{:.1f}")
    r = results[2.4]
    lines += ["", "| quantity (2.4 Hz) | simulated | HopExo mean (14 subjects, no exoskeleton) |", "|---|---|---|",
              f"| hop frequency (Hz) | {r['freq_hz']:.2f} | {hopexo['hz']:.2f} |",
              f"| contact time (s) | {r['stance_ms'] / 1000:.3f} | {hopexo['tc']:.3f} |",
              f"| peak vertical GRF (N) | {r['grf_n']:.0f} (54.8 kg subject, {r['grf_bw']:.2f} BW) | "
              f"{hopexo['fz']:.0f} (body mass not given; ~3 BW at ~75 kg) |"]
    for j, name in enumerate(("ankle", "knee", "hip")):
        lines.append(f"| {name} range over the hop cycle (deg) | {r['rom_cycle_deg'][j]:.1f} | {hopexo['rom_deg'][j]:.1f} |")
    for j, name in enumerate(("ankle", "knee", "hip")):
        lines.append(f"| {name} mean positive / negative power (W/kg, per leg, hop cycle) | "
                     f"{r['power_pos_w_kg'][j]:.2f} / {r['power_neg_w_kg'][j]:.2f} | "
                     f"{hopexo['power_pos_w_kg'][j]:.2f} / {hopexo['power_neg_w_kg'][j]:.2f} |")
    for j, name in enumerate(("ankle", "knee", "hip")):
        lines.append(f"| {name} mean moment (N m/kg, per leg, hop cycle; extensor +) | "
                     f"{r['moment_nm_kg'][j]:.2f} | {hopexo['moment_nm_kg'][j]:.2f} |")
    return "\n".join(lines)


#: Seed Table 2 overall leg stiffness (kN/m) at 1.53 / 1.87 / 2.20 Hz.
SEED_LEG_STIFFNESS_KN_M = {1.53: 9.8, 1.87: 14.6, 2.20: 20.9}


def newton_com_drop(freq_hz: float, stance_s: float, peak_bw: float, g: float = 9.81) -> tuple[float, float]:
    """(n, centre-of-mass drop in stance, m) for a vertical force ``F(t) ~ sin^n(pi t / Tc)`` with the given peak.

    Over one hop the ground's impulse equals the weight's (``int F dt = m g / f``); the COM lands at
    ``g (1/f - Tc) / 2`` (symmetric flight) and its lowest point in stance follows by integrating
    ``a = F/m - g`` twice. ``n`` is found so that the force peaks at ``peak_bw`` (n = 1: half-sine, ~1.57 x
    the mean force; larger n, a more peaked force and a deeper drop). The seed's Table 1 has no force
    curve, so the shape is this one-parameter family; the drop grows with the peak for any single-humped
    shape of the same impulse.
    """
    from scipy.optimize import brentq

    period = 1.0 / freq_hz
    t = np.linspace(0.0, stance_s, 4001)

    def accel(n: float) -> np.ndarray:
        shape = np.sin(np.pi * t / stance_s) ** n
        return g * period * shape / np.trapezoid(shape, t) - g  # F/m - g, up positive

    n = brentq(lambda n: accel(n).max() / g + 1.0 - peak_bw, 0.05, 20.0)
    vz = -g * (period - stance_s) / 2.0 + np.concatenate([[0.0], np.cumsum(0.5 * (accel(n)[1:] + accel(n)[:-1]) * np.diff(t))])
    z = np.concatenate([[0.0], np.cumsum(0.5 * (vz[1:] + vz[:-1]) * np.diff(t))])
    return float(n), float(-z.min())


def seed_newton_check(mass_kg: float = 54.8, g: float = 9.81) -> str:
    """What Newton's law allows for the seed's Table 1 at its own stance times and frequencies (markdown).

    Over one hop the ground's impulse equals the weight's, so the mean vertical force in stance is
    ``BW / (f Tc)``; a spring-like contact has a half-sine force (peak = pi/2 x mean) and the centre of
    mass, landing at ``g (1/f - Tc) / 2``, drops ``v th + g th^2/2 - (Fp/m)(Tc/pi)(th - Tc/pi)`` by
    mid-stance (``th = Tc/2``); a constant force (the flattest profile) gives the least drop, ``v Tc/4``.
    The last column tests the reading of Table 1's hip excursion: the seed's leg stiffness (Table 2)
    equals peak GRF over *half* the hip excursion at all three frequencies.
    """
    lines = ["| f (Hz) | seed stance (ms) | seed peak GRF (BW) | half-sine peak for that stance (BW) | "
             "COM drop, half-sine / constant force (m) | seed hip excursion (m) | seed peak GRF / (excursion/2) "
             "(kN/m) vs seed Table 2 leg stiffness | COM drop for the seed's peak GRF, sin^n force (n; m) | seed hip "
             "excursion / that drop, and half the excursion / that drop | seed max ankle / knee / hip moment over "
             "peak GRF (m) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for f, row in SEED_TABLE1.items():
        tc, period = row["stance_ms"] / 1000.0, 1.0 / f
        v = g * (period - tc) / 2.0
        th = tc / 2.0
        fp = np.pi / 2.0 * g * period / tc  # per unit mass
        drop = v * th + g * th**2 / 2.0 - fp * (tc / np.pi) * (th - tc / np.pi)
        k_half = row["grf_bw"] * mass_kg * g / (row["hip_exc_m"] / 2.0) / 1000.0
        n, drop_n = newton_com_drop(f, tc, row["grf_bw"], g)
        lines.append(f"| {f:.2f} | {row['stance_ms']} | {row['grf_bw']:.1f} | {fp / g:.2f} | {drop:.3f} / "
                     f"{v * tc / 4.0:.3f} | {row['hip_exc_m']:.2f} | {k_half:.1f} vs {SEED_LEG_STIFFNESS_KN_M[f]} | "
                     f"{n:.2f}; {drop_n:.3f} | {row['hip_exc_m'] / drop_n:.2f}, {row['hip_exc_m'] / 2.0 / drop_n:.2f} | "
                     + " / ".join(f"{m / (row['grf_bw'] * mass_kg * g):.3f}" for m in row["mmax"]) + " |")
    return "\n".join(lines)


def failed(freq_hz: float, reason: str) -> dict:
    """Placeholder figures (NaN, shown as 'nan') for a frequency whose trial could not be measured."""
    scalar = ("stance_ms", "grf_bw", "grf_n", "hip_exc_m", "com_drop_m", "hip_range_cycle_m", "k_leg", "freq_hz")
    joint = ("rom", "mmax", "brake_j", "push_j", "power_pos_w_kg", "power_neg_w_kg", "moment_nm_kg", "rom_cycle_deg")
    return {**{k: np.nan for k in scalar}, **{k: np.full(3, np.nan) for k in joint},
            "notes": [f"{freq_hz} Hz not measured: {reason}"], "n_stances": 0}


SEED_LIKE_BEGIN = "<!-- simulator_realism --seed-like table begin -->"
SEED_LIKE_END = "<!-- simulator_realism --seed-like table end -->"


def write_seed_like(text: str, newton: str, notes: list[str], setup: str) -> None:
    """``--seed-like --write``: the tables between docs/simulator.md's markers (the README's table is the default
    hopper's, whose recordings the README shows, so it is left alone)."""
    block = (f"Written by `.venv/bin/python bench/simulator_realism.py --seed-like --write` ({setup}):\n\n{text}\n\n"
             + "".join(f"- note: {n}\n" for n in notes) + "\nSeed Table 1 against Newton (no simulation):\n\n"
             + newton + "\n")
    replace_between_markers(ROOT / "docs" / "simulator.md", SEED_LIKE_BEGIN, SEED_LIKE_END, block)


def replace_between_markers(doc: Path, begin: str, end: str, block: str) -> None:
    """Put ``block`` between the lines ``begin`` and ``end`` of ``doc`` (exits if a marker is missing)."""
    body = doc.read_text()
    if begin not in body or end not in body:
        raise SystemExit(f"{doc}: no {begin} marker; nothing written")
    head, rest = body.split(begin, 1)
    _, tail = rest.split(end, 1)
    doc.write_text(head + begin + "\n" + block + end + tail)
    print(f"wrote the tables between {begin} and {end} in {doc}")


README_BEGIN = "<!-- simulator_realism table begin -->"
README_END = "<!-- simulator_realism table end -->"


#: Issue 17: each binding cell left outside its band is marked with the cause found (quantity -> cause). Only causes
#: measured by a bench are listed; a cell out for another quantity prints "cause not found".
OUT_CAUSES = {
    "hip vertical excursion (m)": (
        "with the trunk upright the hip can drop at most 1.297 x the centre of mass (dynamics.hip_over_com_drop_bound); "
        "the seed's excursion is 1.16-1.39 x the COM drop Newton gives for its own peak GRF and stance, so its hip must "
        "stand 8.5 / 11.6 mm higher at take-off than at touchdown at 1.87 / 2.2 Hz "
        "(bench/simulator_hip_excursion_bound.py), and our less peaked force (peak / mean 1.62-1.79 against 1.75-2.17) "
        "drops the centre of mass less (docs/simulator.md, sessions 11-12)"),
}


#: A maximal moment "follows the law over its range" when it is within this fraction of Table 2's law moment over
#: the simulated range (:func:`law_moment_cause`).
LAW_MOMENT_MATCH = 0.10


def table2_law_moment(freq_hz: float, joint: int, rom_rad: float) -> float:
    """The moment seed Table 2's reduced law K = k0 + k1 (rho - rho0) builds from touchdown over a range of flexion
    ``rom_rad``: k0 rom + k1 rom^2 / 2 (N m; the moment at touchdown and the damping, small in the seed, left out)."""
    k0, k1 = table2_k(freq_hz)[:, joint]
    return float(k0 * rom_rad + 0.5 * k1 * rom_rad**2)


def law_moment_cause(freq_hz: float, joint: int, mmax_nm: float, rom_rad: float) -> str | None:
    """The cause of a maximal-moment cell out of its band, if it is the seed's own tables: the simulated moment is
    what Table 2's law gives over the simulated range (within :data:`LAW_MOMENT_MATCH`), that range is inside its
    band, and the law over that range is itself out of the moment's band. The seed's Table 2 law over its own Table 1
    range already differs from its Table 1 moment (knee at 1.53 Hz +22 %), and the law grows with the square of the
    range, so a range inside its 20 % band can carry the moment past its 25 % band. None if that is not what holds."""
    seed = SEED_TABLE1[freq_hz]
    at_seed_range = table2_law_moment(freq_hz, joint, seed["rom"][joint])
    at_sim_range = table2_law_moment(freq_hz, joint, rom_rad)
    rom_dev = rom_rad / seed["rom"][joint] - 1.0
    if not (abs(mmax_nm / at_sim_range - 1.0) <= LAW_MOMENT_MATCH and abs(rom_dev) <= BANDS["rom"]
            and abs(at_sim_range / seed["mmax"][joint] - 1.0) > BANDS["mmax"]):
        return None
    return (f"{freq_hz:.2f} Hz: seed Table 2's law over seed Table 1's range ({seed['rom'][joint]:.2f} rad) gives "
            f"{at_seed_range:.0f} N m ({at_seed_range / seed['mmax'][joint] - 1.0:+.0%} against Table 1's "
            f"{seed['mmax'][joint]:.0f}: the seed's own tables disagree), over the simulated range ({rom_rad:.2f} rad, "
            f"{rom_dev:+.0%}, inside its band) {at_sim_range:.0f} N m ({at_sim_range / seed['mmax'][joint] - 1.0:+.0%}), "
            f"and the simulated maximal moment is {mmax_nm / at_sim_range - 1.0:+.0%} from that "
            f"(simulator_realism.law_moment_cause)")


#: A hip excursion "falls as the seed's relative to the centre of mass" when its ratio to the COM drop is within this
#: fraction of the seed's (:func:`hip_excursion_cause`).
HIP_OVER_COM_MATCH = 0.10


def hip_excursion_cause(freq_hz: float, result: dict) -> str | None:
    """The cause of a hip-excursion cell out of its band, if it is the centre of mass's drop: the simulated hip falls
    the same multiple of the COM drop as the seed's hip does of the COM drop Newton gives for the seed's peak GRF and
    stance (within :data:`HIP_OVER_COM_MATCH`), and the COM itself drops less than that by more than the excursion's
    band. The hip then moves as the seed's does over a shallower stance; the peak GRF that sets the drop is in its own
    band. None if that is not what holds (e.g. at 1.87 / 2.2 Hz, where the seed's ratio is above the upright trunk's
    bound: :data:`OUT_CAUSES`)."""
    seed = SEED_TABLE1[freq_hz]
    newton = newton_com_drop(freq_hz, seed["stance_ms"] / 1000.0, seed["grf_bw"])[1]
    ratio_sim, ratio_seed = result["hip_exc_m"] / result["com_drop_m"], seed["hip_exc_m"] / newton
    drop_dev = result["com_drop_m"] / newton - 1.0
    if not (abs(ratio_sim / ratio_seed - 1.0) <= HIP_OVER_COM_MATCH and drop_dev < -BANDS["hip_exc"]):
        return None
    return (f"{freq_hz:.2f} Hz: the hip falls {ratio_sim:.2f} x the centre of mass's drop, as the seed's does "
            f"({ratio_seed:.2f} x Newton's drop for its peak GRF and stance), and the centre of mass drops "
            f"{drop_dev:+.0%} against that (peak GRF {result['grf_bw'] / seed['grf_bw'] - 1.0:+.0%}, inside its band) "
            f"(simulator_realism.hip_excursion_cause)")


#: The knee's range less the hip's "matches the seed's" within this fraction (:func:`hip_range_cause`).
KNEE_LESS_HIP_MATCH = 0.10


def hip_range_cause(freq_hz: float, result: dict) -> str | None:
    """The cause of a hip range-of-flexion cell out of its band, if it is the knee's range: with the trunk upright the
    hip flexes as the thigh turns, i.e. by the knee's flexion less the shank's forward turn, so the knee's range less
    the hip's stands for the shank's (and the trunk's) turn. When that difference is the seed's (within
    :data:`KNEE_LESS_HIP_MATCH`) and the knee's range is inside its band, the hip's range is the knee's less a seed-like
    turn: a knee deviation comes to the hip multiplied by the seed's knee / hip ratio (1.9 at 1.53 Hz), so a knee in
    its band can carry the hip out of it. None if that is not what holds."""
    seed_knee, seed_hip = SEED_TABLE1[freq_hz]["rom"][1:3]
    knee, hip = float(result["rom"][1]), float(result["rom"][2])
    turn_dev = (knee - hip) / (seed_knee - seed_hip) - 1.0
    knee_dev = knee / seed_knee - 1.0
    if not (abs(turn_dev) <= KNEE_LESS_HIP_MATCH and abs(knee_dev) <= BANDS["rom"]):
        return None
    turn_extra = (knee - hip) - (seed_knee - seed_hip)
    return (f"{freq_hz:.2f} Hz: the knee's range less the hip's, the shank's and trunk's turn with the trunk upright, is "
            f"{knee - hip:.2f} rad against the seed's {seed_knee - seed_hip:.2f} ({turn_dev:+.0%}), and the knee's range "
            f"is {knee_dev:+.0%} (inside its band); x {seed_knee / seed_hip:.1f} (the seed's knee / hip ranges) that gives "
            f"{knee_dev * seed_knee / seed_hip:+.0%} at the hip, the turn's {turn_extra:+.2f} rad "
            f"{-turn_extra / seed_hip:+.0%} (simulator_realism.hip_range_cause)")


def cause_function(name: str):
    """The function that measures the cause of a binding cell out of band for quantity ``name`` (as
    :func:`binding_cells` names it): :func:`hip_excursion_cause`, :func:`hip_range_cause`, :func:`law_moment_cause`
    for a maximal moment, else None."""
    if name.startswith("hip vertical excursion"):
        return hip_excursion_cause
    if name.startswith("hip range of flexion"):
        return hip_range_cause
    return law_moment_cause if "max moment" in name else None


def cell_cause(name: str, freq_hz: float, result: dict) -> str | None:
    """The cause measured for one binding cell out of band (``result``: :func:`measure`'s figures at ``freq_hz``) by
    :func:`cause_function`'s function, or None."""
    measure = cause_function(name)
    if measure is law_moment_cause:
        joint = JOINT_NAMES.index(name.split()[0])
        return law_moment_cause(freq_hz, joint, result["mmax"][joint], result["rom"][joint])
    return None if measure is None else measure(freq_hz, result)


def out_cells(results: dict) -> list[str]:
    """One line per quantity with binding cells outside their band: the cells and the causes, measured per cell
    (:func:`cell_cause`) or, for the cells without one, the quantity's :data:`OUT_CAUSES` entry."""
    out: dict[str, list[tuple[float, float, str | None]]] = {}
    bands = {}
    for name, f, sim, seed, band in binding_cells(results):
        if np.isfinite(sim) and abs(sim / seed - 1.0) > band:
            out.setdefault(name, []).append((f, sim / seed - 1.0, cell_cause(name, f, results[f])))
            bands[name] = band
    lines = []
    for name, cells in out.items():
        causes = [c for _, _, c in cells if c]
        rest = ", ".join(f"{f:.2f} Hz" for f, _, c in cells if not c)
        if rest:
            causes.append(f"{rest}: {OUT_CAUSES[name]}" if name in OUT_CAUSES else f"{rest} not found")
        lines.append(f"- OUT {name} (band {bands[name]:.0%}) at {', '.join(f'{f:.2f} Hz {d:+.0%}' for f, d, _ in cells)}"
                     ": cause: " + "; ".join(causes))
    return lines


def measure_all(freqs: str | None, measure_one) -> dict:
    """``measure_one(f)`` at each seed frequency and 2.4 Hz (only those in ``freqs``, '1.53,2.2', if given); a trial
    that fails (e.g. no calibrated hop) is reported by :func:`failed` instead."""
    wanted = None if freqs is None else [float(v) for v in freqs.split(",")]
    results = {}
    for f in (*SEED_TABLE1, 2.4):
        if wanted is not None and not any(abs(f - w) < 1e-6 for w in wanted):
            results[f] = failed(f, "not asked for (--freqs)")
            continue
        try:
            results[f] = measure_one(f)
        except ValueError as exc:  # e.g. no calibrated hop, or a trial that stops before a second stance
            results[f] = failed(f, str(exc))
    return results


def preset_changed(args: argparse.Namespace) -> bool:
    """Whether the command line changes ``--hopper``'s preset: a flag that acts on it only, or ``--flight`` /
    ``--push-timing`` with ``--hopper`` (without it they vary the other hoppers)."""
    only_preset = (args.push_weights, args.law_scale_file, args.trunk_gains, args.landing, args.push_off_gain is not None,
                   args.passive_landing is not None)
    return bool(any(only_preset) or args.hopper and (args.flight != "prescribed" or args.push_timing))


def run_hopper(args: argparse.Namespace) -> tuple[dict, str]:
    """``--hopper seed-like``: the realism figures of the package's preset on its surface, and the setup line;
    ``--push-weights`` / ``--law-scale-file`` change the preset as bench/simulator_issue17.py's same flags do,
    ``--trunk-gains K,B`` as its ``--trunk K,B``, ``--flight energy_keeping`` as its ``--flight``, and ``--push-timing`` /
    ``--landing`` as its same flags."""
    options, variant = seed_like_hopper_options(), ""
    flight = None if args.flight == "prescribed" else args.flight
    gain = args.push_off_gain
    if preset_changed(args):
        import simulator_issue17 as s17  # a bench next to this one, which imports this one: not at the top

        options, _ = s17.variant_options(s17.VariantArgs(hopper="seed-like", surface=SEED_LIKE_HOPPER_SURFACE,
                                                         law_scale="none", push_weights=args.push_weights,
                                                         law_scale_file=args.law_scale_file, trunk=args.trunk_gains,
                                                         flight=flight, push_timing=args.push_timing,
                                                         landing=args.landing, push_off_gain=gain,
                                                         passive_landing=args.passive_landing))
        variant = "".join(f" with {name} {value}" for name, value in (
            ("push-off weights", args.push_weights), ("push-off timing", args.push_timing),
            ("trunk balance", args.trunk_gains), ("flight", flight), ("landing", args.landing),
            ("push-off gain", None if gain is None else f"{gain:g}"),
            ("passive landing (s)", None if args.passive_landing is None else f"{args.passive_landing:g}"),
            ("the law Table 2 x", args.law_scale_file)) if value)
    results = measure_all(args.freqs, lambda f: measure_hopper(f, options, SEED_LIKE_HOPPER_SURFACE, args.hops,
                                                                         fits=args.fits))
    setup = (f"scenarios.seed_like_hopper_options() (the hopper of the bundled Table 1 recordings){variant} on the "
             f"{SEED_LIKE_HOPPER_SURFACE} plate with its shoe pad, "
             f"{min(r['n_stances'] for r in results.values())}-{max(r['n_stances'] for r in results.values())} "
             "analysed stances per frequency")
    return results, setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true",
                        help="write docs/simulator_realism.md and the seed table between the README's markers")
    parser.add_argument("--trunk", action="store_true", help="with the trunk-balance moment (scenarios.TRUNK_BALANCE)")
    parser.add_argument("--flight", default="prescribed", choices=FLIGHT_MODELS)
    parser.add_argument("--posture", default=None,
                        help="touchdown ankle rho1, knee flexion, hip flexion (rad), e.g. 1.6,0.8,0.5; "
                             "default scenarios.DEFAULT_TOUCHDOWN_RHO")
    parser.add_argument("--contact", default="marker", choices=("marker", "toe_tip"),
                        help="ground contact at the toe marker (default) or at the tip of the toe, the seed's "
                             "virtual hinge (scenarios.toe_tip_ahead_m)")
    parser.add_argument("--seed-like", action="store_true",
                        help="issue 17's candidate: scenarios.seed_like_options (toe-tip contact, its touchdown posture, "
                             "trunk balance, late push-off); overrides --trunk and --contact (--posture, --push-timing "
                             "then vary it)")
    parser.add_argument("--push-timing", default=None,
                        help="push-off onset, duration as fractions of the passive stance, e.g. 0.4,0.4 (after --seed-like; "
                             "with --hopper: instead of the preset's 0.6,0.8, not with --write)")
    parser.add_argument("--landing", choices=LANDINGS, default=None,
                        help="with --hopper --flight energy_keeping or trunk_held: land along the take-off rates reversed "
                             "(default) or along the prescribed flight's own landing motion (simulator_issue17.py's flag); "
                             "not with --write")
    parser.add_argument("--push-off-gain", type=float, default=None, metavar="G",
                        help="with --hopper: the hop-by-hop push-off controller's gain as a fraction of its deadbeat one "
                             "(simulator_issue17.py's flag; default 1); not with --write")
    parser.add_argument("--passive-landing", type=float, default=None, metavar="S",
                        help="with --hopper: the flight's last S s as the free chain with zero joint moments "
                             "(simulator_issue17.py's flag; HoppingConfig.passive_landing_s); not with --write")
    parser.add_argument("--bell", type=float, default=None, metavar="A_MIN",
                        help="the bell activation from A_MIN at touchdown over the passive stance "
                             "(hopping_config bell_activation_min; --seed-like: scenarios.SEED_LIKE_BELL_MIN, 0.7; "
                             "1 = no bell)")
    parser.add_argument("--fit-law", action="store_true",
                        help="with --seed-like: simulate the law whose per-stance fit returns Table 2 "
                             "(scenarios.SEED_LIKE_LAW_SCALE x Table 2) instead of Table 2 itself")
    parser.add_argument("--activation", action="store_true",
                        help="with the time-based activation of the elastic moment (scenarios.ACTIVATION, Effects)")
    parser.add_argument("--fits", action="store_true",
                        help="also the per-stance Eq. 3 fits (k0, k1, b0) that analyze adds, medians against Table 2")
    parser.add_argument("--freqs", default=None,
                        help="measure only these of 1.53,1.87,2.2,2.4 (the others print as nan; not with --write)")
    parser.add_argument("--hopper", choices=("seed-like",), default=None,
                        help="the package's preset scenarios.seed_like_hopper_options() on its rigid plate (the hopper "
                             "of the bundled Table 1 recordings since session 14); the other hopper flags are ignored; "
                             "with --write its table goes into the README and docs/simulator_realism.md")
    parser.add_argument("--push-weights", metavar="A,K,H",
                        help="with --hopper: the push-off's shares per joint (simulator_issue17.py's flag), not with --write")
    parser.add_argument("--law-scale-file", metavar="PATH",
                        help="with --hopper: the law Table 2 x PATH's factors (simulator_issue17_search.py --save)")
    parser.add_argument("--trunk-gains", metavar="K,B",
                        help="with --hopper: the trunk balance's stiffness and damping instead of the preset's 500,60 "
                             "(simulator_issue17.py's --trunk); not with --write")
    parser.add_argument("--hops", type=int, default=TABLE1_TRIAL_HOPS,
                        help=f"the trials' hops (default {TABLE1_TRIAL_HOPS}, TABLE1_TRIAL_HOPS); another count is printed, "
                             "not written")
    args = parser.parse_args()
    if args.write and args.hops != TABLE1_TRIAL_HOPS:
        parser.error(f"--write writes the {TABLE1_TRIAL_HOPS}-hop trials' table only (TABLE1_TRIAL_HOPS)")
    if args.hops < 3:
        parser.error("--hops: at least 3 (the stances after the first are averaged)")
    if args.hopper and (args.seed_like or args.freqs and args.write):
        parser.error("--hopper is the preset: not with --seed-like, and --write not with --freqs")
    if preset_changed(args) and (not args.hopper or args.write):
        parser.error("--push-weights, --law-scale-file, --trunk-gains, --landing, --push-off-gain, --passive-landing and "
                     "(with --hopper) --flight and --push-timing change --hopper's preset, and are not written")
    if args.hopper:
        t0 = time.perf_counter()
        results, setup = run_hopper(args)
        report(args, results, setup, t0)
        return
    contact = toe_tip_ahead_m() if args.contact == "toe_tip" else 0.0
    posture = DEFAULT_TOUCHDOWN_RHO
    push_timing = PUSH_OFF_TIMING
    if args.posture:
        a, k, h = (float(v) for v in args.posture.split(","))
        posture = (a, np.pi + k, np.pi + h)
    bell_override = None
    law_scale = None
    if args.seed_like:
        opts = seed_like_options()
        args.trunk, contact, posture, push_timing = True, opts["contact_ahead_m"], opts["touchdown_rho_rad"], opts["push_timing"]
        bell_override, args.bell = args.bell, opts["bell_activation_min"] if args.bell is None else args.bell
        law_scale = SEED_LIKE_LAW_SCALE if args.fit_law else None
    if args.bell == 1.0:  # a(t) = 1: no bell (and room for --activation)
        args.bell = None
        args.contact = "toe_tip"
    if args.push_timing:
        push_timing = tuple(float(v) for v in args.push_timing.split(","))
    if args.posture and args.seed_like:  # a posture trial on the seed-like hopper
        a, k, h = (float(v) for v in args.posture.split(","))
        posture = (a, np.pi + k, np.pi + h)
    if args.write and (args.freqs or args.push_timing or args.activation or (args.posture and args.seed_like)
                       or (args.seed_like and bell_override is not None) or args.fit_law):
        parser.error("--write writes the chosen configuration only: not with --freqs, --push-timing, --activation, "
                     "or --posture / --bell with --seed-like")
    t0 = time.perf_counter()
    effects = Effects(time_activation=args.activation)
    results = measure_all(args.freqs, lambda f: measure(
        f, args.hops, trunk=args.trunk, flight=args.flight, posture=posture, contact_ahead_m=contact, push_timing=push_timing,
        effects=effects, bell_activation_min=args.bell, fits=args.fits, law_scale=law_scale))
    setup = (f"{'with' if args.trunk else 'without'} trunk balance, {args.flight} flight, touchdown posture "
             f"ankle {posture[0]:.2f}, knee {posture[1] - np.pi:.2f}, hip {posture[2] - np.pi:.2f} rad, "
             f"ground contact {'at the toe marker' if not contact else f'{contact:.3f} m ahead of the toe marker (toe tip)'}, "
             f"push-off from {push_timing[0]:.0%} for {push_timing[1]:.0%} of the passive stance, "
             f"{'time-based activation, ' if args.activation else ''}"
             f"{'' if args.bell is None else f'bell activation from {args.bell:g} at touchdown, '}"
             f"{'' if law_scale is None else 'law: Table 2 x scenarios.SEED_LIKE_LAW_SCALE (its fit returns Table 2), '}"
             f"{min(r['n_stances'] for r in results.values())}-{max(r['n_stances'] for r in results.values())} "
             "analysed stances per frequency")
    report(args, results, setup, t0)


def report(args: argparse.Namespace, results: dict, setup: str, t0: float) -> None:
    """Print the tables, the out-of-band cells with their causes and the notes; ``--write`` writes them."""
    text = table(results, hopexo_means())
    notes = [n for f in results for n in results[f]["notes"]]
    causes = out_cells(results)
    print(text)
    newton = seed_newton_check()
    print("\nSeed Table 1 against Newton (the seed's own figures, no simulation):\n" + newton)
    print("\n".join(causes))
    for n in notes:
        print("note:", n)
    print(f"({setup}; measured in {time.perf_counter() - t0:.0f} s)")
    if args.write and args.seed_like:
        write_seed_like(text, newton, notes, setup)
    elif args.write:
        write_tables(args, text, newton, notes, causes, setup)


def write_tables(args: argparse.Namespace, text: str, newton: str, notes: list[str], causes: list[str], setup: str) -> None:
    """``--write``: docs/simulator_realism.md and the seed rows between the README's markers."""
    command = ("--hopper seed-like" if args.hopper else
               f"{' --trunk' if args.trunk else ''}{'' if args.flight == 'prescribed' else ' --flight ' + args.flight}"
               f"{' --posture ' + args.posture if args.posture else ''}"
               f"{'' if args.contact == 'marker' else ' --contact ' + args.contact}").strip()
    doc = ROOT / "docs" / "simulator_realism.md"
    doc.write_text(
        "# Simulator realism\n\nProduced by `.venv/bin/python bench/simulator_realism.py --write"
        f"{' ' + command if command else ''}`; "
        "every simulated figure is measured by the analysis (`hop-impedance analyze`: stance detection and 2D "
        "inverse dynamics from the recorded markers and force plate) on noise-free simulated recordings "
        f"({setup}; subject 54.8 kg, 1.63 m; mean of the complete stances after the first of a "
        f"{TABLE1_TRIAL_HOPS}-hop trial). "
        "Cells read *simulated / published (deviation)*; OUT marks a cell outside issue 17's binding band "
        "(stance time, peak GRF, hip excursion 15 %; ranges of flexion 20 %; ankle and knee maximal moments 25 %), "
        "and each OUT cell is listed under the table with the cause found. "
        "Range of flexion = maximal rho in stance minus rho at touchdown. "
        "Brake/push-phase energy: integral of the negative/positive joint power P = -M drho/dt over the stance. "
        "The seed's brake energies are about half of what its own moments and ranges imply for a spring-like joint "
        "(ankle 1.53 Hz: 0.5 x 233 N m x 0.85 rad = 99 J against 51.8 J), so they are probably per leg while its "
        "moments are both legs (as ours are); read the simulated energies against twice the seed's.\n\n"
        + text + "\n\n" + "\n".join(causes) + ("\n\n" if causes else "")
        + "\n".join(f"- note: {n}" for n in notes) + "\n\n"
        "## Seed Table 1 against Newton\n\n"
        "The seed's own stance time and frequency fix the mean force in stance (impulse = weight x period); "
        "a spring-like (half-sine) force then has the peak and the centre-of-mass drop below, a constant force "
        "the least drop. At 2.2 Hz the seed's 3.5 BW is 1.38 x the half-sine peak of its own 282 ms stance, so "
        "stance time and peak GRF cannot both sit near the seed's means for a spring-like leg. The seed's "
        "Table 2 leg stiffness is its peak GRF over half its hip excursion, but Newton rules out reading the "
        "excursion as twice the leg compression: half of it is 0.58-0.69 x the COM drop that the seed's own "
        "peak GRF and stance time imply (sin^n column), so the binding cell reads it as the hip's range in "
        "stance (this bench's docstring). (`seed_newton_check` in this bench.)\n\n" + newton + "\n"
    )
    print(f"wrote {doc}")
    readme = ROOT / "README.md"
    body = readme.read_text()
    if README_BEGIN in body and README_END in body:
        seed_rows = "\n".join(row for row in text.split("\n\n")[0].splitlines() if "energy" not in row)
        head, rest = body.split(README_BEGIN, 1)
        _, tail = rest.split(README_END, 1)
        block = seed_rows + ("\n\n" + "\n".join(causes) if causes else "")
        readme.write_text(head + README_BEGIN + "\n" + block + "\n" + README_END + tail)
        print(f"wrote the table in {readme}")
    else:
        print(f"{readme}: no {README_BEGIN} marker; README not changed")

if __name__ == "__main__":
    main()
