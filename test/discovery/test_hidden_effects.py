"""Hidden effects at the documented sizes (EffectSizes), two-effect and ambiguity cases, held-out gaps.

Recordings: stance-set generator, 8 hops, default sensor noise (2 N force, 1 mm
markers), cached per session. Seeds and frequencies are fixed; the hit-rate
study (bench/discovery_hit_rates.py) covers many seeds.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.discovery.forward import law_forward_gap
from hop_impedance.discovery.identify import compliance_index, surface_split
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.workflow import discover
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import (
    EffectSizes,
    ground_law,
    nominal_touchdown_speed,
    simulate_stance_set_recording,
    sized_law,
)
from hop_impedance.simulation.impedance_laws import CompositeLaw, PushOff
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.stance import simulate_stance

BASE = dict(angle_dependent_stiffness=False, damping=False, push_off=False)
#: name -> (law switches, surfaces, sensor effects, frequency, seed)
CASES = {
    "null": ({}, ("rigid",), {}, 2.2, 2),
    "rate": ({"rate_dependent_stiffness": True}, ("rigid",), {}, 1.87, 1),
    "rate_2.2": ({"rate_dependent_stiffness": True}, ("rigid",), {}, 2.2, 2),
    "damping": ({"damping": True}, ("rigid",), {}, 2.2, 2),
    "activation_two_surfaces": ({"time_activation": True}, ("hard", "soft"), {}, 2.2, 1),
    "hard": ({}, ("hard",), {}, 2.2, 2),
    "angle+offset": ({"angle_dependent_stiffness": True}, ("rigid",), {"force_offset_n": 20.0}, 2.2, 2),
    "offset": ({}, ("rigid",), {"force_offset_n": 20.0}, 2.2, 2),
}
_CACHE: dict = {}
_DOCS: dict = {}


def recording(name: str):
    """Cached (recording, truth) of a named case."""
    if name not in _CACHE:
        law, surfaces, sensors, freq, seed = CASES[name]
        _CACHE[name] = simulate_stance_set_recording(freq, surfaces, 8, seed=seed, effects=Effects(**{**BASE, **law}),
                                                     sensors=SensorConfig(**sensors), rtol=1e-6, sizes=EffectSizes(),
                                                     redraws=10)
    return _CACHE[name]


def discovered(name: str, forward: bool = False) -> dict:
    """Cached discovery document of a case."""
    key = (name, forward)
    if key not in _DOCS:
        _DOCS[key] = discover(recording(name)[0], forward=forward)
    return _DOCS[key]


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
    assert push.amplitude_nm[0] == pytest.approx(0.3 * st.moments_nm[:, 0].max(), rel=1e-6)
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


@pytest.mark.parametrize("name,expected", [
    ("null", []),
    ("rate", ["rate_dependent_stiffness"]),
    ("damping", ["joint_damping"]),
    ("hard", ["surface_compliance"]),
    ("offset", ["force_plate_offset"]),
])
def test_sized_hidden_effect_is_named_and_nothing_else(name, expected):
    doc = discovered(name)
    assert doc["effects_found"] == expected, doc["selection"]["rounds"]


def test_activation_is_told_from_angle_stiffness_with_hops_on_two_surfaces():
    """Hard and soft hops: same activation time course, different angle courses; both effects named."""
    doc = discovered("activation_two_surfaces")
    assert sorted(doc["effects_found"]) == ["surface_compliance", "time_dependent_activation"]
    act = next(st for st in doc["steps"] if st["effect"] == "time_dependent_activation")
    assert "angle_dependent_stiffness" not in [a["effect"] for a in act["ambiguous_with"]]
    assert act["parameters"]["tau_s"] == pytest.approx(0.05, abs=0.03)


def test_two_hidden_effects_are_both_named():
    doc = discovered("angle+offset")
    assert sorted(doc["effects_found"]) == ["angle_dependent_stiffness", "force_plate_offset"]
    off = next(st for st in doc["steps"] if st["effect"] == "force_plate_offset")
    assert off["parameters"]["offset_n"] == pytest.approx(20.0, abs=1.0)


def test_look_alike_effect_is_reported_ambiguous():
    """Rate-dependent stiffness at 2.2 Hz (short stances): the push-off pulse explains the same moment
    course as k3 S within noise; the workflow names one and lists rate_dependent_stiffness as ambiguous
    with the separating evidence, rather than claiming certainty."""
    doc = discovered("rate_2.2")
    named = doc["effects_found"]
    listed = {a["effect"]: a for st in doc["steps"] for a in st["ambiguous_with"]}
    assert "rate_dependent_stiffness" in named or "rate_dependent_stiffness" in listed
    if "rate_dependent_stiffness" in listed:
        assert listed["rate_dependent_stiffness"]["p_value_difference"] > 0.05
        assert listed["rate_dependent_stiffness"]["separating_evidence"]


@pytest.mark.slow
def test_gap_shrinks_on_held_out_stances_in_every_named_step():
    """Two-effect recording: each step's held-out forward gap shrinks on the signals the effect acts on."""
    doc = discovered("angle+offset", forward=True)
    acts_on = {"force_plate_offset": ("grf",),
               "angle_dependent_stiffness": ("moment_ankle", "moment_knee", "moment_hip")}
    assert len(doc["steps"]) == 2
    for st in doc["steps"]:
        for sig in acts_on[st["effect"]]:
            assert st["gap_after"][sig]["rms"] < st["gap_before"][sig]["rms"], (st["effect"], sig)


