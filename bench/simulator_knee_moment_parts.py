"""The knee's maximal moment split into the simulator's law parts (issue 17, session 30).

At 1.53 Hz the analysis' knee maximal moment of the trunk-held variants is +22..+64 % over seed Table 1's 96.8 N m
(band 25 %). This bench simulates one noise-free 10-hop trial of the variant given by bench/simulator_issue17.py's
flags (``add_variant_arguments``), analyses it as ``hop-impedance analyze`` does, and prints per stance after the
first (the stances the criteria average), from the truth file's samples:

- the simulator's net knee moment at its maximum and its parts there: the Eq. 3 law's elastic part (its
  ``k0 dr`` and ``k1 dr^2 / 2`` terms times the bell activation a(t), and any k2 / k3 term), its damping
  (``b0 dw`` and the rest of Eq. 3's B terms), its touchdown moment m0, the push-off's knee share, the passive
  knee-ankle spring's knee moment (``samples.biarticular_moments_nm``) and what is left (net minus those; zero
  unless a part is missing here);
- the same parts' means over the stance;
- the knee's flexion from touchdown to its maximum (truth and analysis) against seed Table 1's 0.70 rad, and
  seed Table 2's reduced law over that range (``simulator_realism.table2_law_moment``: what the fitted law, which
  the law search returns to Table 2, builds over the range);
- the analysis' maximal knee moment of the same stance (inverse dynamics from markers and plate: the Table 1 cell's
  input).

Then the means over the stances and the excess of each over 1.25 x 96.8 N m. The Eq. 3 part is recomputed from the
stance's coefficients (``impedance``, ``activation``) and checked against ``samples.eq3_moments_nm`` (largest
difference printed).

Usage::

    .venv/bin/python bench/simulator_knee_moment_parts.py --hopper seed-like --surface rigid --flight trunk_held \\
        --landing prescribed --push-off-gain 0.5 --passive-landing 0.08 --push-weights 1,0.3,0.3 \\
        --biarticular 35 --law-scale-file LAW.json [--freq 1.53] [--seed 1]

About 30 s a trial on this machine.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (a bench next to this one)
from simulator_realism import SEED_TABLE1, table2_law_moment  # noqa: E402

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.simulation.impedance_laws import BellActivation, TimeActivation  # noqa: E402
from hop_impedance.simulation.sensors import SensorConfig, noise_free  # noqa: E402
from hop_impedance.simulation.simulate import simulate_recording  # noqa: E402

KNEE = 1
#: The parts printed, in order (N m, extensor positive).
PARTS = ("net", "k0 term", "k1 term", "k2/k3", "damping", "m0", "push-off", "spring", "rest")


def activation_values(stance: dict, t_s: np.ndarray) -> np.ndarray:
    """The Eq. 3 elastic part's activation a(t) along the stance (1 without one); ``t_s`` since touchdown."""
    act = stance.get("activation")
    if not act:
        return np.ones_like(t_s)
    law = BellActivation(**act) if "duration_s" in act else TimeActivation(**act)
    return law.value(t_s)


def knee_parts(stance: dict) -> tuple[dict, float]:
    """The knee moment's parts along one truth stance (:data:`PARTS` -> array) and the largest difference (N m)
    between the recomputed Eq. 3 part and the truth's ``eq3_moments_nm``."""
    sm, c = stance["samples"], stance["impedance"]["knee"]
    t = np.asarray(sm["t_s"], float) - stance["touchdown_s"]
    rho, omega = np.asarray(sm["rho_rad"], float)[:, KNEE], np.asarray(sm["omega_rad_s"], float)[:, KNEE]
    dr, dw = rho - c["rho0_rad"], omega - c["omega0_rad_s"]
    rate = dw * omega  # dS/dt of Eq. 3's k3 / b3 state, zero at touchdown
    s = np.concatenate(([0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))))
    a = activation_values(stance, t)
    parts = {
        "net": np.asarray(sm["moments_nm"], float)[:, KNEE],
        "k0 term": a * c["k0"] * dr,
        "k1 term": a * c["k1"] * dr**2 / 2,
        "k2/k3": a * (c["k2"] * dr**3 / 3 + c["k3"] * s),
        "damping": c["b0"] * dw + c["b1"] * dw**2 / 2 + c["b2"] * dw**3 / 3 + c["b3"] * (dr * dw - s),
        "m0": np.full_like(t, c["m0"]),
        "push-off": np.asarray(sm["push_off_moments_nm"], float)[:, KNEE],
        "spring": (np.asarray(sm["biarticular_moments_nm"], float)[:, KNEE] if "biarticular_moments_nm" in sm
                   else np.zeros_like(t)),
    }
    eq3 = sum(parts[p] for p in ("k0 term", "k1 term", "k2/k3", "damping", "m0"))
    parts["rest"] = parts["net"] - eq3 - parts["push-off"] - parts["spring"]
    parts["flexion"] = dr
    parts["ankle flexion"] = np.asarray(sm["rho_rad"], float)[:, 0] - stance["impedance"]["ankle"]["rho0_rad"]
    parts["activation"] = a
    mismatch = float(np.max(np.abs(eq3 - np.asarray(sm["eq3_moments_nm"], float)[:, KNEE])))
    return parts, mismatch


