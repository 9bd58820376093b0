"""Issue 17 (session 26): the passive knee-ankle (gastrocnemius-like) spring, off by default."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import chain_from_body_model, mechanical_energy_j
from hop_impedance.simulation.energy_budget import stance_energy_budget
from hop_impedance.simulation.ground import HARD, lossless
from hop_impedance.simulation.hopping_trial import simulate_hopping, touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import (
    BiarticularSpring,
    CompositeLaw,
    Eq3Law,
    TouchdownReference,
    TrunkBalance,
)
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT, Effects, hopping_config
from hop_impedance.simulation.simulate import simulate_recording
from hop_impedance.simulation.stance import simulate_stance, stance_energy_j

CHAIN = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
REF = TouchdownReference(np.array([1.9, 3.6, 3.7]), np.zeros(3))
SPRING = BiarticularSpring(150.0, 1.0, 0.6)


def test_moments_are_the_potentials_gradient_with_the_muscles_signs():
    """M_j = dE/drho_j (extensor positive, as Eq. 3's k0 dr) to 1e-9 N m; stretched by dorsiflexion or knee extension
    it is an ankle plantarflexor (+) and a knee flexor (-); no hip moment; the co-flexion d_knee / d_ankle = r_a / r_k
    is free, the zig-zag (ankle and knee opposite) is stiff."""
    rng = np.random.default_rng(4)
    h = 1e-5
    for _ in range(20):
        rho = REF.rho0_rad + rng.normal(0.0, 0.3, 3)
        m = SPRING.moments_nm(np.float64(0.1), rho, np.zeros(3), np.zeros(0), REF)
        grad = [(SPRING.elastic_energy_j(rho + h * e, REF) - SPRING.elastic_energy_j(rho - h * e, REF)) / (2 * h)
                for e in np.eye(3)]
        np.testing.assert_allclose(m, grad, rtol=0, atol=1e-9)
    dorsiflexed = SPRING.moments_nm(0.0, REF.rho0_rad + [0.1, 0.0, 0.0], np.zeros(3), np.zeros(0), REF)
    assert dorsiflexed[0] == pytest.approx(150.0 * 0.1) and dorsiflexed[1] == pytest.approx(-150.0 * 0.6 * 0.1)
    knee_extended = SPRING.moments_nm(0.0, REF.rho0_rad + [0.0, -0.1, 0.0], np.zeros(3), np.zeros(0), REF)
    assert knee_extended[0] > 0 > knee_extended[1] and knee_extended[2] == 0.0
    co_flexion = REF.rho0_rad + 0.2 * np.array([0.6, 1.0, 0.5])
    np.testing.assert_allclose(SPRING.moments_nm(0.0, co_flexion, np.zeros(3), np.zeros(0), REF), 0.0, atol=1e-12)
    zig_zag = REF.rho0_rad + 0.01 * np.array([-1.0, 1.0, 0.0])
    assert SPRING.elastic_energy_j(zig_zag, REF) == pytest.approx(0.5 * 150.0 * (0.01 * 1.6) ** 2)
    with pytest.raises(ValueError):
        BiarticularSpring(-1.0)


def test_off_by_default_and_a_part_of_the_law_when_on():
    """Without it the law is the same to the parameter; with it the Eq. 3 and push-off parts are unchanged and the
    spring sits after the Eq. 3 part in the trial's law (its passive stance too: the push-off timing may move)."""
    _, plain = hopping_config(2.2, "hard", 2, variability=False)
    _, none = hopping_config(2.2, "hard", 2, variability=False, biarticular=None)
    _, with_spring = hopping_config(2.2, "hard", 2, variability=False, biarticular=SPRING)
    assert plain.law.to_dict() == none.law.to_dict()
    assert plain.law.part(BiarticularSpring) is None
    assert isinstance(with_spring.law, CompositeLaw) and with_spring.law.part(BiarticularSpring) is SPRING
    assert [type(p).__name__ for p in with_spring.law.parts] == ["Eq3Law", "BiarticularSpring", "PushOff"]
    assert with_spring.law.part(Eq3Law).to_dict() == plain.law.part(Eq3Law).to_dict()


def test_a_lossless_stance_keeps_its_energy_with_the_spring():
    """Eq. 3 springs without damping + the biarticular spring on a lossless surface: kinetic + gravity + both springs'
    energy + the surface's constant to 1e-5 relative over the stance, while the biarticular spring stores joules."""
    law = CompositeLaw((Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8]), BiarticularSpring(200.0, 1.0, 0.5)))
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    ground = lossless(HARD)
    st = simulate_stance(CHAIN, law, ground, touchdown_state(CHAIN, q, np.array([0.0, -1.0]), 0.0), t_max_s=0.6,
                         sample_times_s=np.linspace(0, 0.6, 2000), rtol=1e-10, atol=1e-12)
    assert st.end_reason == "take_off"
    energy = stance_energy_j(CHAIN, law, ground, st)
    assert np.abs(energy - energy[0]).max() / energy[0] < 1e-5
    stored = law.parts[1].elastic_energy_j(st.rho_rad, st.ref)
    assert stored.max() > 0.5  # not trivially flat: the coupling is loaded


