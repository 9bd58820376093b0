"""The simulation decides (issue 16): held-out forward selection, its nuisances and its physics evidence.

Pinned cases of the outside generator (``../shared/foreign``: its own model, integrator and body
parameters perturbed up to +-5 % from de Leva; truth files give the per-hop law, touchdown moments and
effects). Numbers asserted are against that truth or against physics (a lossless stance does no net
joint work; a push-off adds it).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.discovery.forward_selection import (
    admissible,
    law_gaps,
    measured_net_work_j,
    physics_evidence,
)
from hop_impedance.discovery.identify import identify, touchdown_moments
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.ground import GroundLaw
from hop_impedance.simulation.impedance_laws import Eq3Law

FOREIGN = Path(__file__).resolve().parents[3] / "shared" / "foreign"
needs_foreign = pytest.mark.skipif(not FOREIGN.is_dir(), reason="../shared/foreign not present")
#: The outside generator's strict-baseline ground (truth file's baseline note).
STRICT_GROUND = GroundLaw("stiff", 1.0e7, 1.5, 0.0)
_CACHE: dict = {}


def foreign(name: str):
    """(recording, measured trial, truth) of one outside recording, cached."""
    if name not in _CACHE:
        rec = load_recording(FOREIGN / f"{name}.mcap")
        _CACHE[name] = (rec, measure_trial(rec), json.loads((FOREIGN / f"{name}.truth.json").read_text()))
    return _CACHE[name]


def truth_hop(truth: dict, touchdown_s: float) -> dict:
    """The truth's hop whose touchdown is nearest a measured one."""
    return min(truth["per_hop"], key=lambda h: abs(h["t_td"] - touchdown_s))


@needs_foreign
def test_strict_baseline_stiffness_and_touchdown_moments_are_recovered():
    """Strict baseline M = M_td + K phi with a different M_td every hop: the within-stance fit recovers
    K (measured: 195/209/195 vs 193/208/191 N m/rad) and each stance's M_td (rms error 3.6/1.5/0.9 N m
    against per-hop values of -17..+32 N m)."""
    _, trial, truth = foreign("none_1101")
    spec, coefs = identify(ModelSpec(), trial, trial.stances)
    assert coefs[:, 0] == pytest.approx(truth["law"]["kc"], rel=0.05)
    err = [touchdown_moments(spec, coefs, s) - truth_hop(truth, s.touchdown_s)["law"]["M_td"] for s in trial.stances]
    assert np.all(np.sqrt(np.mean(np.square(err), axis=0)) < 6.0)


@needs_foreign
@pytest.mark.parametrize("name", ["none_1101", "angle_dependent_stiffness_1201", "rate_dependent_stiffness_1301"])
def test_lossless_stances_do_no_net_joint_work(name):
    """Lossless, time-symmetric stances: net joint work per stance ~0 (measured |mean| < 0.5 J against
    ~36 J of kinetic energy at touchdown), so a push-off is inadmissible there."""
    _, trial, _ = foreign(name)
    w = np.array([measured_net_work_j(s) for s in trial.stances])
    assert abs(w.mean()) < 0.5 and np.all(np.abs(w) < 2.5)
    runs = _fake_runs(trial)
    ok, why = admissible("active_push_off", physics_evidence(trial, runs, runs))
    assert not ok and "not positive" in why


@needs_foreign
@pytest.mark.parametrize("name", ["active_push_off+surface_compliance_1001", "surface_compliance+active_push_off_1501"])
def test_push_off_recordings_show_the_net_work_it_adds(name):
    """A push-off replacing the ground's loss: every stance shows net positive joint work (measured 1-6 J)."""
    _, trial, _ = foreign(name)
    w = np.array([measured_net_work_j(s) for s in trial.stances])
    assert w.mean() > 2.0 and np.all(w > 0.5)
    runs = _fake_runs(trial)
    assert physics_evidence(trial, runs, runs)["measured_net_joint_work_j"]["p_positive"] < 0.01


def _fake_runs(trial):
    """Held-out runs with unit gaps (physics_evidence reads only the measured side and these arrays)."""
    from hop_impedance.discovery.forward_selection import HeldOutRuns

    n = len(trial.stances)
    return HeldOutRuns(None, ModelSpec(), np.ones(n), np.ones((n, 7)), np.zeros(n), np.zeros(n), ["take_off"] * n)


@needs_foreign
def test_truth_law_simulated_like_a_candidate_fits_the_foreign_null():
    """The true law (per-hop K and M_td, strict ground) simulated from the measured touchdown states has a
    small gap (measured mean G = 0.0054, i.e. ~7 % of each signal's range); the identified baseline's
    held-out gap is of the same size (0.0029): the remaining gap is touchdown state and segment parameters."""
    rec, trial, truth = foreign("none_1101")
    laws = [Eq3Law(m0=np.array(h["law"]["M_td"]), k0=np.array(h["law"]["kc"]))
            for h in (truth_hop(truth, s.touchdown_s) for s in trial.stances)]
    g = law_gaps(trial, laws, [STRICT_GROUND] * len(laws))
    assert np.all(np.isfinite(g)) and np.mean(g) < 0.01


