"""The knee's K(t) bell at take-off: the hopper or the analysis? (issue 17, session 13)

simulator_issue17.py's bell row fails at the knee because the fitted K(t) = k0 + k1 (rho - rho0) reaches the QP's
K >= 0 bound at take-off. Per stance after the first of one noise-free 10-hop trial per frequency (seed 1, the variant
flags of bench/simulator_issue17.py), this prints the true knee's take-off minus touchdown angle (rad, from the
simulator), the law's k0 / k1 (where its K reaches zero), the stance time and the stance's push-off (ankle amplitude,
onset, work), and the K(t) shape (``simulator_issue17.bell_shape_failure``)
of two fits with k0, k1, b0: the truth's own (the simulator's noise-free knee moment on the true angle,
``simulation.whole_hip.stance_hip_fit(joint=1)``) and the analysis' (markers and force plate, as the bell row).
Stances are matched by touchdown (within 20 ms).

Usage::

    nice -n 19 .venv/bin/python bench/simulator_knee_bell.py --bell 0.9 \\
        --law-scale bell09_rigid_pad15_3_push06_08_trunk500_60 --surface rigid --pad 15,3 --push-timing 0.6,0.8 --trunk 500,60
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import simulator_issue17 as s17  # noqa: E402  (a bench next to this one)

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.impedance.recording_fits import fit_recording_trial, given_structure  # noqa: E402
from hop_impedance.simulation.sensors import SensorConfig, noise_free  # noqa: E402
from hop_impedance.simulation.simulate import simulate_recording  # noqa: E402
from hop_impedance.simulation.whole_hip import stance_hip_fit  # noqa: E402

KNEE = 1
MATCH_S = 0.02


def shape(fit) -> str:
    """'bell (K take-off N)' or the failure, of a fit's K(t)."""
    if not fit.ok:
        return f"rejected ({fit.rejection_reason})"
    why = s17.bell_shape_failure(fit.stiffness)
    return f"bell (take-off {fit.stiffness[-1]:.3g})" if not why else why


def frequency_lines(freq_hz: float, options: dict, surface: str) -> list[str]:
    """One frequency's stances (module docstring)."""
    rec, truth = simulate_recording(freq_hz, surface, 10, seed=1, sensors=noise_free(SensorConfig()), **options)
    analysis = analyze_recording(rec)
    structure = given_structure(("k0", "k1", "b0"), "knee bell bench")
    fits = fit_recording_trial(analysis, structures={j: structure for j in ("ankle", "knee", "hip")}).fits
    lines = []
    for true in truth["stances"][1:]:
        rho = np.asarray(true["samples"]["rho_rad"], float)[:, KNEE]
        law = true["impedance"]["knee"]
        found = [i for i, s in enumerate(analysis.stances) if abs(s.touchdown_s - true["touchdown_s"]) < MATCH_S]
        analysed = shape(fits[found[0]]["knee"]) if found else "not analysed"
        push = true["push_off"] or {"amplitude_nm": [np.nan] * 3, "onset_s": np.nan}
        lines.append(f"  {freq_hz:4.2f} Hz stance {true['index']}: knee take-off - touchdown {rho[-1] - rho[0]:+.3f} rad "
                     f"(law k0/k1 {law['k0'] / law['k1']:.3f}; stance {1000 * true['duration_s']:.0f} ms, push-off ankle "
                     f"{push['amplitude_nm'][0]:.0f} N m from {1000 * push['onset_s']:.0f} ms, "
                     f"{true['energy_j']['push_off_j']:.1f} J); truth's fit: {shape(stance_hip_fit(true, joint=KNEE))}; "
                     f"analysis: {analysed}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    s17.add_variant_arguments(parser)
    parser.add_argument("--freqs", default="1.87,2.2")
    args = parser.parse_args()
    options, said = s17.variant_options(s17.VariantArgs(**vars(args)))
    print(f"variant: {said}", flush=True)
    for f in s17.floats(args.freqs):
        try:
            print("\n".join(frequency_lines(f, options, args.surface)), flush=True)
        except ValueError as exc:
            print(f"{f:4.2f} Hz: no trial ({exc})", flush=True)


if __name__ == "__main__":
    main()
