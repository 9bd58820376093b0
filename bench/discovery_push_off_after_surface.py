"""Why the push-off after a compliant ground is missed (issue 16, session 13): its figures on outside recordings.

For each truth-labelled outside recording (default: the two push-off + surface files of ``../shared/foreign``),
with the table body (``discover`` keeps the table's thigh/HAT split on both, ``nuisance.body_mass_split``):

1. the surface law identified on all stances (what round 1 of ``discover`` starts from) and the measured net joint
   work per stance (``forward_selection.measured_net_work_j``: the physics evidence; a lossy ground needs a source);
2. leave-one-stance-out, like ``discover``'s round 1: the surface model and the surface model + push-off, each
   identified on the other stances and the held-out stance simulated; per model the mean held-out gap split into
   its 10 terms (``forward_selection._gap_of``), the push-off's shrink and one-sided p against ALPHA / 7 (the 7
   candidates left after the surface), its identified timing, per-stance amplitudes and simulated net work, and
   each model's simulated minus measured stance time (sampled past the measured end);
3. the TRUE law (the truth file's per-hop law and surface, ``discovery_truth_gap.truth_law``) with and without its
   push-off, simulated the same way: whether our forward comparison can see the push-off at all;
4. ``--gate``: the held-out stiffness gate (``stiffness_gate.shoot``, 2 folds, Levenberg-Marquardt to convergence)
   on the surface model and on the push-off model: its shrink and p against ALPHA / 7;
5. ``--truth-surface``: step 2 again with the surface law replaced by the truth's (``c = k^(-1/n)``, ``p = 1/n``, its
   damping): whether the identified surface absorbs what the push-off would explain;
6. ``--shoot-surface`` (session 14, issue 16's next step): the surface law identified through the simulation instead
   of from the toe marker: ``k``, ``n`` and the damping (log factors on the toe fit's) chosen by Nelder-Mead on the
   mean in-sample forward gap of all stances, for each model on its own (the surface model, and the surface +
   push-off model with its joint law and push-off as identified), then step 2 with each model's shot surface;
   ``--surface-folds K``: instead, held out like the stiffness gate: per fold, each model's joint law identified and
   its surface shot on the fold's training stances, the held-out stances simulated with them, the push-off's shrink
   and p over every stance's held-out gap.

Usage: .venv/bin/python bench/discovery_push_off_after_surface.py [FILE.mcap ...] [--gate] [--truth-surface]
[--shoot-surface [--surface-folds 2]]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import stiffness_gate as sg
from hop_impedance.discovery.forward import ground_of
from hop_impedance.discovery.identify import identify, per_stance_push_off, touchdown_moments
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import FittedLaw, ModelSpec, feature_names
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.ground import SURFACES
from hop_impedance.simulation.stance import simulate_stance

sys.path.insert(0, str(Path(__file__).resolve().parent))
from discovery_truth_gap import fitted_law, true_touchdown_moment, truth_law  # noqa: E402  (a sibling bench script)

FILES = ("active_push_off+surface_compliance_1001", "surface_compliance+active_push_off_1501")
TERMS = ("grf", "angle_ankle", "angle_knee", "angle_hip", "moment_ankle", "moment_knee", "moment_hip",
         "duration", "net_work", "flight")
#: Candidates left after the surface step (Bonferroni factor of round 1).
N_CANDIDATES = 7


def term_row(out: dict) -> np.ndarray:
    """The 10 terms of one stance's gap (they sum to ``out['gap']``)."""
    return np.r_[np.mean(out["samples"] ** 2, axis=0), out["terms"] ** 2] / len(TERMS)


def held_out(trial, spec: ModelSpec, effect: str | None, scales: np.ndarray, verbose: bool = False) -> np.ndarray:
    """Per stance, the 10 gap terms of ``spec`` (+ ``effect``) identified without it, shape (n, 10)."""
    rows = []
    for s in trial.stances:
        fitted, coefs = identify(spec, trial, [x for x in trial.stances if x.index != s.index], effect)
        out = fs.simulate_held_out(fitted, coefs, trial, s, scales, samples=True)
        if out["samples"] is None:
            raise RuntimeError(f"stance {s.index} did not simulate: {out['end_reason']}")
        rows.append(term_row(out))
        if verbose and fitted.has("active_push_off"):
            push = per_stance_push_off(fitted, coefs, s)[:, feature_names(fitted).index("push")]
            print(f"    stance {s.index}: onset {fitted.onset_s} s, duration {fitted.duration_s} s, amplitude "
                  f"ankle/knee/hip {np.round(push, 1).tolist()} N m, simulated net work {out['net_work_j']:.2f} J, "
                  f"measured {fs.measured_net_work_j(s):.2f} J")
    return np.array(rows)