@needs_foreign
def test_foreign_null_names_nothing_and_reports_physics_per_candidate():
    rec, _, _ = foreign("none_1101")
    doc = discover(rec)
    assert doc["effects_found"] == []
    (round0,) = doc["selection"]["rounds"]
    assert len(round0) == 8 and not any(c["passes"] for c in round0.values())
    for c in round0.values():
        ph = c["physics"]
        assert {"measured_net_joint_work_j", "simulated_net_joint_work_j", "flight_force_n", "fitted_latency_s",
                "fitted_offset_n", "admissible"} <= set(ph)
        assert len(c["per_stance_log_gap_ratio"]) == 6
    assert round0["active_push_off"]["physics"]["admissible"] is False
    assert doc["timing"]["total_s"] > 0 and set(doc["timing"]["per_candidate_s"]) == set(round0)


def _truth_stances(truth: dict):
    """Per hop of the truth's ``stance_truth``: (t since touchdown, rho (flexion positive), omega, moments, hop)."""
    cols = {c: i for i, c in enumerate(truth["stance_truth"]["columns"])}
    rows = np.array(truth["stance_truth"]["rows"])
    for h in np.unique(rows[:, cols["hop"]]).astype(int):
        r = rows[rows[:, cols["hop"]] == h]
        rho, w, m = (np.stack([r[:, cols[f"{kind}_{j}"]] for j in ("ankle", "knee", "hip")], axis=-1)
                     for kind in ("rho", "w", "M"))
        # truth convention: phi = rho(touchdown) - rho, w = dphi/dt (flexion positive, as ours)
        yield r[:, cols["t_s"]] - r[0, cols["t_s"]], -rho, w, m, truth["per_hop"][h]


@needs_foreign
@pytest.mark.parametrize("name", ["rate_dependent_stiffness_1301",
                                  "time_dependent_activation+active_push_off+surface_compliance_1602"])
def test_rate_speed_form_and_tangent_activation_reproduce_the_outside_law(name):
    """The candidate regressors hold the outside generator's laws exactly (its true angles and velocities in,
    its true moments out): rate-dependent stiffness in the speed form ``K = kc + k3 (|w| - |w0|)`` (``k3
    S_speed``) and the bell activation acting on the stiffness (``tangent``). Measured: <= 0.03 % of the RMS
    moment; the signed-rate ``k3 S`` and the secant activation miss by 23-56 % (worst joint of each hop)."""
    from hop_impedance.discovery.model import push_profile, stance_features

    _, _, truth = foreign(name)
    rate = name.startswith("rate")
    for t, rho, w, m, hop in _truth_stances(truth):
        law = hop["law"]
        if rate:
            spec = ModelSpec(effects=("rate_dependent_stiffness",), rate_form="speed")
            coefs = wrong = np.array([[law["kc"][j], law["k3"][j]] for j in range(3)])
        else:
            act, po = law["activation"], law["pushoff"]
            spec = ModelSpec(effects=("time_dependent_activation",), tau_s=act["Ta_s"], activation_shape="bell",
                             activation_form="tangent")
            coefs = np.array([[law["kc"][j] * act["a0"], law["kc"][j] * (1 - act["a0"])] for j in range(3)])
            m = m - np.outer(push_profile(t, po["t1_s"], po["t2_s"] - po["t1_s"]), po["A_Nm"] * np.array(po["pattern"]))
            wrong = coefs
        feats = stance_features(spec, t, rho, w)
        pred = np.stack([law["M_td"][j] + feats[j] @ coefs[j] for j in range(3)], axis=-1)
        scale = np.sqrt(np.mean(m**2, axis=0))
        assert np.all(np.sqrt(np.mean((m - pred) ** 2, axis=0)) < 0.005 * scale)
        other = replace(spec, rate_form="signed", activation_form="secant")
        feats = stance_features(other, t, rho, w)
        pred = np.stack([law["M_td"][j] + feats[j] @ wrong[j] for j in range(3)], axis=-1)
        assert np.max(np.sqrt(np.mean((m - pred) ** 2, axis=0)) / scale) > 0.15