@pytest.fixture(scope="module")
def lossless_trial():
    """No damping, no push-off, lossless surface, no sliding, energy-keeping flight, with the spring (the trunk held by
    the balance as in test_sim_flight_energy.py: not conservative in stance, but the check is the flight's)."""
    chain, cfg = hopping_config(2.2, "hard", 3, Effects(damping=False, push_off=False), variability=False,
                                biarticular=BiarticularSpring(100.0, 1.0, 0.5))
    cfg = dataclasses.replace(cfg, surface=lossless(HARD), friction_coefficient=None, flight="energy_keeping",
                              trunk_balance=TrunkBalance(800.0))
    return simulate_hopping(chain, cfg, seed=1)


def test_the_energy_keeping_flight_returns_the_springs_energy(lossless_trial):
    """Take-off vs next touchdown: kinetic + gravity + the springs' energy (Eq. 3 and biarticular, about the stance's
    touchdown reference) equal to 1e-6 relative; the stance's budget books the spring's work against what it keeps."""
    tr = lossless_trial
    assert tr.stop_reason == "" and len(tr.stances) == 3
    for rec, nxt in zip(tr.stances[:-1], tr.stances[1:]):
        st = rec.stance

        def energy(g, gd, rho, law=rec.law, ref=st.ref):
            return sum(mechanical_energy_j(tr.chain, g, gd)) + float(law.elastic_energy_j(rho, ref))

        e_takeoff = energy(st.g[-1], st.gd[-1], st.rho_rad[-1])
        e_touchdown = energy(nxt.touchdown.g, nxt.touchdown.gd, nxt.stance.rho_rad[0])
        assert abs(e_touchdown - e_takeoff) / e_takeoff < 1e-6, (e_takeoff, e_touchdown)
    budget = stance_energy_budget(tr.chain, tr.stances[1])
    assert abs(budget["biarticular_j"] + budget["biarticular_left_j"]) < 0.02
    assert abs(budget["residual_j"]) < 0.1
    left = [float(r.law.part(BiarticularSpring).elastic_energy_j(r.stance.rho_rad[-1], r.stance.ref))
            for r in tr.stances]
    assert max(left) > 0.01, left  # the flight has the spring's energy to return (not trivially equal)


def test_the_truth_file_states_the_spring_and_its_share_of_the_net_moments():
    """Each stance names the spring and its moments; net = Eq. 3 + push-off + trunk balance + spring (to the file's
    7 digits); without the spring neither key is written (older truth files stay the same)."""
    options = {"variability": False, "trunk_balance": TrunkBalance(500.0, 60.0)}
    _, truth = simulate_recording(2.2, "hard", 2, seed=1, biarticular=SPRING, **options)
    stance = truth["stances"][1]
    assert stance["biarticular"]["stiffness_nm_rad"] == 150.0 and truth["law"]["parts"][1]["type"] == "biarticular"
    s = {k: np.asarray(v) for k, v in stance["samples"].items() if k.endswith("moments_nm")}
    parts = s["eq3_moments_nm"] + s["push_off_moments_nm"] + s["trunk_balance_moments_nm"] + s["biarticular_moments_nm"]
    np.testing.assert_allclose(s["moments_nm"], parts, rtol=0, atol=1e-4 * np.abs(s["moments_nm"]).max())
    assert np.abs(s["biarticular_moments_nm"][:, :2]).max() > 1.0 and np.all(s["biarticular_moments_nm"][:, 2] == 0)
    _, plain = simulate_recording(2.2, "hard", 2, seed=1, **options)
    assert "biarticular" not in plain["stances"][1] and "biarticular_moments_nm" not in plain["stances"][1]["samples"]
