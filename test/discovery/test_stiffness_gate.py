"""The stiffness gate of discovery (hop_impedance.discovery.stiffness_gate): an effect is named only if the
candidate still beats the current model forward when both have their stiffness (and the candidate its own
effect's terms) chosen through the simulation.

Checked against a known truth: a strict null of the second generator (no effect hidden) that the
held-out test alone named falsely (seed 43: angle-dependent stiffness, 8/60 false before the gate), and the
gate's arithmetic against scipy's t-test.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import stiffness_gate as sg
from hop_impedance.discovery.body_nuisance import choose_body
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.discovery.stiffness_gate import SEARCH, ShotStiffness, effect_terms, gate, shoot_stiffness
from hop_impedance.validation.strict_generator import StrictConfig, strict_recording


def test_gate_is_the_one_sided_t_test_of_log_ratios_between_the_shot_models():
    k0 = np.array([250.0, 250.0, 150.0])
    current_gaps = np.array([0.020, 0.018, 0.025, 0.015, 0.030, 0.022])
    current = ShotStiffness(np.ones(3), k0, current_gaps, 0.04, 25, 1.0, SEARCH)
    better = current_gaps * np.array([0.5, 0.6, 0.55, 0.7, 0.5, 0.65])
    out = gate(ShotStiffness(np.ones(3), k0, better, 0.03, 25, 1.0, SEARCH), current, 8)
    d = np.log(current_gaps) - np.log(better)
    assert out["p_value"] == pytest.approx(stats.ttest_1samp(d, 0.0, alternative="greater").pvalue, rel=1e-12)
    assert out["shrink_against_shot"] == pytest.approx(1 - better.mean() / current_gaps.mean())
    assert out["passes"]
    # significant on every stance but under the 10 % floor (Bonferroni over 8 candidates), and worse
    assert not gate(ShotStiffness(np.ones(3), k0, current_gaps * 0.95, 0.03, 25, 1.0, SEARCH), current, 8)["passes"]
    worse = gate(ShotStiffness(np.ones(3), k0, current_gaps * 1.5, 0.03, 25, 1.0, SEARCH), current, 8)
    assert not worse["passes"] and worse["shrink_against_shot"] == pytest.approx(-0.5)


def test_the_terms_a_candidate_shoots_are_its_own_effects_joint_law_terms():
    base = ModelSpec()
    assert effect_terms(base, None) == ()
    assert effect_terms(base.with_effect("angle_dependent_stiffness"), "angle_dependent_stiffness") == ("k1",)
    assert effect_terms(base.with_effect("rate_dependent_stiffness"), "rate_dependent_stiffness") == ("k3",)
    assert effect_terms(base.with_effect("joint_damping"), "joint_damping") == ("b0", "b1")
    # an elastic term added to a model with an activation brings its activation terms too
    act = base.with_effect("time_dependent_activation")
    assert effect_terms(act, "time_dependent_activation") == ("act_k0",)
    assert effect_terms(act.with_effect("angle_dependent_stiffness"), "angle_dependent_stiffness") == ("k1", "act_k1")
    # ground and sensor effects have no joint-law terms: only k0 is shot
    assert effect_terms(base.with_effect("force_plate_offset"), "force_plate_offset") == ()


@pytest.mark.slow
def test_a_strict_null_named_by_the_held_out_test_is_stopped_by_the_shot_stiffness(monkeypatch):
    """Strict null seed 43, 8 hops (the constant-stiffness law, no effect; named falsely before the gate): the
    regression's k0 leaves the baseline's in-sample forward gap at 0.022 and the angle-dependent candidate
    passes the held-out test. The current model's k0 is shot, and the candidate's k0 and the size of its
    k1/k2 terms (session 10's trial, Levenberg-Marquardt to convergence): the candidate nests the current
    model (size 0), so it is never worse in-sample, yet its gain is not significant and it is not named.
    (With one size per joint it was: session 10, stiffness_gate's module docstring.)"""
    for name, value in sg.TO_CONVERGENCE.items():
        monkeypatch.setattr(sg, name, value)
    rec, _ = strict_recording(StrictConfig(seed=43, hops=8))
    trial, body = choose_body(rec, measure_trial(rec))
    spec = ModelSpec(body_fraction=body.fraction)
    spec_fit, coefs = identify(spec, trial, trial.stances)
    with fs.HeldOutEvaluator(rec, trial) as ev:
        current, cand = ev.run(spec, [None, "angle_dependent_stiffness"])
        (sc,) = fs.score(trial, current, [cand])
        assert fs.passes(sc, 8), (sc.shrink, sc.p_value)  # the held-out test alone names it: the case to stop
        shot = shoot_stiffness(ev, spec_fit, coefs, method="levenberg-marquardt")
        cand_fit, cand_coefs = identify(cand.spec, trial, trial.stances)
        shot_cand = shoot_stiffness(ev, cand_fit, cand_coefs, shot, "levenberg-marquardt", "angle_dependent_stiffness")
    assert shot.converged and shot_cand.converged and shot_cand.effect_terms == ("k1",)
    assert np.mean(shot.gaps) < 0.5 * shot.gap_regression, shot.as_json()
    assert np.mean(shot_cand.gaps) <= np.mean(shot.gaps), (shot.as_json(), shot_cand.as_json())
    assert not gate(shot_cand, shot, 8)["passes"], shot_cand.as_json()


def test_the_shot_stiffness_finds_the_generators_k0_where_the_joint_moves():
    """Known truth: strict null seed 3 of the second generator (8 hops) with its own segment parameters given to
    the analysis. The regression's k0 is 276/281/94 N m/rad against the generator's 265/270/138 and its
    in-sample forward gap 0.0345 against the true law's 0.0194 (``bench/discovery_strict_floor.py --seeds 3``).
    Levenberg-Marquardt through the simulation (session 9) brings the ankle and knee from 4 % off to within 3 %
    of the generator's k0 (measured 264/275 N m/rad), and the gap below the true law's (0.0089), within its
    budget of evaluations. The hip (0.04-0.17 rad in stance) is not asserted: the gap barely determines its k0."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from discovery_body_nuisance import generator_overrides
    from discovery_truth_gap import STRICT_GROUND

    from hop_impedance.biomech.analysis import AnalysisOptions
    from hop_impedance.discovery.model import FittedLaw
    from hop_impedance.discovery.stiffness_gate import LM_MAX_EVALUATIONS

    cfg = StrictConfig(seed=3, hops=8)
    rec, truth = strict_recording(cfg)
    trial = measure_trial(rec, options=AnalysisOptions(overrides=generator_overrides(cfg)))
    hops = [min(truth["per_hop"], key=lambda h: abs(h["t_td"] - s.touchdown_s)) for s in trial.stances]
    true_laws = [FittedLaw(ModelSpec(), np.array(h["k0"], float)[:, None], np.asarray(h["M_td"], float)) for h in hops]
    gap_true = float(np.mean(fs.law_gaps(trial, true_laws, [STRICT_GROUND] * len(hops))))
    spec_fit, coefs = identify(ModelSpec(), trial, trial.stances)
    with fs.HeldOutEvaluator(rec, trial) as ev:
        shot = shoot_stiffness(ev, spec_fit, coefs, method="levenberg-marquardt")
    k0_true = np.array(hops[0]["k0"], float)
    k0_shot = shot.k0_regression * shot.factors
    assert shot.method == "levenberg-marquardt" and shot.evaluations <= LM_MAX_EVALUATIONS
    assert shot.gap_regression > 1.5 * gap_true  # the case: the regression's k0 is far from the floor
    assert np.mean(shot.gaps) < gap_true, (shot.as_json(), gap_true)
    np.testing.assert_allclose(k0_shot[:2], k0_true[:2], rtol=0.03, err_msg=str(shot.as_json()))