@needs_foreign
def test_pooled_rate_law_needs_the_absolute_speed_form():
    """The outside rate law with ONE coefficient set for all hops (session 28). Its generator simulates
    ``K = kc + k3 |w|`` (truth ``law_simulated``); the per-hop ``kc_td = kc + k3 |w0|`` moves with each hop's
    ``w0`` (ankle 9.6-11.0, knee 3.1-4.9, hip 0.5-2.5 rad/s). On the truth's own angles and rates the
    ``abs_speed`` regressor with the truth's pooled ``kc``, ``k3`` holds every hop (measured <= 0.03 % of the RMS
    moment); the touchdown-referenced ``speed`` regressor with the best pooled ``k0`` (``kc + k3`` mean ``|w0|``)
    misses the hip by 12.0 % on its worst hop (ankle 2.3 %, knee 4.4 %). Identified on the measured stances the
    pooled ``abs_speed`` finds the knee and hip ``k3`` (measured 14.0 and 24.5 against the truth's 14.0 and 21.7;
    the ankle's 11.5 against 7.2 is not asserted); ``speed`` finds 7.4 and 6.2."""
    from hop_impedance.discovery.model import stance_features

    _, trial, truth = foreign("rate_dependent_stiffness_1301")
    kc, k3 = np.array(truth["law"]["kc"]), np.array(truth["law"]["k3"])
    w0 = np.abs([h["law"]["w0"] for h in truth["per_hop"]]).mean(axis=0)
    spec = ModelSpec(effects=("rate_dependent_stiffness",), rate_form="abs_speed")
    speed = replace(spec, rate_form="speed")
    misses = []
    for t, rho, w, m, hop in _truth_stances(truth):
        scale = np.sqrt(np.mean(m**2, axis=0))
        for form, coefs in ((spec, np.stack([kc, k3], 1)), (speed, np.stack([kc + k3 * w0, k3], 1))):
            feats = stance_features(form, t, rho, w)
            pred = np.stack([hop["law"]["M_td"][j] + feats[j] @ coefs[j] for j in range(3)], axis=-1)
            misses.append(np.sqrt(np.mean((m - pred) ** 2, axis=0)) / scale)
    assert np.max(misses[0::2]) < 0.001
    assert np.max(np.array(misses[1::2])[:, 2]) > 0.10
    _, got = identify(spec, trial, trial.stances)
    np.testing.assert_allclose(got[1:, 1], k3[1:], rtol=0.15)
    _, got = identify(speed, trial, trial.stances)
    assert np.all(got[1:, 1] < 0.6 * k3[1:])


@needs_foreign
def test_per_stance_push_off_amplitude_follows_the_hop_by_hop_control():
    """The outside generator sets the push-off hop by hop (5-22 N m). Identified on the measured stances: timing
    (onset 0.12 s, duration 0.14 s vs truth 0.116 / 0.139 s), pattern (knee/ankle 0.44 vs 0.4), and the
    per-stance amplitude of the held-out nuisance follows the per-hop truth (measured r = 0.99, 2.0 N m low)."""
    from hop_impedance.discovery.identify import per_stance_push_off
    from hop_impedance.discovery.model import feature_names

    _, trial, truth = foreign("active_push_off+surface_compliance_1001")
    spec, coefs = identify(ModelSpec(), trial, trial.stances, "active_push_off")
    k = feature_names(spec).index("push")
    po = truth["law"]["pushoff"]
    assert spec.onset_s == pytest.approx(po["t1_s"], abs=0.02)
    assert spec.duration_s == pytest.approx(po["t2_s"] - po["t1_s"], abs=0.03)
    assert coefs[1, k] / coefs[0, k] == pytest.approx(0.4, abs=0.1)
    got = np.array([per_stance_push_off(spec, coefs, s)[0, k] for s in trial.stances])
    want = np.array([truth_hop(truth, s.touchdown_s)["control"]["pushoff_A_Nm"] for s in trial.stances])
    assert np.corrcoef(got, want)[0, 1] > 0.95 and np.mean(np.abs(got - want)) < 4.0


def test_latency_remeasurement_does_not_depend_on_which_latency_came_first():
    """Each worker process caches re-measured trials by latency to the microsecond; the trial must be the one
    measured at that rounded latency, whatever latency of the bucket a process met first. Before, the first
    arrival's value was used, and two runs of ``discover`` on two workers differed by up to 1.9e-3 relative
    (stream_latency candidate, sim_2p20hz_hard)."""
    from hop_impedance.discovery import forward_selection as fs

    rec = load_recording(Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap")
    trial = measure_trial(rec)
    reference = measure_trial(rec, marker_latency_s=0.012)
    with fs.HeldOutEvaluator(rec, trial, workers=1):
        seen = []
        for latency in (0.0120004, 0.0119996):  # one microsecond bucket, met in either order
            fs._CONTEXT.pop("latency_cache", None)
            seen.append(fs.trial_for(ModelSpec(effects=("stream_latency",), latency_s=latency)))
    for got in seen:
        assert len(got.stances) == len(reference.stances) > 5
        for a, b in zip(got.stances, reference.stances):
            np.testing.assert_array_equal(a.rho_rad, b.rho_rad)
            np.testing.assert_array_equal(a.moment_nm, b.moment_nm)
