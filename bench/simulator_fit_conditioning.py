"""Why the seed-like hopper's per-stance Eq. 3 fit is ill-conditioned at 1.53 Hz (issue 17), measured per frequency.

Usage::

    nice -n 10 .venv/bin/python bench/simulator_fit_conditioning.py                # seed_like_options, Table 2 law
    nice -n 10 .venv/bin/python bench/simulator_fit_conditioning.py --bell 0.85

On the noise-free 6-hop trial the law calibration uses (seed 1, hard surface; ``fit_calibration.seed_model_fits``:
the k0 + k1 + b0 fit of the stances after the first), per frequency and joint (ankle, knee):

- the stance-to-stance spread of the fitted k0 and k1 (min / median / max) and the median relative standard
  error of k0 (the fit's own ``std_errors``);
- the collinearity of the fit's two stiffness regressors: the correlation of ``rho - rho0`` with
  ``(rho - rho0)^2`` over the stance (1 when the joint only flexes from touchdown: k0 and k1 then explain the same
  shape) and the variance inflation factor of k0 (the fit's diagnostics);
- the push-off against the spring: its work per stance (truth ``energy_j.push_off_j``, min / max over the stances
  after the first) and its peak moment over the Eq. 3 moment's peak (truth samples, median); and how much the
  per-hop push-off controller (``hopping_trial._hop_push_scale``: the calibrated scale corrected towards a seeded
  target touchdown speed, sd 2 %) moves the push-off for a 2 % touchdown-speed error: 0.02 x speed /
  (d speed / d scale) over the calibrated scale (truth ``calibration``);
- the sensitivity the calibration has to invert: the same trial with that joint's law k0 10 % larger, and the
  change of the fitted median k0 and k1 over the law's 10 % (an elasticity; ``--step``).
"""

from __future__ import annotations

import argparse

import numpy as np

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.simulation.fit_calibration import median_k0_k1, seed_model_fits
from hop_impedance.simulation.scenarios import seed_like_options
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.simulate import simulate_recording

JOINTS = ("ankle", "knee")


def trial(freq_hz: float, options: dict, scale: np.ndarray, hops: int):
    """The recording's truth and seed-model fits with the law Table 2 x ``scale`` (2, 3)."""
    rec, truth = simulate_recording(freq_hz, "hard", hops, seed=1, sensors=noise_free(SensorConfig()),
                                    law_scale={freq_hz: scale}, **options)
    return truth, seed_model_fits(analyze_recording(rec))


def spread(values) -> str:
    v = np.asarray(values, float)
    return f"{v.min():.0f} / {np.median(v):.0f} / {v.max():.0f}"


def conditioning(freq_hz: float, options: dict, hops: int, step: float) -> list[str]:
    """Table rows for one frequency (module docstring)."""
    base = np.ones((2, 3))
    truth, fits = trial(freq_hz, options, base, hops)
    stances = truth["stances"][1:]
    push_j = [s["energy_j"]["push_off_j"] for s in stances]
    cal = truth["calibration"]
    gain = cal["d_speed_d_scale"]
    controller = 0.02 * cal["speed_m_s"] / gain / cal["push_scale"] if gain > 0 else np.nan
    rows = []
    fitted = median_k0_k1(fits)
    for j, name in enumerate(JOINTS):
        k0 = [f[name].coefficients["k0"] for f in fits]
        k1 = [f[name].coefficients["k1"] for f in fits]
        rse = np.median([f[name].std_errors["k0"] / abs(f[name].coefficients["k0"]) for f in fits])
        corr = np.median([np.corrcoef(f[name].angle_rad - f[name].rho0, (f[name].angle_rad - f[name].rho0) ** 2)[0, 1]
                          for f in fits])
        vif = np.median([f[name].diagnostics.variance_inflation_factors[0] for f in fits if f[name].diagnostics])
        ratio = np.median([np.abs(np.array(s["samples"]["push_off_moments_nm"])[:, j]).max()
                           / np.abs(np.array(s["samples"]["eq3_moments_nm"])[:, j]).max() for s in stances])
        bumped = base.copy()
        bumped[0, j] *= 1.0 + step
        try:
            _, fits_b = trial(freq_hz, options, bumped, hops)
            moved = median_k0_k1(fits_b)[:, j] / fitted[:, j] - 1.0
            elasticity = f"{moved[0] / step:+.1f} / {moved[1] / step:+.1f}"
        except ValueError as exc:  # the bumped law does not hop
            elasticity = f"no hop ({exc})"
        rows.append(f"| {freq_hz:g} | {name} | {spread(k0)} | {spread(k1)} | {100 * rse:.0f} | {corr:.3f} | {vif:.1f} | "
                    f"{min(push_j):.1f} / {max(push_j):.1f} | {100 * controller:.0f} | {ratio:.2f} | {elasticity} |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bell", type=float, default=None, metavar="A_MIN", help="the bell's floor (1: no bell)")
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    parser.add_argument("--hops", type=int, default=6)
    parser.add_argument("--step", type=float, default=0.1, help="relative change of the law's k0 for the elasticity")
    args = parser.parse_args()
    options = seed_like_options()
    if args.bell is not None:
        options["bell_activation_min"] = None if args.bell >= 1.0 else args.bell
    print("| f (Hz) | joint | fitted k0 min / median / max (N m/rad) | fitted k1 min / median / max | median SE(k0)/k0 (%) "
          "| median corr(dr, dr^2) | median VIF(k0) | push-off work per stance min / max (J) "
          "| push-off change for a 2 % speed error (%) | push-off peak / Eq. 3 "
          f"peak | d fitted (k0 / k1) per d law k0 ({args.step:.0%} step, elasticity) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for f in (float(v) for v in args.freqs.split(",")):
        for row in conditioning(f, options, args.hops, args.step):
            print(row, flush=True)
    print(f"(seed_like_options, bell a_min {options['bell_activation_min']}, law Table 2, noise-free {args.hops}-hop trials)")


if __name__ == "__main__":
    main()
