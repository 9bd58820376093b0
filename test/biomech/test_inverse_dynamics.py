"""Bottom-up inverse dynamics against analytic truth (top-down Newton-Euler) and a static posture."""

import numpy as np
import pytest
from biomech_synth import make_model, pinned_chain

from hop_impedance.biomech.inverse_dynamics import EXTENSOR_SIGN, inverse_dynamics_2d, joint_power
from hop_impedance.biomech.kinematics import segment_coms
from hop_impedance.recording import GRAVITY_M_S2


def test_synthetic_ground_wrench_is_consistent():
    """The generator's ground load at the toe (top-down) equals its forward wrench (sanity of the truth)."""
    model = make_model()
    t = np.linspace(0, 1, 201)
    c = pinned_chain(t, model)
    f, couple = c["ground_at_toe"]
    np.testing.assert_allclose(f, c["wrench"][:, :2], atol=1e-9)
    toe = c["points"][:, 0]
    mo = couple + toe[:, 0] * f[:, 1] - toe[:, 1] * f[:, 0]
    np.testing.assert_allclose(mo, c["wrench"][:, 2], atol=1e-9)


def test_bottom_up_matches_top_down_truth_with_exact_kinematics():
    model = make_model()
    t = np.linspace(0, 1, 501)
    c = pinned_chain(t, model)
    loads = inverse_dynamics_2d(c["points"], c["com"], c["com_acc"], c["qdd"], c["wrench"], model)
    np.testing.assert_allclose(loads.moment_ccw_nm, c["moment_ccw"], atol=1e-8)
    np.testing.assert_allclose(loads.moment_nm, c["moment_ccw"] * EXTENSOR_SIGN, atol=1e-8)
    # Closing the chain at the HAT leaves nothing over.
    assert np.max(np.abs(loads.hip_residual_moment_nm)) < 1e-8
    assert np.max(np.abs(loads.hip_residual_force_n)) < 1e-8
    # The moments are not trivially small: ankle peak of the order of 100 N m.
    assert np.max(np.abs(loads.moment_nm[:, 0])) > 50


def test_static_posture_known_load():
    """Standing still: GRF = body weight under the whole-body COM; hip moment = m_HAT g * lever arm."""
    model = make_model()
    q = np.array([[2.6, 1.3, 2.0, 1.4]])
    lengths = [model.foot_geometry.toe_ankle_m, model.shank.length_m, model.thigh.length_m, model.hat.length_m]
    pts = np.zeros((1, 5, 2))
    for i in range(4):
        pts[0, i + 1] = pts[0, i] + lengths[i] * np.array([np.cos(q[0, i]), np.sin(q[0, i])])
    com = segment_coms(pts, q, model)
    m = np.array([s.mass_kg for s in model.segments])
    body_com_x = float(m @ com[0, :, 0] / m.sum())
    w = m.sum() * GRAVITY_M_S2
    wrench = np.array([[0.0, w, body_com_x * w]])  # force W at COP x = body COM x
    loads = inverse_dynamics_2d(pts, com, np.zeros((1, 4, 2)), np.zeros((1, 4)), wrench, model)
    g = GRAVITY_M_S2
    # Hip: the HAT's weight acts at lever arm (c_hat_x - hip_x); COM ahead of the hip needs an extensor moment.
    hip_expected = model.hat.mass_kg * g * (com[0, 3, 0] - pts[0, 3, 0])
    assert loads.moment_nm[0, 2] == pytest.approx(hip_expected, rel=1e-12)
    # Knee: everything above the knee (thigh + HAT) has its weight at the lever arm from the knee;
    # a load ahead of the knee is an *extending* load, so the knee needs a flexor (negative) moment.
    above = [2, 3]
    knee_expected = -sum(m[i] * g * (com[0, i, 0] - pts[0, 2, 0]) for i in above)
    assert loads.moment_nm[0, 1] == pytest.approx(knee_expected, rel=1e-12)
    # Ankle: GRF at the COP minus the foot's weight, about the ankle: COP ahead of the ankle -> plantarflexor.
    ankle_expected = w * (body_com_x - pts[0, 1, 0]) - m[0] * g * (com[0, 0, 0] - pts[0, 1, 0])
    assert loads.moment_nm[0, 0] == pytest.approx(ankle_expected, rel=1e-12)
    assert hip_expected != 0 and ankle_expected > 0


def test_power_sign_braking_is_negative():
    """An extensor moment while the joint flexes (rho increasing) absorbs energy."""
    p = joint_power(np.array([[100.0, 50.0, 10.0]]), np.array([[2.0, 1.0, -1.0]]))
    np.testing.assert_allclose(p, [[-200.0, -50.0, 10.0]])
