"""Can the hip spring be calibrated so that the whole hip law's Eq. 3 fit returns Table 2? (issue 17, session 13)

The seed's Table 2 hip values were fitted to its subjects' whole hip moments, which include whatever kept their
trunks upright. Our hopper's whole hip moment is the Eq. 3 hip spring + the push-off + the trunk balance; its
reference is the Eq. 3 fit of the truth's noise-free whole hip moment on the true hip angle
(:mod:`hop_impedance.simulation.whole_hip`). This bench scales the hip column of the variant's law (factors on
Table 2's hip k0 and k1, ``--hip-scale K0F,K1F`` at every frequency, or found per frequency by
``fit_calibration.next_scale``, the rule ``--law-scale`` used for ankle and knee, with ``--calibrate N`` steps)
and prints per frequency, on one noise-free 10-hop trial (seed 1):

- the whole hip law's median k0 / k1 (stances after the first) against Table 2, and the medians of the fits of its
  parts alone (Eq. 3 spring, push-off, balance: the fit is a projection, so they about add up);
- what the analysis returns at ankle, knee and hip (the calibration's fit k0, k1, b0, median);
- the Table 1 cells of ``bench/simulator_realism.py`` (hip range of flexion and hip maximal moment, the hip
  excursion, ankle and knee) and the binding cells out at that frequency.

``--lever`` prints instead, per frequency, what sets the hip's maximal moment: the trunk's pitch and the HAT's centre
of mass ahead of the hip at peak GRF (the simulator's own state, stances after the first, means), the HAT's share of
the peak GRF times that lever, the hip's maximal net moment, and the lever the seed's Table 1 implies (its hip maximal
moment over the HAT's share of its peak GRF).

Usage (the variant flags of bench/simulator_issue17.py)::

    nice -n 19 .venv/bin/python bench/simulator_whole_hip.py --bell 0.9 \\
        --law-scale bell09_rigid_pad15_3_push06_08_trunk500_60 --surface rigid --pad 15,3 --push-timing 0.6,0.8 \\
        --trunk 500,60 [--hip-scale 0.5,0.5] [--calibrate 5] [--freqs 2.2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (benches next to this one)
from simulator_realism import SEED_TABLE1, binding_cells, summarise  # noqa: E402

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.simulation.fit_calibration import median_k0_k1, next_scale, seed_model_fits, table2_k  # noqa: E402
from hop_impedance.simulation.sensors import SensorConfig, noise_free  # noqa: E402
from hop_impedance.simulation.simulate import simulate_recording  # noqa: E402
from hop_impedance.simulation.whole_hip import BAND, HIP, HIP_PARTS, hip_parts_fits, whole_hip_reference  # noqa: E402


def law_scale_with_hip(options: dict, freq_hz: float, hip: np.ndarray) -> dict:
    """The variant's law scale (2, 3) at ``freq_hz`` (ones without one) with the hip column set to ``hip`` (k0, k1)."""
    scale = np.ones((2, 3))
    if options.get("law_scale") is not None:
        scale = np.array(options["law_scale"][freq_hz], float).reshape(2, 3).copy()
    scale[:, HIP] = hip
    return {**options, "law_scale": {freq_hz: scale}}


def measure(freq_hz: float, options: dict, hip: np.ndarray, surface: str) -> dict:
    """One noise-free 10-hop trial with the hip factors ``hip``: the whole law's medians, its parts', the fits, Table 1."""
    rec, truth = simulate_recording(freq_hz, surface, 10, seed=1, sensors=noise_free(SensorConfig()),
                                    **law_scale_with_hip(options, freq_hz, hip))
    pooled = whole_hip_reference(truth)["pooled"]
    parts = [hip_parts_fits(s) for s in truth["stances"][1:]]
    part_medians = {k: np.median([[p[k].coefficients[c] for c in ("k0", "k1")] for p in parts if p[k].ok], axis=0)
                    for k in HIP_PARTS}
    analysis = analyze_recording(rec)
    return {"whole": np.array([pooled["k0"]["median"], pooled["k1"]["median"]]), "parts": part_medians,
            "fitted": median_k0_k1(seed_model_fits(analysis)), "realism": summarise(freq_hz, rec, truth, analysis=analysis)}


def report(freq_hz: float, hip: np.ndarray, m: dict) -> str:
    """One frequency's lines."""
    t2, seed = table2_k(freq_hz), SEED_TABLE1[freq_hz]
    dev = m["whole"] / t2[:, HIP] - 1.0
    r = m["realism"]
    out = [cell for cell in binding_cells({freq_hz: r}) if abs(cell[2] / cell[3] - 1.0) > cell[4]]
    parts = ", ".join(f"{k.split('_moments')[0]} {v[0]:.0f} / {v[1]:.0f}" for k, v in m["parts"].items())
    fitted = " ".join(f"{j} {m['fitted'][0, i]:.0f}/{m['fitted'][1, i]:.0f}" for i, j in enumerate(("ankle", "knee", "hip")))
    return (f"{freq_hz:4.2f} Hz hip factors {hip[0]:.3f} / {hip[1]:.3f}: whole hip law k0 {m['whole'][0]:.0f} k1 "
            f"{m['whole'][1]:.0f} vs Table 2 {t2[0, HIP]:.0f} / {t2[1, HIP]:.0f} ({100 * dev[0]:+.0f} / {100 * dev[1]:+.0f} %, "
            f"{'within' if np.all(np.abs(dev) <= BAND) else 'outside'} {100 * BAND:.0f} %); parts alone: {parts}\n"
            f"          analysed (median k0/k1): {fitted}; hip range {r['rom'][HIP]:.3f} vs {seed['rom'][HIP]:.2f} rad "
            f"({100 * (r['rom'][HIP] / seed['rom'][HIP] - 1):+.0f} %), hip max moment {r['mmax'][HIP]:.0f} vs "
            f"{seed['mmax'][HIP]:.0f} N m ({100 * (r['mmax'][HIP] / seed['mmax'][HIP] - 1):+.0f} %), hip excursion "
            f"{100 * (r['hip_exc_m'] / seed['hip_exc_m'] - 1):+.0f} %; binding cells out: "
            + ("none" if not out else "; ".join(f"{c[0]} {100 * (c[2] / c[3] - 1):+.0f} %" for c in out)))