def measured_stances(analysis) -> list:
    """The analysis' complete stances with joint data after the first (the criteria's)."""
    return [s for s in analysis.stances if s.complete and s.joints is not None][1:]


def nearest_truth(truth: dict, touchdown_s: float) -> dict:
    """The truth stance whose touchdown is nearest the analysis' (both in seconds of recording time)."""
    return min(truth["stances"], key=lambda st: abs(st["touchdown_s"] - touchdown_s))


def stance_row(measured, stance: dict, freq_hz: float) -> dict:
    """One stance's figures: the parts at the simulator's knee maximum and their means, the ranges, the analysis'."""
    parts, mismatch = knee_parts(stance)
    k = int(np.argmax(parts["net"]))
    angle = measured.joints.angle_rad[:, KNEE]
    rom_truth = float(parts["flexion"].max())
    c, seed_rom = stance["impedance"]["knee"], SEED_TABLE1[freq_hz]["rom"][KNEE]
    return {
        "index": stance["index"] + 1,
        "at_max": {p: float(parts[p][k]) for p in PARTS},
        "mean": {p: float(np.mean(parts[p])) for p in PARTS},
        "when": float(k / max(len(parts["net"]) - 1, 1)),
        "flexion_at_max": float(parts["flexion"][k]),
        "ankle_at_max": float(parts["ankle flexion"][k]),
        "spring_least": (float(parts["spring"].min()), float(np.argmin(parts["spring"]) / max(len(parts["net"]) - 1, 1))),
        "activation_at_max": float(parts["activation"][k]),
        "rom_truth": rom_truth,
        "rom_analysis": float(angle.max() - angle[0]),
        "analysis_max": float(measured.joints.moment_nm[:, KNEE].max()),
        "law_over_range": table2_law_moment(freq_hz, KNEE, rom_truth),
        # the stance's own Eq. 3 elastic part (activation at the maximum) had the knee flexed seed Table 1's range
        "own_law_at_seed_range": float(parts["activation"][k] * (c["k0"] * seed_rom + c["k1"] * seed_rom**2 / 2)),
        "mismatch": mismatch,
    }


def row_line(r: dict) -> str:
    """One stance as text."""
    at = ", ".join(f"{p} {r['at_max'][p]:+6.1f}" for p in PARTS)
    mean = ", ".join(f"{p} {r['mean'][p]:+5.1f}" for p in PARTS)
    return (f"stance {r['index']}: at the knee maximum ({r['when']:.2f} of stance, flexion {r['flexion_at_max']:+.3f} "
            f"rad, a {r['activation_at_max']:.3f}): {at}\n"
            f"    stance means: {mean}\n"
            f"    knee range touchdown -> maximal flexion: truth {r['rom_truth']:.3f}, analysis {r['rom_analysis']:.3f} rad; "
            f"Table 2 law over it {r['law_over_range']:.1f} N m; analysis' maximal moment {r['analysis_max']:.1f} N m; "
            f"Eq. 3 recomputed vs truth {r['mismatch']:.2g} N m\n"
            f"    ankle flexion at the knee maximum {r['ankle_at_max']:+.3f} rad; the spring's least knee moment "
            f"{r['spring_least'][0]:+.1f} N m at {r['spring_least'][1]:.2f} of stance")


