"""``forward_selection.ENERGY_PAIRS`` (session 19, an option): a loss and the push-off that replaces it, tried together.

Our simulator's push-off on the soft surface at 1.53 Hz (``bench/discovery_hit_rates.py`` case ``two:push+soft``,
seed 0, 8 hops) is the case: the soft surface takes energy every stance and the push-off gives it back. Neither
effect alone makes the stances simulate like the measured ones (held out, with the touchdown-velocity fit: the
surface alone -30 %, the push-off alone -16 %), the two together shrink the held-out gap by 95 %; so a selection
that adds one effect at a time names nothing there (session 17's sweep). With the option the second look names both.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec, members
from hop_impedance.discovery.workflow import discover

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from discovery_hit_rates import generate  # noqa: E402  (the bench's own case, so test and bench are one recording)

PAIR = "surface_compliance+active_push_off"


@pytest.fixture(scope="module")
def push_soft():
    rec, freq = generate("two:push+soft", 0, 8)
    assert freq == 1.53
    return rec, measure_trial(rec)


def test_a_pair_is_identified_as_its_loss_then_its_push_off(push_soft):
    _, trial = push_soft
    spec, coefs = identify(ModelSpec(), trial, trial.stances, PAIR)
    loss, _ = identify(ModelSpec(), trial, trial.stances, "surface_compliance")
    both, coefs2 = identify(loss, trial, trial.stances, "active_push_off")
    assert spec == both and spec.effects == ("surface_compliance", "active_push_off")
    assert np.array_equal(coefs, coefs2)
    assert members(PAIR) == ("surface_compliance", "active_push_off")


def test_pairs_are_looked_at_only_with_the_option_and_net_positive_measured_work(push_soft, monkeypatch):
    _, trial = push_soft
    assert fs.energy_pairs(ModelSpec(), trial) == ()  # the option is off by default
    monkeypatch.setattr(fs, "ENERGY_PAIRS", True)
    # the push-off replaces the soft surface's loss: the joints do net positive work in every stance (11-37 J)
    work = np.array([fs.measured_net_work_j(s) for s in trial.stances])
    assert np.all(work > 5.0)
    assert fs.energy_pairs(ModelSpec(), trial) == (PAIR, "joint_damping+active_push_off")
    assert fs.energy_pairs(ModelSpec(effects=("joint_damping",)), trial) == (PAIR,)
    assert fs.energy_pairs(ModelSpec(effects=("active_push_off",)), trial) == ()
    # a null of our simulator (elastic joints, lossy rigid ground): net joint work <= 0, nothing is looked at
    null, _ = generate("null", 2, 6)
    null_trial = measure_trial(null)
    assert not fs.measured_work_positive(null_trial)
    assert fs.energy_pairs(ModelSpec(), null_trial) == ()


def test_a_pair_is_admissible_only_when_each_member_is():
    physics = {"measured_net_joint_work_j": {"mean": 20.0, "p_positive": 1e-4},
               "work_mismatch_j": {"candidate": 5.0, "current": 30.0}}
    assert fs.admissible(PAIR, physics) == (True, "")
    lossless = {**physics, "measured_net_joint_work_j": {"mean": 0.3, "p_positive": 0.4}}
    ok, why = fs.admissible(PAIR, lossless)
    assert not ok and "no energy for a push-off to add" in why
    worse = {**physics, "work_mismatch_j": {"candidate": 31.0, "current": 30.0}}
    assert not fs.admissible(PAIR, worse)[0]


@pytest.mark.slow
def test_push_off_on_the_soft_surface_is_named_as_the_pair(push_soft, monkeypatch):
    rec, _ = push_soft
    monkeypatch.setattr(fs, "TOUCHDOWN_VELOCITY_FIT_S", 0.06)
    monkeypatch.setattr(fs, "ENERGY_PAIRS", True)
    doc = discover(rec)
    assert sorted(doc["effects_found"]) == ["active_push_off", "surface_compliance"]
    first = doc["selection"]["rounds"][0]
    # one at a time neither passes (held-out p 0.64 and 0.53; each makes the gap larger) ...
    for one in members(PAIR):
        assert first[one]["p_value"] > 0.05 and first[one]["held_out_shrink"] < 0.0
    # ... together they shrink it by 95 % (0.087 -> 0.004), every held-out stance better by more than 10x (the cap)
    step = doc["steps"][0]
    assert step["effect"] == PAIR
    assert step["gap_after"]["total"] < 0.1 * step["gap_before"]["total"]
    assert min(step["evidence"]["per_stance_log_gap_ratio"]) > np.log(5.0)
    assert set(step["parameters"]) == set(members(PAIR))
    assert len(doc["timing"]["rounds"]) == len(doc["selection"]["rounds"])  # the pairs' time is their round's
    # the energy balance: the pair brings the simulated net joint work near the measured (+27 J per stance)
    phys = step["evidence"]["physics"]
    assert phys["work_mismatch_j"]["candidate"] < 0.5 * phys["work_mismatch_j"]["current"]
