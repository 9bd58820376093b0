"""Why the held-out stiffness gate does not name the outside angle law (1201): per stance and per channel.

For one recording: the baseline (constant K) and the angle-law candidate, each identified and its k0 shot through the
simulation on the training stances of the held-out gate's folds (:func:`stiffness_gate.shoot_held_out`, the default
gate), and each held-out stance simulated with its fold's parameters. Printed per stance: the gap's ten terms
(GRF, 3 angles, 3 moments, duration, work, flight; each ``term / 10`` so that they sum to ``G_i``) for both models,
the log ratio the gate's t-test sees, their mean / SD / t / p; with ``--truth DIR`` the truth's per-hop law simulated
the same way (``bench/discovery_truth_gap.py``'s ``estimated`` touchdown moment).

Usage: PYTHONPATH=. .venv/bin/python bench/discovery_angle_channels.py REC.mcap [--truth ../shared/foreign]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import stats

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import stiffness_gate as sg
from hop_impedance.discovery.body_nuisance import choose_body
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec, feature_names
from hop_impedance.discovery.workflow import _measured_trial
from hop_impedance.io.recording_io import load_recording

TERMS = ("grf", "ang_a", "ang_k", "ang_h", "mom_a", "mom_k", "mom_h", "dur", "work", "flight")


def channel_terms(run: dict) -> np.ndarray:
    """The ten terms of one run's gap (each /10: they sum to ``gap``), from its scaled samples and signed terms."""
    if run["samples"] is None:
        return np.full(10, np.nan)
    return np.r_[np.mean(run["samples"] ** 2, axis=0), run["terms"] ** 2] / 10.0


def held_out_channels(ev: fs.HeldOutEvaluator, spec_fit: ModelSpec, shot: sg.HeldOutShot) -> np.ndarray:
    """Per stance (evaluator order) the ten terms with the parameters of the fold that held it out."""
    trial = fs.trial_for(spec_fit)
    order = [s.index for s in ev.trial.stances]
    out = np.full((len(order), 10), np.nan)
    col = feature_names(spec_fit).index("k0")
    for f, test in zip(shot.folds, shot.held_out):
        train = [s for s in trial.stances if s.index not in test]
        _, coefs = identify(spec_fit, trial, train)
        coefs = coefs.copy()
        coefs[:, col] *= f.factors
        runs = ev.stance_residuals(spec_fit, [coefs], test)[0]
        for i, r in zip(test, runs):
            out[order.index(i)] = channel_terms(r)
    return out


