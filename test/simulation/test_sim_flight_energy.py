"""Issue 17: a flight that keeps the energy of segment motion, and the trunk-balance moment at the hip."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import (
    chain_from_body_model,
    com_offset_jacobian,
    internal_kinetic_energy_j,
    internal_mass_matrix,
    mechanical_energy_j,
)
from hop_impedance.simulation.ground import HARD, lossless
from hop_impedance.simulation.hopping_trial import (
    simulate_hopping,
    touchdown_posture,
    touchdown_segment_rates,
    touchdown_state,
)
from hop_impedance.simulation.impedance_laws import Eq3Law, TrunkBalance
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT, Effects, hopping_config
from hop_impedance.simulation.stance import simulate_stance, stance_energy_j

CHAIN = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))


def test_internal_kinetic_energy_is_total_minus_com_translation():
    """König: 0.5 gd^T M gd = 0.5 m v_com^2 + internal part, for any state (independent route via the full M)."""
    rng = np.random.default_rng(3)
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    for _ in range(5):
        qd, v_com = rng.normal(0, 3, 4), rng.normal(0, 1, 2)
        toe_v = v_com - com_offset_jacobian(CHAIN, q) @ qd
        g, gd = np.r_[0.0, 0.0, q], np.r_[toe_v, qd]
        kinetic, _ = mechanical_energy_j(CHAIN, g, gd)
        translation = 0.5 * CHAIN.total_mass_kg * float(v_com @ v_com)
        assert kinetic == pytest.approx(translation + internal_kinetic_energy_j(CHAIN, q, qd), rel=1e-12)


def test_touchdown_rates_carry_the_requested_energy_and_keep_the_toe_still():
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    direction = np.array([3.0, -4.0, 6.0, -1.0])
    for vx, energy in ((0.0, 7.5), (0.08, 2.0), (-0.05, 20.0)):
        rates, not_placed = touchdown_segment_rates(CHAIN, q, vx, direction, energy)
        assert not_placed == 0.0
        assert internal_kinetic_energy_j(CHAIN, q, rates) == pytest.approx(energy, rel=1e-10)
        td = touchdown_state(CHAIN, q, np.array([vx, -1.0]), 0.0, rates)
        np.testing.assert_allclose(td.gd[2:], rates, atol=1e-12)  # already free of horizontal toe motion
        toe_x_velocity = vx - com_offset_jacobian(CHAIN, q)[0] @ td.gd[2:]
        assert abs(toe_x_velocity) < 1e-12
    # Less energy than the rates that only cancel vx carry: nothing to scale, the shortfall is reported.
    rates, not_placed = touchdown_segment_rates(CHAIN, q, 0.3, direction, 0.0)
    assert not_placed < 0.0 and internal_kinetic_energy_j(CHAIN, q, rates) == pytest.approx(-not_placed)


def test_trunk_balance_moment_is_added_at_the_hip_and_its_work_is_the_energy_change():
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8])
    trunk = TrunkBalance(800.0)
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.0, -1.0]), 0.0)
    ground = lossless(HARD)
    st = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=np.linspace(0, 0.6, 3000),
                         trunk_balance=trunk)
    assert st.end_reason == "take_off"
    expected_hip = -800.0 * (st.g[:, 5] - q[3])
    np.testing.assert_allclose(st.trunk_moments_nm[:, 2], expected_hip, atol=1e-9)
    law_only = law.moments_nm(st.t_s, st.rho_rad, st.omega_rad_s, st.law_states, st.ref)
    np.testing.assert_allclose(st.moments_nm - law_only, st.trunk_moments_nm, atol=1e-9)
    # Energy bookkeeping: springs + ground + body change only by the balance moment's work at the hip.
    energy = stance_energy_j(CHAIN, law, ground, st)
    work = cumulative_trapezoid(-st.trunk_moments_nm[:, 2] * st.omega_rad_s[:, 2], st.t_s, initial=0.0)
    assert np.abs(energy - energy[0] - work).max() < 0.02 * np.abs(work).max()
    assert np.abs(work).max() > 0.1  # the balance moment did work (the check is not trivially flat)
    # ...and it keeps the trunk nearer its touchdown inclination than the hip law alone.
    free = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=np.linspace(0, 0.6, 300))
    assert np.abs(st.g[:, 5] - q[3]).max() < 0.75 * np.abs(free.g[:, 5] - q[3]).max()  # measured 0.024 vs 0.044 rad


@pytest.fixture(scope="module")
def lossless_trial():
    """No damping, no push-off, lossless surface, no sliding: nothing may be lost in flight."""
    chain, cfg = hopping_config(2.2, "hard", 3, Effects(damping=False, push_off=False), variability=False)
    cfg = dataclasses.replace(cfg, surface=lossless(HARD), friction_coefficient=None,
                              trunk_balance=TrunkBalance(800.0), flight="energy_keeping")
    return simulate_hopping(chain, cfg, seed=1)


def test_energy_at_touchdown_equals_energy_at_the_previous_take_off(lossless_trial):
    """Kinetic + gravitational + energy stored in the joint springs (about the stance's own touchdown
    reference), take-off vs next touchdown: equal to 1e-6 relative (issue 17)."""
    tr = lossless_trial
    assert tr.stop_reason == "" and len(tr.stances) == 3
    chain = tr.chain
    for rec, nxt in zip(tr.stances[:-1], tr.stances[1:]):
        st = rec.stance

        def energy(g, gd, rho, law=rec.law, ref=st.ref):
            return sum(mechanical_energy_j(chain, g, gd)) + float(law.elastic_energy_j(rho, ref))

        e_takeoff = energy(st.g[-1], st.gd[-1], st.rho_rad[-1])
        e_touchdown = energy(nxt.touchdown.g, nxt.touchdown.gd, nxt.stance.rho_rad[0])
        assert abs(e_touchdown - e_takeoff) / e_takeoff < 1e-6, (e_takeoff, e_touchdown)
        # Not trivially equal: segment motion relative to the COM is carried across (joules, not zero).
        assert internal_kinetic_energy_j(chain, nxt.touchdown.g[2:], nxt.touchdown.gd[2:]) > 0.1


def test_prescribed_flight_discards_segment_energy_and_stays_the_default():
    """The default (prescribed) flight brings the segments to rest: energy at touchdown is lower (the
    loss issue 17 measured), which is what the energy-keeping flight removes."""
    chain, cfg = hopping_config(2.2, "hard", 2, Effects(damping=False, push_off=False), variability=False)
    assert cfg.flight == "prescribed"
    cfg = dataclasses.replace(cfg, surface=lossless(HARD), friction_coefficient=None)
    tr = simulate_hopping(chain, cfg, seed=1)
    st, nxt = tr.stances[0].stance, tr.stances[1]
    e_to = sum(mechanical_energy_j(chain, st.g[-1], st.gd[-1]))
    e_td = sum(mechanical_energy_j(chain, nxt.touchdown.g, nxt.touchdown.gd))
    lost = internal_kinetic_energy_j(chain, st.g[-1, 2:], st.gd[-1, 2:]) - internal_kinetic_energy_j(
        chain, nxt.touchdown.g[2:], nxt.touchdown.gd[2:])
    assert e_to - e_td == pytest.approx(lost, rel=1e-6)
    assert e_to - e_td > 0.5


def test_with_energy_keeping_flight_the_push_off_only_replaces_stance_losses():
    """Default law (damping, push-off) with the trunk balance at 2.2 Hz: the flight keeps the segment energy
    (flight term 0), so the push-off is exactly what damping, the ground and the trunk balance take plus the
    change of touchdown energy (the springs left at take-off come back in flight). With the prescribed
    flight the push-off also pays for the discarded segment energy (bench/simulator_energy_budget.py)."""
    from hop_impedance.simulation.energy_budget import trial_energy_budget
    from hop_impedance.simulation.scenarios import TRUNK_BALANCE

    chain, cfg = hopping_config(2.2, "hard", 2, variability=False, trunk_balance=TRUNK_BALANCE,
                                flight="energy_keeping")
    tr = simulate_hopping(chain, cfg, seed=1)
    assert tr.stop_reason == ""
    b, nxt = trial_energy_budget(tr)
    assert abs(b["flight_j"]) < 1e-6 * b["e_takeoff_j"]
    losses = b["damping_j"] - b["ground_j"] - b["trunk_balance_j"]
    gain = nxt["e_touchdown_j"] - b["e_touchdown_j"]
    assert b["push_off_j"] == pytest.approx(losses + gain, abs=0.1)
    assert losses > 5.0 and abs(gain) < 0.5 * losses  # measured: losses ~10 J, a near-periodic hop


def flight_energies(chain, trial) -> list:
    """Per flight of ``trial``: (energy at take-off, energy at the next touchdown, the stance's record, the next
    stance's), each energy the segments' mechanical energy plus the Eq. 3 springs' about the stance's touchdown
    reference (J)."""
    out = []
    for rec, nxt in zip(trial.stances[:-1], trial.stances[1:]):
        st, springs = rec.stance, rec.law.part(Eq3Law)

        def energy(g, gd, rho, springs=springs, ref=st.ref):
            return sum(mechanical_energy_j(chain, g, gd)) + float(springs.elastic_energy_j(rho, ref))

        out.append((energy(st.g[-1], st.gd[-1], st.rho_rad[-1]),
                    energy(nxt.touchdown.g, nxt.touchdown.gd, nxt.stance.rho_rad[0]), rec, nxt))
    return out


def test_landing_along_the_prescribed_flights_motion_keeps_the_energy_and_its_direction():
    """``landing="prescribed"``: the energy-keeping flight lands along the prescribed flight's landing motion
    (hopping_trial.prescribed_landing_direction) instead of the reversed take-off rates; the energy at touchdown
    still equals the previous take-off's (1e-6 relative), and the landing rates are that direction (less its
    toe-moving part) scaled to carry it."""
    from hop_impedance.simulation.dynamics import body_com, com_velocity
    from hop_impedance.simulation.hopping_trial import flight_time_s, prescribed_landing_direction
    from hop_impedance.simulation.scenarios import TRUNK_BALANCE

    # The default law (damping, push-off): its lossless counterpart bounces off at the second touchdown with this
    # landing (measured, session 21); the flight's energy balance does not depend on the stance's losses.
    chain, cfg = hopping_config(2.2, "hard", 3, variability=False, trunk_balance=TRUNK_BALANCE,
                                flight="energy_keeping", landing="prescribed")
    tr = simulate_hopping(chain, cfg, seed=1)
    assert tr.stop_reason == "" and len(tr.stances) == 3
    reversed_tr = simulate_hopping(chain, dataclasses.replace(cfg, landing="reversed"), seed=1)
    for e_takeoff, e_touchdown, rec, nxt in flight_energies(chain, tr):
        st = rec.stance
        assert abs(e_touchdown - e_takeoff) / e_takeoff < 1e-6
        q_next, rates = nxt.touchdown.g[2:], nxt.touchdown.gd[2:]
        v_to = com_velocity(chain, st.g[-1], st.gd[-1])
        t_f = flight_time_s(chain, body_com(chain, st.g[-1])[1], v_to[1], q_next)
        direction = prescribed_landing_direction(chain, st, q_next, float(v_to[0]), t_f)
        j0 = com_offset_jacobian(chain, q_next)[0]
        base = j0 * (float(v_to[0]) / float(j0 @ j0))
        u = direction - j0 * (float(j0 @ direction) / float(j0 @ j0))
        extra = rates - base
        cosine = float(extra @ u) / (np.linalg.norm(extra) * np.linalg.norm(u))
        assert cosine > 1.0 - 1e-9  # parallel, same sense
    # ...and it is another landing than the reversed take-off rates'.
    assert not np.allclose(tr.stances[1].touchdown.gd, reversed_tr.stances[1].touchdown.gd, atol=1e-3)


def test_trunk_held_rates_stop_the_trunk_and_report_its_share():
    """hopping_trial.trunk_held_segment_rates (session 24): zero trunk rate, the toe still horizontally, the legs
    carrying the energy less the trunk's share of the energy-keeping landing, that share the reported loss."""
    from hop_impedance.simulation.hopping_trial import trunk_held_segment_rates

    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    direction = np.array([3.0, -4.0, 6.0, -1.0])
    for vx, energy in ((0.0, 7.5), (0.08, 2.0), (-0.05, 20.0)):
        rates, loss, not_placed = trunk_held_segment_rates(CHAIN, q, vx, direction, energy)
        full, _ = touchdown_segment_rates(CHAIN, q, vx, direction, energy)
        # the trunk's share: what stopping the trunk by an impulse along q4 takes out (M-orthogonal split)
        m_inv = np.linalg.inv(internal_mass_matrix(CHAIN, q))
        stopped = full - m_inv[:, 3] * (full[3] / m_inv[3, 3])
        assert abs(stopped[3]) < 1e-12
        assert not_placed == 0.0 and rates[3] == 0.0 and 0.0 < loss < energy
        assert loss == pytest.approx(energy - internal_kinetic_energy_j(CHAIN, q, stopped), rel=1e-10)
        assert internal_kinetic_energy_j(CHAIN, q, rates) == pytest.approx(energy - loss, rel=1e-10)
        assert abs(vx - com_offset_jacobian(CHAIN, q)[0] @ rates) < 1e-12  # the toe still horizontally
        if vx == 0.0:  # no toe correction: the legs move along the direction's leg part less its toe-moving part
            j0 = com_offset_jacobian(CHAIN, q)[0].copy()
            j0[3] = 0.0
            leg_dir = np.r_[direction[:3], 0.0]
            u = leg_dir - j0 * (float(j0 @ leg_dir) / float(j0 @ j0))
            assert float(rates @ u) / (np.linalg.norm(rates) * np.linalg.norm(u)) > 1.0 - 1e-12


