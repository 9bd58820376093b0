"""What sets the hip's initial stiffness in seed Fig. 7 (issue 17, session 23): the hip moment at touchdown per stance.

Seed Fig. 7 plots the mean maximal against the mean initial stiffness (K at touchdown, the fitted k0) of each joint
and frequency. Under the energy-keeping flight the 1.53 Hz hip point has an initial K near 0 (bench/simulator_fig7.py
--simulate), so this bench prints, for one noise-free 10-hop trial of the variant given by bench/simulator_issue17.py's
flags, per stance after the first:

- the analysis' per-stance fit of the seed's k0, k1, b0 (``fit_calibration.seed_model_fits``) at the hip, its initial
  and maximal K (the Fig. 7 point's inputs), and at ankle and knee for comparison;
- the analysis' hip moment at touchdown and 20 ms later (inverse dynamics from markers and plate);
- the simulator's own hip moment at touchdown and the trunk balance's part of it (truth file samples), and the hip
  rate there.

Usage::

    .venv/bin/python bench/simulator_hip_touchdown.py --hopper seed-like --surface rigid [--freq 1.53]
    .venv/bin/python bench/simulator_hip_touchdown.py --hopper seed-like --surface rigid --flight energy_keeping \\
        --landing prescribed --push-weights 1,-0.1,0.3 --push-off-gain 0.5 --law-scale-file LAW.json

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

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.simulation.fit_calibration import seed_model_fits  # noqa: E402
from hop_impedance.simulation.sensors import SensorConfig, noise_free  # noqa: E402
from hop_impedance.simulation.simulate import simulate_recording  # noqa: E402

JOINTS = ("ankle", "knee", "hip")


def fit_lines(analysis) -> list[str]:
    """Per stance after the first: k0, k1, b0, initial and maximal K of the seed model's fit, every joint."""
    lines = []
    for i, fits in enumerate(seed_model_fits(analysis)):
        cells = []
        for j in JOINTS:
            c = fits[j].coefficients
            cells.append(f"{j} k0 {c['k0']:5.0f} k1 {c['k1']:6.0f} b0 {c['b0']:5.1f} K {fits[j].initial_stiffness:4.0f}"
                         f" -> {fits[j].max_stiffness:4.0f}")
        lines.append(f"stance {i + 2}: " + " | ".join(cells))
    return lines


def measured_after_first(analysis) -> list:
    """The analysis' complete stances with joint data, after the first (it lands from the lead-in)."""
    return [s for s in analysis.stances if s.complete and s.joints is not None][1:]


def moment_lines(analysis, truth: dict) -> list[str]:
    """Per stance after the first: the analysis' hip moment at touchdown and +20 ms, the simulator's and its balance part."""
    lines = []
    measured = measured_after_first(analysis)
    for i, s in enumerate(measured):
        m = s.joints.moment_nm[:, 2]
        k = int(np.searchsorted(s.joints.time_s, 0.02))
        lines.append(f"stance {i + 2} (analysis): hip moment at touchdown {m[0]:6.1f} N m, +20 ms {m[k]:6.1f}, "
                     f"maximal {m.max():5.1f}; hip rate at touchdown {s.joints.angular_velocity_rad_s[0, 2]:+.2f} rad/s")
    for st in truth["stances"][1:]:
        sm = st["samples"]
        m, balance = np.asarray(sm["moments_nm"], float), np.asarray(sm["trunk_balance_moments_nm"], float)
        lines.append(f"stance {st['index'] + 1} (simulator): hip moment at touchdown {m[0, 2]:6.1f} N m, of it the trunk "
                     f"balance {balance[0, 2]:6.1f}; hip rate {np.asarray(sm['omega_rad_s'], float)[0, 2]:+.2f} rad/s")
    return lines


def path_lines(analysis) -> list[str]:
    """Per stance after the first (``--path``): knee and hip angle relative to touchdown (rad) at the hip's maximal
    moment, its least and largest value in stance and at take-off, and the hip's maximal moment (analysis)."""
    lines = []
    measured = measured_after_first(analysis)
    for i, s in enumerate(measured):
        d = s.joints.angle_rad - s.joints.angle_rad[0]
        peak = int(np.argmax(s.joints.moment_nm[:, 2]))
        cells = [f"{name} at hip peak {d[peak, j]:+.3f}, range {d[:, j].min():+.3f}..{d[:, j].max():+.3f}, "
                 f"take-off {d[-1, j]:+.3f}" for name, j in (("knee", 1), ("hip", 2))]
        lines.append(f"stance {i + 2} (path): " + " | ".join(cells) +
                     f" | hip peak {s.joints.moment_nm[peak, 2]:.1f} N m at {s.joints.time_s[peak] / s.joints.time_s[-1]:.2f}"
                     " of stance")
    return lines


