"""Effect sizes (EffectSizes), two surfaces, a two-effect case and its held-out gaps against the true law.

Recordings: stance-set generator, 8 hops, default sensor noise (2 N force, 1 mm
markers), cached per session. Seeds and frequencies are fixed; the hit-rate
study (bench/discovery_hit_rates.py) covers many seeds and every effect (one discovery run costs
10-60 s now that every candidate is simulated on every held-out stance, so single-effect cases live there).
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.discovery.forward_selection import law_gaps
from hop_impedance.discovery.identify import compliance_index, identify, surface_split
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.discovery.workflow import discover
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import CompositeLaw, PushOff
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT, Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance import simulate_stance
from hop_impedance.simulation.stance_set import (
    EffectSizes,
    ground_law,
    nominal_touchdown_speed,
    simulate_stance_set_recording,
    sized_law,
)

BASE = dict(angle_dependent_stiffness=False, damping=False, push_off=False)
#: name -> (law switches, surfaces, sensor effects, frequency, seed)
CASES = {
    "activation_two_surfaces": ({"time_activation": True}, ("hard", "soft"), {}, 2.2, 1),
    "hard": ({}, ("hard",), {}, 2.2, 2),
    "angle+offset": ({"angle_dependent_stiffness": True}, ("rigid",), {"force_offset_n": 20.0}, 2.2, 2),
}
_CACHE: dict = {}
_DOCS: dict = {}
#: Final held-out gap / true law's gap (issue 16 asks for 1.2).
RATIO_TO_TRUTH = 1.2


def recording(name: str):
    """Cached (recording, truth) of a named case."""
    if name not in _CACHE:
        law, surfaces, sensors, freq, seed = CASES[name]
        _CACHE[name] = simulate_stance_set_recording(freq, surfaces, 8, seed=seed, effects=Effects(**{**BASE, **law}),
                                                     sensors=SensorConfig(**sensors), rtol=1e-6, sizes=EffectSizes(),
                                                     redraws=10)
    return _CACHE[name]


def discovered(name: str) -> dict:
    """Cached discovery document of a case."""
    if name not in _DOCS:
        _DOCS[name] = discover(recording(name)[0])
    return _DOCS[name]


def _nominal(law, freq=1.87, ground="rigid"):
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    passive = CompositeLaw(tuple(p for p in law.parts if not isinstance(p, PushOff)))
    speed, _ = nominal_touchdown_speed(chain, passive, ground_law(ground), DEFAULT_TOUCHDOWN_RHO, freq)
    td = touchdown_state(chain, touchdown_posture(chain, np.asarray(DEFAULT_TOUCHDOWN_RHO)), np.array([0.0, -speed]), 0.0)
    return chain, simulate_stance(chain, passive, ground_law(ground), td, t_max_s=1.0, rtol=1e-6, atol=1e-8)


def test_rate_stiffness_size_is_the_stated_share_of_the_peak_moment():
    """max |k3 S| / max |M| per joint on the nominal stance with k3 in (fixed point of the sizing)."""
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    eff = Effects(**{**BASE, "rate_dependent_stiffness": True})
    law, _ = sized_law(chain, 1.87, eff, EffectSizes(rate_fraction=0.15), ground_law("rigid"))
    _, st = _nominal(law)
    k3 = law.parts[0].k3
    share = np.max(np.abs(k3 * st.law_states), axis=0) / np.max(np.abs(st.moments_nm), axis=0)
    assert share == pytest.approx([0.15, 0.15, 0.15], abs=0.02)


def test_push_off_size_is_the_stated_share_of_the_ankle_peak():
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    law, ts = sized_law(chain, 1.87, Effects(**{**BASE, "push_off": True}), EffectSizes(push_fraction=0.3),
                        ground_law("rigid"))
    push = law.parts[1]
    _, st = _nominal(law)
    # the sizing and this check each integrate the nominal stance (LSODA, rtol 1e-6, different t_max): they agree
    # to the integrator's accuracy, not to round-off (5.7e-6 relative with scipy 1.17.1)
    assert push.amplitude_nm[0] == pytest.approx(0.3 * st.moments_nm[:, 0].max(), rel=1e-4)
    assert push.amplitude_nm / push.amplitude_nm[0] == pytest.approx([1.0, 0.6, 0.3])
    assert (push.onset_s, push.duration_s) == pytest.approx((0.35 * ts, 0.6 * ts))


def test_stance_that_does_not_take_off_is_a_clear_error_or_redrawn():
    """Damping b0 = 2 at 1.53 Hz: the passive stance never unloads; the message says so (and after re-draws)."""
    eff = Effects(**{**BASE, "damping": True})
    with pytest.raises(ValueError, match=r"hop 0: stance ended by (t_max|collapse).*2 re-draws tried"):
        simulate_stance_set_recording(1.53, ("rigid",), 2, seed=0, effects=eff, sizes=EffectSizes(), rtol=1e-6,
                                      redraws=2)


def test_two_surfaces_are_split_exactly_and_one_surface_is_not():
    rec, truth = recording("activation_two_surfaces")
    trial = measure_trial(rec)
    split = surface_split(trial.stances, 0.0)
    assert split is not None
    soft = [s["surface"] == "soft" for s in truth["stances"]]
    assert [compliance_index(s, 0.0) > split for s in trial.stances] == soft
    assert surface_split(measure_trial(recording("hard")[0]).stances, 0.0) is None


def test_two_hidden_effects_are_both_named():
    doc = discovered("angle+offset")
    assert sorted(doc["effects_found"]) == ["angle_dependent_stiffness", "force_plate_offset"]
    off = next(st for st in doc["steps"] if st["effect"] == "force_plate_offset")
    assert off["parameters"]["offset_n"] == pytest.approx(20.0, abs=1.0)


def test_gap_shrinks_on_held_out_stances_in_every_named_step():
    """Two-effect recording: every named step shrank the held-out forward gap it was chosen on (total), on
    most held-out stances (significant by the step's own t-test), and on the signals the effect acts on."""
    doc = discovered("angle+offset")
    acts_on = {"force_plate_offset": ("grf",),
               "angle_dependent_stiffness": ("moment_ankle", "moment_knee", "moment_hip")}
    assert len(doc["steps"]) == 2
    for st in doc["steps"]:
        assert st["gap_after"]["total"] < st["gap_before"]["total"]
        assert st["p_value"] < st["p_value_threshold"]
        assert np.mean(np.array(st["evidence"]["per_stance_log_gap_ratio"]) > 0) >= 0.75
        for sig in acts_on[st["effect"]]:
            assert st["gap_after"][sig]["rms"] < st["gap_before"][sig]["rms"], (st["effect"], sig)


def _truth_gap(name: str) -> float:
    """Mean per-stance gap G of the *true* law simulated from the measured touchdown states, exactly like a
    candidate (forward_selection.law_gaps): what is left when the model is right."""
    law_switches, surfaces, sensors, freq, _ = CASES[name]
    assert surfaces == ("rigid",)
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    law, _ = sized_law(chain, freq, Effects(**{**BASE, **law_switches}), EffectSizes(), ground_law("rigid"))
    trial = measure_trial(recording(name)[0])
    n = len(trial.stances)
    return float(np.mean(law_gaps(trial, [law] * n, [ground_law("rigid")] * n, sensors.get("force_offset_n", 0.0))))


@pytest.mark.slow
def test_final_gap_is_below_the_baselines_and_within_2p5_of_the_true_models():
    """Angle-dependent stiffness + offset (both in the candidate set): the final model with the regression's
    coefficients, each stance left out once (``final_gap``), 0.0112 against 0.0055 for the true law simulated the
    same way (2.03x; session 30, seed 000's Eq. 10 angle law; with Eq. 3's k1/k2 0.0079, 1.44x), the baseline 0.088.
    The regression's law is fitted to the ID moments, not through the simulation; the identified model discovery
    stands behind is the next test's (0.75x with Eq. 10, 0.98x with Eq. 3)."""
    doc, floor = discovered("angle+offset"), _truth_gap("angle+offset")
    final = doc["final_gap"]["total"]
    assert final < 0.2 * doc["baseline_gap"]["total"]
    assert final < 2.5 * floor, (final, floor)


@pytest.mark.slow
def test_final_gap_within_1p2_of_the_true_models():
    """Issue 16: the final model identified through the simulation (``final_gap_through_simulation``: per fold the
    law identified on the training stances, k0 shot on their forward gap, the held-out stances simulated) is within
    1.2x of the true law's gap. Measured (session 30, seed 000's Eq. 10 angle law): 0.00414 against the truth's
    0.00549 (0.75x; Eq. 3's k1/k2, session 17: 0.00538, 0.98x); with the regression's coefficients, left out one
    stance at a time, 0.0112 (2.03x; Eq. 3 0.00792, 1.44x: the joint law identified by regression on the ID moments,
    not through the simulator)."""
    doc, floor = discovered("angle+offset"), _truth_gap("angle+offset")
    shot = doc["final_gap_through_simulation"]
    assert shot["total"] < RATIO_TO_TRUTH * floor
    assert shot["total"] < doc["final_gap"]["total"]  # shooting k0 is what closes it
    assert shot["held_out_gap_regression_shot"][1] == pytest.approx(shot["total"], abs=1e-5)


def test_two_surface_law_of_the_soft_hops_is_seed_001s_soft_surface():
    """Soft hops of the hard/soft recording: Fz = 7.5e4 |y|^1.4 - 68.4 y' (seed 001). Measured: k = 7.58e4,
    n = 1.43 (grid p = 0.7), d = 68.1 N s/m. (The hard surface's law is not recovered: its ~1 cm give puts
    the exponent at the grid edge, n = 3.3 vs 2.0; see docs/discovery.md.)"""
    trial = measure_trial(recording("activation_two_surfaces")[0])
    spec, _ = identify(ModelSpec(), trial, trial.stances, "surface_compliance")
    (c, p), d = spec.compliance, spec.ground_damping_n_s_m
    assert c ** (-1 / p) == pytest.approx(7.5e4, rel=0.1)
    assert 1 / p == pytest.approx(1.4, abs=0.15)
    assert d == pytest.approx(68.4, rel=0.15)
    c2, p2, _ = spec.stiff_compliance
    assert c2 ** (-1 / p2) > 10 * c ** (-1 / p)