def calibrate(freq_hz: float, options: dict, start: np.ndarray, steps: int, surface: str) -> None:
    """``next_scale``'s steps on the hip column, the whole hip law's medians as the fit (prints each step)."""
    target = table2_k(freq_hz)
    hip, history = start.copy(), []
    for _ in range(steps):
        try:
            m = measure(freq_hz, options, hip, surface)
        except ValueError as exc:  # no periodic hop with this hip: half the step back, as calibrate_law_scale does
            print(f"{freq_hz:4.2f} Hz hip factors {hip[0]:.3f} / {hip[1]:.3f}: no trial ({exc})", flush=True)
            if not history:
                return
            hip = np.sqrt(hip * history[-1][0][:, HIP])
            continue
        print(report(freq_hz, hip, m), flush=True)
        whole = np.tile(m["whole"][:, None], (1, 3))
        history.append((np.tile(hip[:, None], (1, 3)), whole))
        ratio = target[:, HIP] / m["whole"]
        if np.all(np.abs(1.0 / ratio - 1.0) <= BAND):
            return
        if np.any(ratio <= 0):  # a fitted k0 or k1 of the other sign than Table 2's: no multiplicative step reaches it
            ratio = np.where(ratio <= 0, 1.0 / 2.25, ratio)
        hip = next_scale(history, target, HIP, ratio)


def lever(freq_hz: float, options: dict, surface: str) -> str:
    """``--lever``: one frequency's trunk pitch, HAT lever and hip moment at peak GRF (module docstring)."""
    from hop_impedance.simulation.dynamics import joint_positions, segment_com_positions
    from hop_impedance.simulation.hopping_trial import simulate_hopping
    from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects, hopping_config

    chain, config = hopping_config(freq_hz, surface, 10, Effects(), **options)
    trial = simulate_hopping(chain, config, seed=1)
    share = chain.mass_kg[3] / float(np.sum(chain.mass_kg))
    rows = []
    for rec in trial.stances[1:]:
        st = rec.stance
        i = int(np.argmax(st.grf_n[:, 1]))
        ahead = segment_com_positions(chain, st.g[i])[3, 0] - joint_positions(chain, st.g[i])[3, 0]
        rows.append((np.degrees(st.g[i, 5]), ahead, st.grf_n[i, 1], st.moments_nm[:, HIP].max()))
    pitch, ahead, grf, m_hip = np.mean(rows, axis=0)
    seed = SEED_TABLE1[freq_hz]
    seed_lever = seed["mmax"][HIP] / (share * seed["grf_bw"] * SEED_SUBJECT.body_weight_n)
    return (f"{freq_hz:4.2f} Hz: trunk {pitch:.1f} deg from the horizontal at peak GRF, HAT centre of mass {100 * ahead:.1f} cm "
            f"ahead of the hip; HAT share {share:.3f} x peak GRF {grf:.0f} N x lever = {share * grf * ahead:.0f} N m "
            f"against the hip's maximal moment {m_hip:.0f} N m; the seed's {seed['mmax'][HIP]:.1f} N m at {seed['grf_bw']:g} BW "
            f"implies a lever of {100 * seed_lever:.1f} cm")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--hip-scale", default="1,1", metavar="K0F,K1F", help="factors on Table 2's hip k0, k1 [1,1]")
    parser.add_argument("--calibrate", type=int, default=0, metavar="N", help="N calibration steps per frequency")
    parser.add_argument("--freqs", default="1.53,1.87,2.2")
    parser.add_argument("--lever", action="store_true", help="what sets the hip's maximal moment, per frequency")
    args = parser.parse_args()
    options, said = s17.variant_options(s17.VariantArgs(**vars(args)))
    hip = np.array(s17.floats(args.hip_scale, 2), float)
    print(f"variant: {said}", flush=True)
    t0 = time.perf_counter()
    for f in s17.floats(args.freqs):
        if args.lever:
            print(lever(f, law_scale_with_hip(options, f, hip), args.surface), flush=True)
        elif args.calibrate:
            calibrate(f, options, hip, args.calibrate, args.surface)
        else:
            try:
                print(report(f, hip, measure(f, options, hip, args.surface)), flush=True)
            except ValueError as exc:  # no periodic hop with this variant: one line, no traceback
                print(f"{f:4.2f} Hz: no trial ({exc})", flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