def _spring_cells(samples: dict) -> str:
    """The biarticular spring's ankle and knee moments (N m) at the stance's middle and at take-off, when present."""
    if "biarticular_moments_nm" not in samples:
        return ""
    m = np.asarray(samples["biarticular_moments_nm"], float)
    mid = m[len(m) // 2]
    return (f"; spring ankle, knee mid-stance {mid[0]:+.1f}, {mid[1]:+.1f}, take-off {m[-1, 0]:+.1f}, {m[-1, 1]:+.1f}"
            f" N m, least knee {m[:, 1].min():+.1f}, largest {m[:, 1].max():+.1f}")


def part_lines(truth: dict) -> list[str]:
    """Per stance after the first (``--path``): the simulator's hip moment at its maximum and its parts there (push-off,
    trunk balance, the rest = Eq. 3 hip law), the hip's push-off peak, the stance's energy budget (J) and the joint
    rates at take-off (the trunk-held flight lands along them reversed, ``hopping_trial.flight_segment_rates``)."""
    lines = []
    for st in truth["stances"][1:]:
        sm, e = st["samples"], st["energy_j"]
        hip = np.asarray(sm["moments_nm"], float)[:, 2]
        push = np.asarray(sm["push_off_moments_nm"], float)[:, 2]
        balance = np.asarray(sm["trunk_balance_moments_nm"], float)[:, 2]
        k = int(np.argmax(hip))
        left = e.get("biarticular_left_j")
        lines.append(f"stance {st['index'] + 1} (simulator): hip max {hip[k]:5.1f} N m = push-off {push[k]:5.1f} + "
                     f"balance {balance[k]:5.1f} + law {hip[k] - push[k] - balance[k]:5.1f}; hip push-off peak "
                     f"{push.max():5.1f}; push-off {e['push_off_j']:5.1f} J, damping {e['damping_j'] or 0:5.1f}, springs left "
                     f"{e['springs_left_j'] or 0:5.1f}" + ("" if left is None else f", spring left {left:5.1f}") +
                     f", flight {e.get('flight_j', float('nan')):6.1f}; rates at take-off (rad/s) ankle, knee, hip "
                     + ", ".join(f"{w:+.2f}" for w in np.asarray(sm["omega_rad_s"], float)[-1])
                     + _spring_cells(sm) + _knee_push_cell(st))
    return lines


def _knee_push_cell(stance: dict) -> str:
    """The knee's push-off impulse (N m s) inside the stance against its whole window's (``A (1 - lag) T / 2``): how much
    of a (lagged, session 28) knee push acts before take-off."""
    push = stance.get("push_off")
    if not push or push["amplitude_nm"][1] == 0:
        return ""
    sm = stance["samples"]
    inside = float(np.trapezoid(np.asarray(sm["push_off_moments_nm"], float)[:, 1], np.asarray(sm["t_s"], float)))
    lag = push.get("lag_fraction", [0.0, 0.0, 0.0])[1]
    whole = push["amplitude_nm"][1] * (1.0 - lag) * push["duration_s"] / 2.0
    return f"; knee push in stance {inside:+.2f} of {whole:+.2f} N m s"


def landing_from_law(args, options: dict, law_file: str) -> tuple[float, ...]:
    """Segment rates at hop 2's touchdown (rad/s) of the same variant with ``law_file``'s law and no spring
    (``--landing-from-law``): used as ``landing_rates_rad_s``, every landing of the probed trial goes along them."""
    from hop_impedance.simulation.hopping_trial import simulate_hopping
    from hop_impedance.simulation.scenarios import hopping_config

    other = {k: v for k, v in options.items() if k != "biarticular"}
    other["law_scale"] = s17.read_law_scale(law_file)
    chain, config = hopping_config(args.freq, args.surface, 3, **other)
    trial = simulate_hopping(chain, config, seed=args.seed)
    return tuple(float(v) for v in trial.stances[1].touchdown.gd[2:])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--freq", type=float, default=1.53, help="the trial's target frequency (Hz; default 1.53)")
    parser.add_argument("--seed", type=int, default=1, help="the trial's seed (default 1)")
    parser.add_argument("--landing-from-law", metavar="LAW.json", default=None,
                        help="land every hop along the touchdown segment rates of this law's trial without the spring "
                             "(HoppingConfig.landing_rates_rad_s; session 27's probe: does the landing alone move the "
                             "hip's fit?)")
    parser.add_argument("--path", action="store_true", help="also the knee and hip angle paths relative to touchdown "
                        "(session 27: what the hip's fit sees with the biarticular spring)")
    parser.set_defaults(seed001_keep_pad=False)  # variant_options' --pad line reads it
    args = parser.parse_args()
    t0 = time.perf_counter()
    options, said = s17.variant_options(args)
    if args.landing_from_law:
        options["landing_rates_rad_s"] = landing_from_law(args, options, args.landing_from_law)
        said += f", landing along {args.landing_from_law}'s hop-2 touchdown rates " + \
            ", ".join(f"{v:+.2f}" for v in options["landing_rates_rad_s"])
    print(f"{said}; {args.freq:g} Hz, seed {args.seed}, noise-free 10 hops")
    rec, truth = simulate_recording(args.freq, args.surface, 10, seed=args.seed, sensors=noise_free(SensorConfig()),
                                    **options)
    analysis = analyze_recording(rec)
    extra = path_lines(analysis) + part_lines(truth) if args.path else []
    print("\n".join(fit_lines(analysis) + moment_lines(analysis, truth) + extra))
    print(f"stopped: {truth['stop_reason']}" if truth["stop_reason"] else "all hops made")
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
