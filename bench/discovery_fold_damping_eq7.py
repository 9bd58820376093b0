"""Does the damping law identified in discovery keep seed 000's Eq. 7 (B >= 0) on the stances it is judged on?

Session 16, findings only (the method is unchanged). Session 15's sweep at 2.2 Hz missed our simulator's damping
case because in the held-out stiffness gate 3 of 8 stances of the damping candidate blew up (per-stance gaps 515863,
338, 17). Here: one recording of a case of ``bench/discovery_hit_rates.py`` (default ``joint_damping``, seed 0, 2.2
Hz, 8 hops), the table body (the sweep's document chose fraction 0.0), and per fold of the held-out gate (2 folds,
position k held out in fold k % 2; plus all stances) the damping model identified by regression on the training
stances (as ``stiffness_gate.shoot_held_out`` does, k0 not shot), then per held-out stance and joint the damping
``B = dM/domega = b0 + b1 (omega - omega0)`` along the measured omega and along the forward-simulated one (its
minimum and the share of samples with B < 0), the stance's simulated end and its held-out gap. K = k0 > 0 here.

``--eq7-fit``: the same with ``identify.EQ7_FIT`` on (the law identified subject to Eq. 7 on the training stances'
samples; session 16, second helper), set in this process: run with ``PYTHONPATH=<this checkout>``.

Usage: .venv/bin/python bench/discovery_fold_damping_eq7.py [--case joint_damping] [--seed 0] [--freq 2.2] [--eq7-fit]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import discovery_hit_rates as hr  # noqa: E402

from hop_impedance.discovery import forward_selection as fs  # noqa: E402
from hop_impedance.discovery import identify as identify_module  # noqa: E402
from hop_impedance.discovery.forward import ground_of  # noqa: E402
from hop_impedance.discovery.identify import identify, per_stance_push_off, touchdown_moments  # noqa: E402
from hop_impedance.discovery.measurement import measure_trial  # noqa: E402
from hop_impedance.discovery.model import FittedLaw, ModelSpec, feature_names  # noqa: E402
from hop_impedance.discovery.stiffness_gate import fold_indices  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default="joint_damping")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--freq", type=float, default=2.2)
    ap.add_argument("--eq7-fit", action="store_true", help="identify.EQ7_FIT = True (the law fitted subject to Eq. 7)")
    args = ap.parse_args()
    identify_module.EQ7_FIT = args.eq7_fit
    rec, freq = hr.generate(args.case, args.seed, 8, freqs=(args.freq,))
    trial = measure_trial(rec)
    scales = fs.gap_scales(trial)
    base = ModelSpec(body_fraction=0.0)
    order = [s.index for s in trial.stances]
    print(f"{args.case} seed {args.seed} f={freq}: stances {order}, EQ7_FIT {identify_module.EQ7_FIT}")
    for label, train, test in [("all", tuple(order), tuple(order))] + [
            (f"fold {k}", tr, te) for k, (tr, te) in enumerate(fold_indices(order, 2))]:
        spec, coefs = identify(base, trial, [s for s in trial.stances if s.index in train], "joint_damping")
        names = feature_names(spec)
        print(f"\n{label}: trained on {train}, judged on {test}")
        for j, joint in enumerate(("ankle", "knee", "hip")):
            print(f"  {joint}: " + ", ".join(f"{n} {c:.3g}" for n, c in zip(names, coefs[j])))
        ib0, ib1 = names.index("b0"), names.index("b1")
        b_train = np.concatenate([coefs[:, ib0] + coefs[:, ib1] * (s.omega_rad_s - s.omega_rad_s[0])
                                  for s in trial.stances if s.index in train])
        print(f"  training samples: min B {np.round(b_train.min(0), 4)}, share B<0 {np.round((b_train < 0).mean(0), 3)}")
        for i in test:
            s = next(x for x in trial.stances if x.index == i)
            b_meas = coefs[:, ib0] + coefs[:, ib1] * (s.omega_rad_s - s.omega_rad_s[0])
            c = per_stance_push_off(spec, coefs, s)
            law = FittedLaw(spec, np.asarray(c, float), touchdown_moments(spec, c, s), fs.identification_reference(s))
            try:
                sim = fs.simulate_for_gap(trial.chain, law, ground_of(spec, s), s)
            except RuntimeError as exc:
                sim_text = f"simulation failed: {exc}"
            else:
                b_sim = coefs[:, ib0] + coefs[:, ib1] * (sim.omega_rad_s - s.omega_rad_s[0])
                gap = fs._gap_of(sim, s, spec.offset_n, scales, np.nan)["gap"]
                sim_text = (f"simulated: min B {np.round(b_sim.min(0), 2)}, share B<0 {np.round((b_sim < 0).mean(0), 2)}, "
                            f"{sim.end_reason} at {sim.t_s[-1]:.3f} s (measured {s.t_s[-1]:.3f} s), gap {gap:.4g}")
            print(f"  stance {i}: measured: min B {np.round(b_meas.min(0), 2)}, share B<0 "
                  f"{np.round((b_meas < 0).mean(0), 2)} | {sim_text}")


if __name__ == "__main__":
    main()
