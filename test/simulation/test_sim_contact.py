"""Ground contact at the tip of the toe (seed 000's virtual hinge) instead of the toe marker (issue 17)."""

from __future__ import annotations

import numpy as np
import pytest
from moment_truth import analysed_and_true_moments

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.biomech.joint_angles import joint_angles
from hop_impedance.simulation.dynamics import (
    body_com,
    chain_from_body_model,
    contact_ahead_of_toe_marker,
    heel_position,
    joint_positions,
    segment_com_positions,
    toe_marker_position,
)
from hop_impedance.simulation.scenarios import SEED_SUBJECT, seed_like_options, toe_tip_ahead_m
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.simulate import simulate_recording

MODEL = body_model_from_stature(SEED_SUBJECT)
MARKER_CHAIN = chain_from_body_model(MODEL)


def test_toe_tip_is_the_rest_of_de_leva_foot_length_ahead_of_the_marker():
    # de Leva female foot 0.2283 m of a 1.735 m reference, scaled to 1.63 m; the marker sits at 72 % of it.
    assert toe_tip_ahead_m() == pytest.approx(0.28 * 0.2283 / 1.735 * 1.63, rel=1e-9)
    assert contact_ahead_of_toe_marker(MARKER_CHAIN, 0.0) is MARKER_CHAIN
    with pytest.raises(ValueError, match="ahead"):
        contact_ahead_of_toe_marker(MARKER_CHAIN, -0.01)


@pytest.mark.parametrize("sole_deg", [0.0, 25.0, 50.0])
def test_moving_the_contact_moves_only_the_hinge_not_the_body(sole_deg):
    """Same body, same rho1: markers, joint centres, segment COMs identical; the contact is on the sole line."""
    ahead = toe_tip_ahead_m()
    tip = contact_ahead_of_toe_marker(MARKER_CHAIN, ahead)
    sole_back = np.pi - np.radians(sole_deg)  # direction toe -> heel (heel raised by sole_deg)
    q_rest = np.array([1.2, 1.75, 1.5])
    g_marker = np.r_[0.3, 0.0, sole_back - MARKER_CHAIN.alpha_rad, q_rest]
    forward = -np.array([np.cos(sole_back), np.sin(sole_back)])
    g_tip = np.r_[np.array([0.3, 0.0]) + ahead * forward, sole_back - tip.alpha_rad, q_rest]
    np.testing.assert_allclose(toe_marker_position(tip, g_tip), [0.3, 0.0], atol=1e-12)
    np.testing.assert_allclose(joint_positions(tip, g_tip)[1:], joint_positions(MARKER_CHAIN, g_marker)[1:], atol=1e-12)
    np.testing.assert_allclose(heel_position(tip, g_tip), heel_position(MARKER_CHAIN, g_marker), atol=1e-12)
    np.testing.assert_allclose(segment_com_positions(tip, g_tip), segment_com_positions(MARKER_CHAIN, g_marker),
                               atol=1e-12)
    np.testing.assert_allclose(body_com(tip, g_tip), body_com(MARKER_CHAIN, g_marker), atol=1e-12)
    np.testing.assert_allclose(joint_angles(g_tip[None, 2:], tip.alpha_rad),
                               joint_angles(g_marker[None, 2:], MARKER_CHAIN.alpha_rad), atol=1e-12)
    # The flat-foot lever of the ground force about the ankle grows by exactly the distance moved.
    flat = np.r_[0.0, 0.0, np.pi - tip.alpha_rad, q_rest]
    # (the default foot has its heel marker straight below the ankle).
    assert joint_positions(tip, flat)[0, 0] - joint_positions(tip, flat)[1, 0] == pytest.approx(
        MODEL.foot_geometry.heel_toe_m + ahead, abs=1e-12)


@pytest.fixture(scope="module")
def toe_tip_recording():
    return simulate_recording(2.2, "hard", 4, seed=1, sensors=noise_free(SensorConfig()), **seed_like_options())


def test_seed_like_hopper_has_the_seed_stance_time_at_2p2_hz(toe_tip_recording):
    """Issue 17: with the toe-tip contact (seed_like_options) the 2.2 Hz stances last as long as the seed's
    subjects' (Table 1: 282 ms, band 15 %); with the contact at the toe marker and the default posture they
    lasted 207 ms (-26 %, bench/simulator_realism.py before this option). Truth file durations, hops 2-4."""
    _, truth = toe_tip_recording
    assert truth["stop_reason"] == "" and len(truth["stances"]) == 4
    durations = np.array([s["duration_s"] for s in truth["stances"][1:]])
    assert abs(durations.mean() / 0.282 - 1.0) < 0.15, durations
    peak = np.array([s["peak_grf_bw"] for s in truth["stances"][1:]])
    assert 2.6 < peak.mean() < 3.5  # seed 3.5 BW; a half-sine force over 282 ms at 2.2 Hz peaks at 2.53 BW