def overrun_ms(trial, spec: ModelSpec, effect: str | None) -> np.ndarray:
    """Per stance, simulated minus measured stance time (ms), leave-one-out, the simulation sampled at 1 ms past the
    measured end (``discover`` samples it at the measured times only, so a stance simulated too long shows no
    duration error there)."""
    out = []
    for s in trial.stances:
        fitted, coefs = identify(spec, trial, [x for x in trial.stances if x.index != s.index], effect)
        coefs = per_stance_push_off(fitted, coefs, s)
        law = FittedLaw(fitted, np.asarray(coefs, float), touchdown_moments(fitted, coefs, s))
        t_max = 1.5 * float(s.t_s[-1]) + 0.05
        sim = simulate_stance(trial.chain, law, ground_of(fitted, s), s.touchdown, t_max_s=t_max, rtol=fs.RTOL,
                              atol=fs.ATOL, sample_times_s=np.arange(0.0, t_max, 0.001))
        out.append(1e3 * (sim.duration_s - float(s.t_s[-1])))
    return np.array(out)


def compare(label: str, cur: np.ndarray, cand: np.ndarray) -> None:
    """Print both models' mean terms and the candidate's shrink and p."""
    for name, rows in (("without push-off", cur), ("with push-off", cand)):
        print(f"  {label}, {name}: gap {rows.sum(1).mean():.5f}; "
              + ", ".join(f"{t} {v:.5f}" for t, v in zip(TERMS, rows.mean(0))))
    d, shrink, p = fs.compare_gaps(cur.sum(1), cand.sum(1))
    print(f"  {label}: push-off shrink {shrink:+.3f}, p {p:.3g} (threshold {fs.ALPHA / N_CANDIDATES:.4f}), "
          f"per-stance log ratios {np.round(d, 3).tolist()}")


def truth_rows(trial, truth: dict, scales: np.ndarray, push_scale: float) -> np.ndarray:
    """Per stance, the 10 gap terms of the truth's per-hop law and surface (push-off amplitude times ``push_scale``).

    ``M_td`` and the reference are set as for a candidate (``discovery_truth_gap``'s default ``estimated``, session 15):
    the truth's ``M_td`` at the true contact, which this bench used before session 16, starts the simulation 1-2 ms
    before the first plate sample it is read at."""
    rows = []
    for s in trial.stances:
        hop = min(truth["per_hop"], key=lambda h: abs(h["t_td"] - s.touchdown_s))
        spec, coefs = truth_law(hop)
        coefs[:, feature_names(spec).index("push")] *= push_scale
        m_td = true_touchdown_moment("estimated", truth, hop, s, 0, spec, coefs)
        law = fitted_law("estimated", spec, coefs, m_td, s)
        sim = fs.simulate_for_gap(trial.chain, law, SURFACES[hop["surface"]], s)
        rows.append(term_row(fs._gap_of(sim, s, 0.0, scales, fs.take_off_level_n(trial), samples=True)))
    return np.array(rows)


def surface_spec(spec: ModelSpec, k: float, n: float, d: float) -> ModelSpec:
    """``spec`` on the ground ``Fz = k |y|^n - d y'`` (the discovery's ``c = k^(-1/n)``, ``p = 1/n``)."""
    return replace(spec, compliance=(k ** (-1.0 / n), 1.0 / n), ground_damping_n_s_m=d)


def shoot_surface(rec, trial, spec: ModelSpec, effect: str | None, train: list | None = None) -> ModelSpec:
    """``spec`` (+ ``effect``) with its surface law chosen by the simulation (module docstring, step 6), on the
    stances of ``train`` (None: all)."""
    train = trial.stances if train is None else train
    indices = tuple(s.index for s in train)
    fitted, coefs = identify(spec, trial, train, effect)
    c, p = fitted.compliance
    k0, n0, d0 = c ** (-1.0 / p), 1.0 / p, max(fitted.ground_damping_n_s_m, 1.0)

    def law(x: np.ndarray) -> ModelSpec:
        return surface_spec(fitted, k0 * np.exp(x[0]), n0 * np.exp(np.clip(x[1], -0.7, 0.7)), d0 * np.exp(x[2]))

    with fs.HeldOutEvaluator(rec, trial) as ev:
        def mean_gap(x: np.ndarray) -> float:
            runs = ev.stance_residuals(law(x), [coefs], indices)[0]
            return float(np.mean(np.minimum([r["gap"] for r in runs], 10.0)))

        start = mean_gap(np.zeros(3))
        res = minimize(mean_gap, np.zeros(3), method="Nelder-Mead",
                       options={"initial_simplex": np.vstack([np.zeros(3), 0.5 * np.eye(3)]), "maxfev": 80,
                                "xatol": 0.02, "fatol": 0.01 * start})
    shot = law(res.x)
    c, p = shot.compliance
    print(f"  shot surface ({effect or 'surface model'}): k {c ** (-1 / p):.3g} n {1 / p:.2f} damping "
          f"{shot.ground_damping_n_s_m:.0f} N s/m (toe fit: k {k0:.3g} n {n0:.2f} damping {d0:.0f}); in-sample gap "
          f"{start:.5f} -> {res.fun:.5f} in {res.nfev} evaluations", flush=True)
    return replace(spec, compliance=shot.compliance, ground_damping_n_s_m=shot.ground_damping_n_s_m)