def _truth_floor(name: str) -> dict:
    """Noise floor of a case: held-out-free forward gap of the *true* law from the measured touchdown states."""
    law_switches, surfaces, sensors, freq, _ = CASES[name]
    assert surfaces == ("rigid",)
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    law, _ = sized_law(chain, freq, Effects(**{**BASE, **law_switches}), EffectSizes(), ground_law("rigid"))
    trial = measure_trial(recording(name)[0])
    return law_forward_gap(trial, law, ground_law("rigid"), sensors.get("force_offset_n", 0.0))


FLOOR_SIGNALS = ("grf", "moment_ankle", "moment_knee", "moment_hip")


@pytest.mark.slow
def test_final_gap_near_noise_floor_for_a_sensor_effect():
    """Offset recording (truth = constant stiffness + 20 N offset, inside the candidate set): the final
    gaps are within 60 % of the true law's gap (the floor). The 60 % is the measured cost of identifying even
    the right model family by regression on low-passed ID moments: ankle 9.1 N m final vs 6.7 N m with the
    true k0 (k0 recovered within ~10 %, see test_discovery.py)."""
    doc, floor = discovered("offset", forward=True), _truth_floor("offset")
    assert doc["steps"][0]["gap_after"]["grf"]["rms"] < doc["steps"][0]["gap_before"]["grf"]["rms"]
    for sig in FLOOR_SIGNALS:
        assert doc["final_gap"][sig]["rms"] < 1.6 * floor[sig]["rms"], (sig, doc["final_gap"][sig]["rms"], floor[sig])


@pytest.mark.slow
def test_final_gap_near_noise_floor_for_a_joint_effect():
    """Angle-dependent stiffness + offset: final gap within 60 % of the true law's gap and below the
    baseline's on every signal. Measured (seed 2, 2.2 Hz): truth floor GRF 219 N, moments 12.6/9.6/10.8 N m;
    final 251 N, 19.4/12.7/11.7 N m (ratios 1.14, 1.54, 1.33, 1.08); baseline 271 N, 21.7/17.2/12.1 N m.
    The remaining excess is the regression identification: k0, k1, k2 are collinear over one stance's
    angle range and the ID moments are biased near the trimmed edges."""
    doc, floor = discovered("angle+offset", forward=True), _truth_floor("angle+offset")
    for sig in FLOOR_SIGNALS:
        final = doc["final_gap"][sig]["rms"]
        assert final < 1.6 * floor[sig]["rms"], (sig, final, floor[sig]["rms"])
        assert final < doc["baseline_gap"][sig]["rms"], sig


def test_two_surface_law_of_the_soft_hops_is_seed_001s_soft_surface():
    """Soft hops of the hard/soft recording: Fz = 7.5e4 |y|^1.4 - 68.4 y' (seed 001). Measured: k = 7.58e4,
    n = 1.43 (grid p = 0.7), d = 68.1 N s/m. (The hard surface's law is not recovered: its ~1 cm give puts
    the exponent at the grid edge, n = 3.3 vs 2.0; see docs/discovery.md.)"""
    doc = discovered("activation_two_surfaces")
    par = next(st for st in doc["steps"] if st["effect"] == "surface_compliance")["parameters"]
    assert par["stiffness_n_per_m_n"] == pytest.approx(7.5e4, rel=0.1)
    assert par["exponent_n"] == pytest.approx(1.4, abs=0.15)
    assert par["damping_n_s_per_m"] == pytest.approx(68.4, rel=0.15)
    assert par["two_surfaces"]["stiffer_surface"]["stiffness_n_per_m_n"] > 10 * par["stiffness_n_per_m_n"]
