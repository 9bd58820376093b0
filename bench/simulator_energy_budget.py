"""Where the simulated hopper's energy goes, hop by hop (issue 4: why the push-off is as large as it is).

For each hop of a noise-free hard-surface trial with the default law (seed
Table 2 k0, k1; b0 = 0.5 N m s/rad; push-off), mechanical energy E = kinetic +
gravitational of the four segments (J):

- ``push-off``   work of the active push-off moment on the body, int -M_push omega dt;
- ``damping``    energy the Eq. 3 law's damping (b0) dissipates, int b0 omega^2 dt;
- ``springs``    elastic energy left in the joint springs at take-off,
  U = k0 d^2/2 + k1 d^3/6 with d = rho(take-off) - rho0, summed over joints;
  the law is referenced to the touchdown angle, so this energy does not come
  back to the next stance;
- ``ground``     work of the surface law on the foot, int Fz dz_toe/dt dt
  (the hard law dissipates through its damping; its spring is unloaded at take-off);
- ``flight``     E(next touchdown) - E(take-off): the prescribed flight
  (hopping_trial.py docstring) keeps the COM ballistic but brings the segments
  to the next touchdown posture, so the kinetic energy of segment motion
  relative to the COM at take-off is discarded.

Check: E(take-off) - E(touchdown) = push-off - damping - springs + ground (the
horizontal no-slip constraint does no work); the residual is printed.

Push-off timing is printed as fractions of the actual stance: onset, peak and
end of the sin^2 pulse, and the instant of maximal ankle flexion.

Usage: .venv/bin/python bench/simulator_energy_budget.py [--hops 5] [--freqs 1.53,1.87,2.2] [--write]
(``--write`` also writes docs/simulator_energy.md.)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hop_impedance.simulation.dynamics import mechanical_energy_j
from hop_impedance.simulation.hopping_trial import push_off_part, simulate_hopping, simulate_resample
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import hopping_config

DT_S = 1e-4
ROOT = Path(__file__).resolve().parents[1]


def _eq3_part(law) -> Eq3Law:
    return law if isinstance(law, Eq3Law) else law.part(Eq3Law)


def _energy(chain, g, gd) -> float:
    kinetic, potential = mechanical_energy_j(chain, g, gd)
    return kinetic + potential


def stance_budget(chain, rec) -> dict:
    """Energy terms (J) of one stance record (see module docstring)."""
    t = np.arange(0.0, rec.stance.duration_s, DT_S)
    t = np.append(t, rec.stance.duration_s)
    st = simulate_resample(chain, rec, t)
    eq3, push = _eq3_part(rec.law), push_off_part(rec.law)
    if eq3.k2.any() or eq3.k3.any() or eq3.b1.any() or eq3.b2.any() or eq3.b3.any() or eq3.activation is not None:
        raise ValueError("the budget is written for the default law (k0, k1, b0, push-off)")
    omega = st.omega_rad_s
    push_power = -(push.profile(t)[:, None] * push.amplitude_nm * omega).sum(axis=1) if push else np.zeros_like(t)
    d = st.rho_rad[-1] - st.rho_rad[0]
    toe_vz = st.gd[:, 1]
    duration = rec.stance.duration_s
    return {
        "push_onset": push.onset_s / duration if push else np.nan,
        "push_peak": (push.onset_s + push.duration_s / 2) / duration if push else np.nan,
        "push_end": (push.onset_s + push.duration_s) / duration if push else np.nan,
        "ankle_max_flexion": float(t[np.argmax(st.rho_rad[:, 0])] / duration),
        "push_off": float(np.trapezoid(push_power, t)),
        "damping": float(np.trapezoid((eq3.b0 * omega**2).sum(axis=1), t)),
        "springs": float(np.sum(eq3.k0 * d**2 / 2 + eq3.k1 * d**3 / 6)),
        "ground": float(np.trapezoid(st.grf_n[:, 1] * toe_vz, t)),
        "e_touchdown": _energy(chain, st.g[0], st.gd[0]),
        "e_takeoff": _energy(chain, st.g[-1], st.gd[-1]),
    }


def trial_budget(freq_hz: float, hops: int, seed: int = 1) -> list[dict]:
    """Per-hop budgets of a hard-surface trial; the flight term needs the next touchdown, so the last hop has none."""
    chain, config = hopping_config(freq_hz, "hard", hops)
    trial = simulate_hopping(chain, config, seed=seed)
    rows = [stance_budget(chain, rec) for rec in trial.stances]
    for row, nxt in zip(rows[:-1], rows[1:]):
        row["flight"] = nxt["e_touchdown"] - row["e_takeoff"]
    return rows[:-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hops", type=int, default=5)
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    parser.add_argument("--write", action="store_true", help="also write docs/simulator_energy.md")
    args = parser.parse_args()
    lines = ["| frequency (Hz) | push-off work | damping | springs left at take-off | ground | flight | "
             "stance balance residual |", "|---|---|---|---|---|---|---|"]
    timing = ["| frequency (Hz) | push-off onset | push-off peak | push-off end | ankle max flexion |",
              "|---|---|---|---|---|"]
    for freq in (float(f) for f in args.freqs.split(",")):
        rows = trial_budget(freq, args.hops)[1:]  # the first hop starts from the calibrated state
        mean = {k: np.mean([r[k] for r in rows]) for k in rows[0]}
        residual = max(abs(r["e_takeoff"] - r["e_touchdown"] - (r["push_off"] - r["damping"] - r["springs"] + r["ground"]))
                       for r in rows)
        lines.append(f"| {freq:.2f} | {mean['push_off']:.1f} J | -{mean['damping']:.1f} J | -{mean['springs']:.1f} J | "
                     f"{mean['ground']:.1f} J | {mean['flight']:.1f} J | {residual:.2f} J |")
        timing.append(f"| {freq:.2f} | {mean['push_onset']:.0%} | {mean['push_peak']:.0%} | {mean['push_end']:.0%} | "
                      f"{mean['ankle_max_flexion']:.0%} |")
    caption = f"(mean of hops 2-{args.hops - 1}; noise-free, hard surface, default law; fractions of the actual stance)"
    text = "\n".join(lines) + "\n\n" + "\n".join(timing) + "\n\n" + caption
    print(text)
    if args.write:
        doc = ROOT / "docs" / "simulator_energy.md"
        doc.write_text("# Simulator energy budget and push-off timing\n\nProduced by "
                       "`.venv/bin/python bench/simulator_energy_budget.py --write`; the terms are defined in "
                       "that script's docstring.\n\n" + text + "\n")
        print(f"wrote {doc}")

if __name__ == "__main__":
    main()