def test_force_plate_sees_the_toe_tip_and_the_analysis_recovers_the_true_moments(toe_tip_recording):
    """The plate's centre of pressure lies at the tip, ahead of the toe marker; inverse dynamics from the
    recorded markers and wrench (which never assumes the force acts at the toe marker) recovers the
    simulator's true moments as closely as with the contact at the marker (test_sim_trials round trip)."""
    pytest.importorskip("hop_impedance.biomech.analysis")
    rec, truth = toe_tip_recording
    assert truth["config"]["contact_ahead_of_toe_marker_m"] == pytest.approx(toe_tip_ahead_m(), rel=1e-9)
    at_marker = np.searchsorted(rec.force.stamp_ns, rec.markers.stamp_ns)  # force stamps include marker stamps
    assert np.array_equal(rec.force.stamp_ns[at_marker], rec.markers.stamp_ns)
    loaded = rec.force.force_n[at_marker, 2] > 300
    toe, heel = rec.markers.positions_m[loaded, 0, ::2], rec.markers.positions_m[loaded, 1, ::2]
    cos_pitch = (toe[:, 0] - heel[:, 0]) / np.linalg.norm(toe - heel, axis=1)
    gap = rec.force.cop_x_m()[at_marker][loaded] - toe[:, 0]
    # Ahead of the marker by the tip distance along the sole; the line of action meets the plate where the
    # hard surface has sunk by ~1-2 mm, which shifts the COP by that times |Fx/Fz| (<= mu = 0.8).
    assert loaded.sum() > 40
    np.testing.assert_allclose(gap, toe_tip_ahead_m() * cos_pitch, atol=2e-3)
    assert cos_pitch.min() < 0.95  # the heel is up for part of the stance, so the test sees the pitch
    for est, true in analysed_and_true_moments(rec, truth):
        n = len(true)
        inner = np.isfinite(est).all(axis=1)
        inner[: int(0.1 * n)] = inner[int(0.9 * n):] = False
        rms = np.sqrt(np.mean((est[inner] - true[inner]) ** 2, axis=0)) / np.abs(true).max(axis=0)
        assert np.all(rms < 0.02), rms


def test_seed_like_hopper_keeps_seed_001_directions_on_an_unexpected_hard_surface():
    """Seed 001 with issue 17's candidate (toe-tip contact, flexed touchdown, trunk balance, bell activation):
    the same law and touchdown meet an unexpected hard surface instead of the expected soft one; leg stiffness
    falls, the compression grows with the peak force, the ankle and knee flex more and the hip less than the
    knee. The bell activation is fixed in time since touchdown and blind to the surface, as seed 001's
    pre-programmed activation (which this test used before the bell: -2.6 %, 0.010 / 0.018 / 0.009 rad);
    measured with the bell: -4.7 %, 0.021 / 0.023 / 0.012 rad (the default hopper's test_sim_trials asks
    <= -3 % and >= 0.02 rad). Since session 20 the experiment prepares the hopper for the soft surface
    (surface_surprise: springs x 1.894 here, k1 pre-programmed in time): -14.7 %, 0.078 / 0.045 / 0.016 rad. Seed 001's
    "joint stiffness ... most pronounced at the ankle" (to midstance) does not hold for this hopper (ankle -7.8 %,
    knee -4.4 %, hip -7.9 %; without the preparation -1.2 / -4.2 / -12.1 %), so it is not asserted; it holds on
    the preset (test_sim_seed001_prepared)."""
    from hop_impedance.simulation.surface_surprise import unexpected_hard_vs_soft

    s = unexpected_hard_vs_soft(2.2, **seed_like_options())
    soft, hard = s.leg_soft, s.leg_hard
    assert hard[0] < 0.99 * soft[0] and hard[2] > soft[2] and hard[1] > soft[1]
    extra = s.extra_flexion_rad
    assert extra[0] > 0.005 and extra[1] > 0.005 and 0.0 < extra[2] < extra[1]
    directions = s.directions()
    assert directions["leg stiffness falls"] and directions["ankle and knee flex more, the hip less"]
