"""Issue 17: with lossless laws the push-off-free hopper keeps its hop for 30 hops.

The seed-like hopper (toe-tip contact and flexed touchdown posture, scenarios.seed_like_options) with
no damping, no push-off, a lossless surface and the energy-keeping flight. Its trunk is held either by
the active trunk balance (scenarios.TRUNK_BALANCE: a moment on the trunk's absolute pitch, acting at
the hip) or by a hip spring of the same stiffness (scenarios.HIP_TRUNK_SPRING_NM_RAD): only the
spring is conservative, and only with it does the hop keep its energy.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import trapezoid

from hop_impedance.simulation.dynamics import (
    body_com,
    com_offset_jacobian,
    com_velocity,
    internal_kinetic_energy_j,
    mechanical_energy_j,
)
from hop_impedance.simulation.hopping_trial import flight_segment_rates, simulate_hopping, simulate_resample
from hop_impedance.simulation.periodic_hop import hop_step, touchdown_vector
from hop_impedance.simulation.scenarios import lossless_hopper_config, seed_like_options


def lossless_trial(hops: int, hip_spring: bool):
    chain, config = lossless_hopper_config(2.2, hops, seed_like_options(), "hard",
                                           "hip_spring" if hip_spring else "balance")
    return simulate_hopping(chain, config, seed=1)


def touchdown_energy_j(trial, rec) -> float:
    return float(sum(mechanical_energy_j(trial.chain, rec.touchdown.g, rec.touchdown.gd)))


@pytest.fixture(scope="module")
def hip_spring_trial():
    return lossless_trial(30, hip_spring=True)


def test_lossless_hopper_keeps_its_hop_for_30_hops(hip_spring_trial):
    """Issue 17: >= 30 hops without a push-off, hop 30's stance time and apex height within 5 % of hop 3's
    (bench/simulator_energy_budget.py --lossless --seed-like --balance hip_spring measured +1.2 % and
    +0.05 %)."""
    tr = hip_spring_trial
    assert tr.stop_reason == "" and len(tr.stances) == 30

    def stance_and_apex(rec):
        g, gd = rec.stance.g[-1], rec.stance.gd[-1]
        vz = com_velocity(tr.chain, g, gd)[1]
        return rec.stance.duration_s, body_com(tr.chain, g)[1] + max(vz, 0.0) ** 2 / (2 * tr.chain.gravity_m_s2)

    (ts3, apex3), (ts30, apex30) = stance_and_apex(tr.stances[2]), stance_and_apex(tr.stances[29])
    assert abs(ts30 / ts3 - 1) < 0.05
    assert abs(apex30 / apex3 - 1) < 0.05
    # a hop, not a bounce: the stance is a real fraction of the 2.2 Hz period and the body leaves the ground
    assert 0.2 < ts30 < 0.3 and apex30 > body_com(tr.chain, tr.stances[29].touchdown.g)[1] + 0.05


def test_lossless_hopper_keeps_its_energy_and_its_trunk(hip_spring_trial):
    """Nothing is gained or lost over 30 hops: kinetic + gravitational energy at every touchdown equals the
    first one's (the touchdown posture is the springs' reference, so they store nothing there); the hip
    spring holds the trunk within 0.05 rad of its touchdown pitch."""
    tr = hip_spring_trial
    e0 = touchdown_energy_j(tr, tr.stances[0])
    drift = max(abs(touchdown_energy_j(tr, rec) - e0) for rec in tr.stances) / e0
    assert drift < 1e-6  # measured 3e-8
    pitch = max(np.abs(rec.stance.g[:, 5] - rec.touchdown.g[5]).max() for rec in tr.stances)
    assert pitch < 0.05  # rad; measured 0.017


def test_hop_map_is_the_trials_noise_free_hop(hip_spring_trial):
    """periodic_hop.hop_step from the trial's first touchdown gives the trial's second touchdown."""
    tr = hip_spring_trial
    cal, first, second = tr.calibration, tr.stances[0], tr.stances[1]
    x1, st = hop_step(tr.chain, tr.config, cal,
                      touchdown_vector(cal.speed_m_s, 0.0, cal.com_ahead_m, cal.touchdown_rates_rad_s))
    assert st.duration_s == pytest.approx(first.stance.duration_s, abs=1e-9)
    v2 = com_velocity(tr.chain, second.touchdown.g, second.touchdown.gd)
    ahead2 = body_com(tr.chain, second.touchdown.g)[0] - second.touchdown.g[0]
    expected = touchdown_vector(-v2[1], v2[0], ahead2, second.touchdown.gd[2:])
    np.testing.assert_allclose(x1, expected, atol=1e-9)


def test_active_trunk_balance_is_the_energy_source_of_the_drifting_hop():
    """With TRUNK_BALANCE instead, the lossless hop gains energy hop after hop, and the gain is the balance
    moment's work at the hip (its reaction on the thigh: a moment on the trunk's absolute pitch has no
    potential)."""
    tr = lossless_trial(4, hip_spring=False)
    assert len(tr.stances) == 4
    gains, works = [], []
    for rec, nxt in zip(tr.stances[:-1], tr.stances[1:]):
        t = np.linspace(0.0, rec.stance.duration_s, 4001)
        st = simulate_resample(tr.chain, rec, t)
        works.append(trapezoid(-st.trunk_moments_nm[:, 2] * st.omega_rad_s[:, 2], t))
        gains.append(touchdown_energy_j(tr, nxt) - touchdown_energy_j(tr, rec))
    np.testing.assert_allclose(gains, works, atol=1e-3)  # J; measured within 1e-5 J
    assert sum(gains) > 5.0  # J over three hops: measured 1.2 + 3.0 + 7.4 J


def test_landing_rates_choose_the_direction_and_keep_the_energy(hip_spring_trial):
    """HoppingConfig.landing_rates_rad_s: the energy-keeping flight lands along the given rates (their part
    that does not slide the toe) with the same energy as along the reversed take-off rates."""
    tr = hip_spring_trial
    rec, q_next = tr.stances[0], tr.stances[1].touchdown.g[2:]
    vx = float(com_velocity(tr.chain, tr.stances[1].touchdown.g, tr.stances[1].touchdown.gd)[0])
    reversed_rates, carried, _ = flight_segment_rates(tr.chain, rec.law, rec.stance, q_next, vx)
    landing = np.array([1.0, -0.5, 0.3, 0.2])
    rates, carried_too, not_placed = flight_segment_rates(tr.chain, rec.law, rec.stance, q_next, vx, landing)
    assert carried_too == carried and not_placed == 0.0
    assert internal_kinetic_energy_j(tr.chain, q_next, rates) == pytest.approx(carried, rel=1e-10)
    assert internal_kinetic_energy_j(tr.chain, q_next, reversed_rates) == pytest.approx(carried, rel=1e-10)
    j0 = com_offset_jacobian(tr.chain, q_next)[0]
    base = j0 * (vx / float(j0 @ j0))
    along = landing - j0 * (float(j0 @ landing) / float(j0 @ j0))
    scale = float((rates - base) @ along) / float(along @ along)
    assert scale > 0
    np.testing.assert_allclose(rates - base, scale * along, atol=1e-12)