def test_trunk_held_flight_loses_exactly_the_reported_balance_loss():
    """``flight="trunk_held"``: the trunk lands without pitching (zero absolute trunk rate at every touchdown, the
    calibrated one included), and energy at touchdown = energy at the previous take-off - the balance's reported
    flight loss (1e-6 relative), reported in the trial and in the energy budget beside the push-off's work."""
    from hop_impedance.simulation.energy_budget import trial_energy_budget
    from hop_impedance.simulation.scenarios import TRUNK_BALANCE

    chain, cfg = hopping_config(2.2, "hard", 3, variability=False, trunk_balance=TRUNK_BALANCE,
                                flight="trunk_held", landing="prescribed")
    tr = simulate_hopping(chain, cfg, seed=1)
    assert tr.stop_reason == "" and len(tr.stances) == 3
    assert tr.calibration.touchdown_rates_rad_s[3] == 0.0
    assert len(tr.flight_balance_loss_j) == 2
    budget = trial_energy_budget(tr)
    for (e_takeoff, e_touchdown, _, nxt), loss, row in zip(flight_energies(chain, tr), tr.flight_balance_loss_j, budget):
        assert abs(e_touchdown - (e_takeoff - loss)) / e_takeoff < 1e-6, (e_takeoff, e_touchdown, loss)
        assert abs(nxt.touchdown.gd[5]) < 1e-12  # the trunk's absolute pitch rate at touchdown
        assert internal_kinetic_energy_j(chain, nxt.touchdown.g[2:], nxt.touchdown.gd[2:]) > 0.1  # the legs carry some
        assert loss > 1e-3 and row["flight_balance_loss_j"] == loss and "push_off_j" in row
    assert abs(tr.stances[0].touchdown.gd[5]) < 1e-12