def summary_lines(rows: list[dict], freq_hz: float) -> list[str]:
    """Means over the stances, against seed Table 1's knee (its moment, the band's top, its range)."""
    seed = SEED_TABLE1[freq_hz]
    top = 1.25 * seed["mmax"][KNEE]
    lines = [f"means over {len(rows)} stances (seed Table 1 knee: {seed['mmax'][KNEE]:.1f} N m, band top {top:.1f}; "
             f"range {seed['rom'][KNEE]:.2f} rad):"]
    at = {p: float(np.mean([r["at_max"][p] for r in rows])) for p in PARTS}
    mean = {p: float(np.mean([r["mean"][p] for r in rows])) for p in PARTS}
    lines.append("  at the knee maximum: " + ", ".join(f"{p} {v:+.1f}" for p, v in at.items()))
    lines.append("  stance means:        " + ", ".join(f"{p} {v:+.1f}" for p, v in mean.items()))
    analysis_max = float(np.mean([r["analysis_max"] for r in rows]))
    rom = float(np.mean([r["rom_truth"] for r in rows]))
    rom_a = float(np.mean([r["rom_analysis"] for r in rows]))
    law = table2_law_moment(freq_hz, KNEE, rom_a)
    lines.append(f"  simulator's net maximum {at['net']:.1f} N m ({at['net'] / seed['mmax'][KNEE] - 1:+.0%}), the analysis' "
                 f"{analysis_max:.1f} N m ({analysis_max / seed['mmax'][KNEE] - 1:+.0%}; over the band's top "
                 f"{analysis_max - top:+.1f} N m); knee / ankle flexion at it {np.mean([r['flexion_at_max'] for r in rows]):.3f}"
                 f" / {np.mean([r['ankle_at_max'] for r in rows]):.3f} rad, "
                 f"a {np.mean([r['activation_at_max'] for r in rows]):.3f}")
    lines.append(f"  knee range: truth {rom:.3f} rad ({rom / seed['rom'][KNEE] - 1:+.0%}), analysis {rom_a:.3f} rad "
                 f"({rom_a / seed['rom'][KNEE] - 1:+.0%}); Table 2's law over the analysis' range {law:.1f} N m "
                 f"({law / seed['mmax'][KNEE] - 1:+.0%}), over seed Table 1's "
                 f"{table2_law_moment(freq_hz, KNEE, seed['rom'][KNEE]):.1f} N m; the stances' own Eq. 3 elastic part "
                 f"over seed Table 1's range {np.mean([r['own_law_at_seed_range'] for r in rows]):.1f} N m")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--freq", type=float, default=1.53, help="the trial's target frequency (Hz; default 1.53)")
    parser.add_argument("--seed", type=int, default=1, help="the trial's seed (default 1)")
    parser.add_argument("--hops", type=int, default=10, help="hops in the trial (default 10, the criteria's)")
    args = s17.VariantArgs(**vars(parser.parse_args()))  # a variant flag this bench does not define reads as not given
    t0 = time.perf_counter()
    options, said = s17.variant_options(args)
    print(f"{said}; {args.freq:g} Hz, seed {args.seed}, noise-free {args.hops} hops")
    rec, truth = simulate_recording(args.freq, args.surface, args.hops, seed=args.seed,
                                    sensors=noise_free(SensorConfig()), **options)
    analysis = analyze_recording(rec)
    rows = [stance_row(m, nearest_truth(truth, m.touchdown_s), args.freq) for m in measured_stances(analysis)]
    print("\n".join([row_line(r) for r in rows] + summary_lines(rows, args.freq)))
    knee_law = truth["stances"][-1]["impedance"]["knee"]
    push = truth["stances"][-1].get("push_off") or {"amplitude_nm": [0.0] * 3}
    print(f"the last stance's knee law: k0 {knee_law['k0']:.1f} N m/rad, k1 {knee_law['k1']:.1f} N m/rad^2, b0 "
          f"{knee_law['b0']:.2f} N m s/rad; push-off amplitude (ankle, knee, hip) "
          + ", ".join(f"{v:.1f}" for v in push["amplitude_nm"]) + " N m")
    print(f"stopped: {truth['stop_reason']}" if truth["stop_reason"] else "all hops made")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