def truth_channels(rec, trial, folder: Path, name: str) -> np.ndarray:
    """The truth's per-hop law simulated on every stance as a candidate is (bench/discovery_truth_gap.py)."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from discovery_truth_gap import STRICT_GROUND, fitted_law, trial_clock_ns, true_touchdown_moment, truth_hop, truth_law

    truth = json.loads((folder / f"{name}.truth.json").read_text())
    clock_ns = trial_clock_ns(rec, trial)  # the trial's zero (the latency-shifted first stamp)
    out = []
    for s in trial.stances:
        hop = truth_hop(truth, clock_ns, s)
        spec, coefs = truth_law(hop)
        law = fitted_law("estimated", spec, coefs, true_touchdown_moment("estimated", truth, hop, s, clock_ns,
                                                                         spec, coefs), s)
        try:
            sim = fs.simulate_for_gap(trial.chain, law, STRICT_GROUND, s)
            out.append(channel_terms(fs._gap_of(sim, s, 0.0, fs.gap_scales(trial), np.nan, True)))
        except RuntimeError:
            out.append(np.full(10, np.nan))
    return np.array(out)


def show(label: str, terms: np.ndarray) -> None:
    print(f"{label}: per stance G_i and terms ({' '.join(TERMS)})")
    for i, t in enumerate(terms):
        print(f"  {i}: G {np.sum(t):.5f} | " + " ".join(f"{x:.5f}" for x in t))
    print(f"  mean G {np.mean(np.sum(terms, axis=1)):.5f} | " + " ".join(f"{x:.5f}" for x in np.mean(terms, axis=0)))


def _recording(name: str, hops: int):
    if not name.startswith("strict:"):
        return load_recording(name)
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from discovery_hit_rates import STRICT_CASES

    from hop_impedance.validation.strict_generator import strict_recording

    _, case, seed = name.split(":")
    return strict_recording(replace(STRICT_CASES[case], seed=int(seed), hops=hops))[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording", help="REC.mcap, or strict:CASE:SEED (second generator, --hops hops)")
    ap.add_argument("--truth", default="", help="folder of the truth files (outside recordings)")
    ap.add_argument("--after", default="", help="effects already in the current model, e.g. force_plate_offset")
    ap.add_argument("--candidate", default="angle_dependent_stiffness")
    ap.add_argument("--hops", type=int, default=8)
    args = ap.parse_args()
    rec = _recording(args.recording, args.hops)
    trial, body = choose_body(rec, _measured_trial(rec), None)
    spec = ModelSpec(body_fraction=body.fraction)
    for e in filter(None, args.after.split(",")):
        spec, _ = identify(spec, trial, trial.stances, e)
        trial, body = choose_body(rec, measure_trial(rec, spec.latency_s, trial.options, 0.0, trial.table_model), None,
                                  spec)
        spec = replace(spec, body_fraction=body.fraction)
    spec_fit, _ = identify(spec, trial, trial.stances)
    with fs.HeldOutEvaluator(rec, trial) as ev:
        cand_spec, _ = identify(spec, fs.trial_for(spec), fs.trial_for(spec).stances, args.candidate)
        cur = sg.shoot_held_out(ev, spec_fit)
        cand = sg.shoot_held_out(ev, cand_spec, cur)
        tc, ta = held_out_channels(ev, spec_fit, cur), held_out_channels(ev, cand_spec, cand)
        print(f"body fraction {body.fraction}; gate gaps current {np.round(cur.gaps, 5).tolist()}, "
              f"angle {np.round(cand.gaps, 5).tolist()}")
        print(f"current factors per fold {[np.round(f.factors, 3).tolist() for f in cur.folds]}, "
              f"angle {[np.round(f.factors, 3).tolist() for f in cand.folds]}")
        show("current (constant K, k0 shot held out)", tc)
        show("angle law (k0 shot held out)", ta)
        if args.truth:
            tt = truth_channels(rec, fs.trial_for(spec), Path(args.truth), Path(args.recording).stem)
            show("truth per-hop law (in-sample, estimated M_td)", tt)
        d = np.log(np.sum(tc, axis=1)) - np.log(np.sum(ta, axis=1))
        p_one = stats.ttest_1samp(d, 0, alternative="greater").pvalue
        print(f"log ratios {np.round(d, 3).tolist()} mean {d.mean():.3f} SD {d.std(ddof=1):.3f} "
              f"t {d.mean() / (d.std(ddof=1) / np.sqrt(d.size)):.2f} p {p_one:.4f}")
        print(f"{args.recording} after [{args.after}] {args.candidate}: gate gaps current {np.mean(cur.gaps):.5f} "
              f"candidate {np.mean(cand.gaps):.5f} shrink {1 - np.mean(cand.gaps) / np.mean(cur.gaps):.3f} "
              f"p {fs.compare_gaps(cur.gaps, cand.gaps)[2]:.4g}")
        groups = {"grf": [0], "angles": [1, 2, 3], "moments": [4, 5, 6], "duration": [7], "work": [8], "flight": [9]}
        for g, k in groups.items():
            with np.errstate(divide="ignore", invalid="ignore"):
                dg = np.log(np.sum(tc[:, k], axis=1)) - np.log(np.sum(ta[:, k], axis=1))
            print(f"  channel {g}: current {np.mean(np.sum(tc[:, k], axis=1)):.5f} angle "
                  f"{np.mean(np.sum(ta[:, k], axis=1)):.5f} log ratios {np.round(dg, 2).tolist()} mean {dg.mean():.3f} "
                  f"SD {dg.std(ddof=1):.3f} p {stats.ttest_1samp(dg, 0, alternative='greater').pvalue:.4f}")


if __name__ == "__main__":
    main()