def test_trunk_still_flight_lands_the_trunk_at_rest_and_keeps_all_the_energy():
    """``flight="trunk_still"`` (session 32): zero absolute trunk rate at every touchdown, the calibrated one included,
    and, unlike ``"trunk_held"``, nothing taken out: energy at touchdown = energy at the previous take-off (1e-6
    relative), the legs carrying the whole carried energy (no balance loss reported)."""
    from hop_impedance.simulation.energy_budget import trial_energy_budget
    from hop_impedance.simulation.scenarios import TRUNK_BALANCE

    chain, cfg = hopping_config(2.2, "hard", 3, variability=False, trunk_balance=TRUNK_BALANCE,
                                flight="trunk_still", landing="prescribed")
    tr = simulate_hopping(chain, cfg, seed=1)
    assert tr.stop_reason == "" and len(tr.stances) == 3
    assert tr.calibration.touchdown_rates_rad_s[3] == 0.0 and abs(tr.stances[0].touchdown.gd[5]) < 1e-12
    assert tr.flight_balance_loss_j == [0.0, 0.0]
    budget = trial_energy_budget(tr)
    for (e_takeoff, e_touchdown, _, nxt), row in zip(flight_energies(chain, tr), budget):
        assert abs(e_touchdown - e_takeoff) / e_takeoff < 1e-6, (e_takeoff, e_touchdown)
        assert abs(row["flight_j"]) / e_takeoff < 1e-6 and "flight_balance_loss_j" not in row
        assert abs(nxt.touchdown.gd[5]) < 1e-12  # the trunk's absolute pitch rate at touchdown
        assert internal_kinetic_energy_j(chain, nxt.touchdown.g[2:], nxt.touchdown.gd[2:]) > 0.1  # the legs carry it