def surface_folds(rec, trial, spec: ModelSpec, scales: np.ndarray, folds: int) -> None:
    """The push-off against the surface model, each with its surface shot on a fold's training stances (step 6)."""
    gaps = {None: {}, "active_push_off": {}}
    for train_idx, test_idx in sg.fold_indices([s.index for s in trial.stances], folds):
        train = [s for s in trial.stances if s.index in train_idx]
        for effect in gaps:
            shot = shoot_surface(rec, trial, spec, effect, train)
            fs._CONTEXT.update(rec=rec, trial=trial, scales=scales)  # the evaluator cleared it
            fitted, coefs = identify(shot, trial, train, effect)
            for s in trial.stances:
                if s.index in test_idx:
                    gaps[effect][s.index] = fs.simulate_held_out(fitted, coefs, trial, s, scales)["gap"]
    order = [s.index for s in trial.stances]
    cur, cand = (np.array([gaps[e][i] for i in order]) for e in (None, "active_push_off"))
    d, shrink, p = fs.compare_gaps(cur, cand)
    print(f"  surface shot on {folds} folds' training stances: held-out gap {cur.mean():.5f} -> {cand.mean():.5f}, "
          f"push-off shrink {shrink:+.3f}, p {p:.3g} (threshold {fs.ALPHA / N_CANDIDATES:.4f}), per-stance log ratios "
          f"{np.round(d, 3).tolist()}", flush=True)


def gate_figures(rec, trial, spec: ModelSpec) -> None:
    """The held-out stiffness gate on the surface model and the push-off model."""
    with fs.HeldOutEvaluator(rec, trial) as ev:
        shot = sg.shoot(ev, *identify(spec, trial, trial.stances))
        cand = sg.shoot(ev, *identify(spec, trial, trial.stances, "active_push_off"), shot)
        g = sg.gate(cand, shot, N_CANDIDATES)
    print(f"  stiffness gate ({sg.FOLDS} folds, {sg.SEARCH}): held-out gap with shot k0 {np.mean(shot.gaps):.5f} -> "
          f"{np.mean(cand.gaps):.5f}, shrink {g['shrink_against_shot']:+.3f}, p {g['p_value']:.3g}, "
          f"passes {g['passes']}; per-stance log ratios {g['per_stance_log_gap_ratio']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", default=[f"../shared/foreign/{f}.mcap" for f in FILES])
    ap.add_argument("--gate", action="store_true", help="also the held-out stiffness gate on both models")
    ap.add_argument("--truth-surface", action="store_true", help="also leave-one-out with the truth's surface law")
    ap.add_argument("--shoot-surface", action="store_true", help="also leave-one-out with each model's shot surface")
    ap.add_argument("--surface-folds", type=int, default=0, help="with --shoot-surface: shot on K folds, held out")
    args = ap.parse_args()
    for path in map(Path, args.files):
        rec = load_recording(path)
        truth = json.loads(path.with_suffix(".truth.json").read_text())
        trial = measure_trial(rec)
        fs._CONTEXT.clear()
        fs._CONTEXT.update(rec=rec, trial=trial, scales=fs.gap_scales(trial))
        scales = fs._CONTEXT["scales"]
        spec, _ = identify(ModelSpec(), trial, trial.stances, "surface_compliance")
        work = fs.measured_net_works_j(trial)
        c, p = spec.compliance
        print(f"{path.stem}: surface c {c:.3g} p {p} (n {1 / p:.2f}), damping {spec.ground_damping_n_s_m:.0f} N s/m; "
              f"truth surfaces {sorted(set(h['surface'] for h in truth['per_hop']))}")
        print(f"  measured net joint work per stance {np.round(work, 2).tolist()} J, mean {work.mean():.2f} J, "
              f"p(> 0) {fs.one_sided_t(work):.2g}")
        compare("identified surface", held_out(trial, spec, None, scales),
                held_out(trial, spec, "active_push_off", scales, verbose=True))
        for effect in (None, "active_push_off"):
            print(f"  identified surface, {'with' if effect else 'without'} push-off: simulated minus measured stance "
                  f"time {np.round(overrun_ms(trial, spec, effect), 1).tolist()} ms")
        compare("true law", truth_rows(trial, truth, scales, 0.0), truth_rows(trial, truth, scales, 1.0))
        if args.truth_surface:
            ground = SURFACES[truth["per_hop"][0]["surface"]]
            true_spec = replace(spec, compliance=(ground.stiffness ** (-1.0 / ground.exponent), 1.0 / ground.exponent),
                                ground_damping_n_s_m=ground.damping_n_s_m)
            compare("truth's surface law", held_out(trial, true_spec, None, scales),
                    held_out(trial, true_spec, "active_push_off", scales))
        if args.shoot_surface and args.surface_folds:
            surface_folds(rec, trial, spec, scales, args.surface_folds)
        elif args.shoot_surface:
            shot = shoot_surface(rec, trial, spec, None), shoot_surface(rec, trial, spec, "active_push_off")
            fs._CONTEXT.update(rec=rec, trial=trial, scales=scales)  # the evaluator cleared it
            compare("shot surface", held_out(trial, shot[0], None, scales), held_out(trial, shot[1], "active_push_off",
                                                                                      scales))
        if args.gate:
            gate_figures(rec, trial, spec)


if __name__ == "__main__":
    main()
