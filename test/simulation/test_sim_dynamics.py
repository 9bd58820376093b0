"""Equations of motion: statics by hand, energy bookkeeping, and an independent Newton-Euler cross-check."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import (
    _velocity_products,
    accelerations,
    body_com,
    chain_from_body_model,
    com_jacobians,
    equations_of_motion,
    joint_positions,
    mechanical_energy_j,
    segment_com_positions,
)
from hop_impedance.simulation.ground import HARD, SOFT, GroundLaw, lossless
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT
from hop_impedance.simulation.stance import FRICTION_TOLERANCE_N, STANCE_FREE, simulate_stance, stance_energy_j

MODEL = body_model_from_stature(SEED_SUBJECT)
CHAIN = chain_from_body_model(MODEL)
G = 9.81


def balanced_state() -> np.ndarray:
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    return np.r_[0.0, 0.0, q]


def static_moments_by_hand(g: np.ndarray) -> np.ndarray:
    """Extensor moments holding the chain still: weight of everything above a joint times its lever arm."""
    com = segment_com_positions(CHAIN, g)
    joints = joint_positions(CHAIN, g)
    m = CHAIN.mass_kg

    def above(k):  # mass and COM x of segments k.. (k = 1: shank and up)
        mass = m[k:].sum()
        return mass, (m[k:] * com[k:, 0]).sum() / mass

    m_a, x_a = above(1)
    m_k, x_k = above(2)
    m_h, x_h = above(3)
    ankle = m_a * G * (x_a - joints[1, 0])  # weight ahead of the ankle dorsiflexes it
    knee = m_k * G * (joints[2, 0] - x_k)  # weight behind the knee flexes it
    hip = m_h * G * (x_h - joints[3, 0])  # HAT ahead of the hip flexes it
    return np.array([ankle, knee, hip])


def test_mass_matrix_is_symmetric_positive_definite_and_matches_kinetic_energy_of_points():
    rng = np.random.default_rng(3)
    g = balanced_state()
    gd = rng.normal(0, 1, 6)
    mass, _, _ = equations_of_motion(CHAIN, g, gd)
    assert np.allclose(mass, mass.T, atol=1e-12)
    assert np.linalg.eigvalsh(mass).min() > 0
    # Kinetic energy from finite-difference COM velocities and segment spins (independent of M).
    h = 1e-6
    v = (segment_com_positions(CHAIN, g + h * gd) - segment_com_positions(CHAIN, g - h * gd)) / (2 * h)
    ke_points = 0.5 * (CHAIN.mass_kg * (v**2).sum(axis=1)).sum() + 0.5 * (CHAIN.inertia_kgm2 * gd[2:] ** 2).sum()
    assert mechanical_energy_j(CHAIN, g, gd)[0] == pytest.approx(ke_points, rel=1e-7)


def test_static_equilibrium_with_hand_computed_moments():
    g = balanced_state()
    assert body_com(CHAIN, g)[0] == pytest.approx(0.0, abs=1e-10)  # COM over the toe
    moments = static_moments_by_hand(g)
    pinned = np.array([False, False, True, True, True, True])
    gdd, constraint = accelerations(CHAIN, g, np.zeros(6), moments, np.zeros(2), pinned)
    assert np.abs(gdd).max() < 1e-9
    # The toe carries body weight and no horizontal force.
    assert constraint[1] == pytest.approx(CHAIN.total_mass_kg * G, rel=1e-12)
    assert constraint[0] == pytest.approx(0.0, abs=1e-9)
    # Plausible signs for a crouched hopper: extensor moments at all three joints.
    assert np.all(moments > 0)


def test_wrong_static_moment_accelerates_the_chain():
    g = balanced_state()
    moments = static_moments_by_hand(g) + np.array([0.0, 10.0, 0.0])  # 10 N m extra knee extensor
    pinned = np.array([False, False, True, True, True, True])
    gdd, _ = accelerations(CHAIN, g, np.zeros(6), moments, np.zeros(2), pinned)
    rho_dd = np.array([[1, -1, 0, 0], [0, -1, 1, 0], [0, 0, 1, -1]]) @ gdd[2:]
    assert rho_dd[1] < -1.0  # the knee extends (rho2 decreases)


@pytest.mark.parametrize("ground", [lossless(HARD), lossless(SOFT)], ids=["hard", "soft"])
def test_energy_is_conserved_with_elastic_joints_and_lossless_ground(ground):
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8], k2=[100.0, 50.0, 20.0])
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.05, -1.0]), 0.0)
    st = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=np.linspace(0, 0.6, 300),
                         friction_coefficient=None)  # sliding friction dissipates: next test
    assert st.end_reason == "take_off"
    energy = stance_energy_j(CHAIN, law, ground, st)
    work_done = np.ptp(energy)
    assert work_done / energy[0] < 1e-6, f"energy drift {work_done:.2e} J of {energy[0]:.1f} J"
    # ...and the joints did store a lot of energy meanwhile (the test is not trivially flat).
    assert law.elastic_energy_j(st.rho_rad, st.ref).max() > 10.0


def test_sliding_friction_dissipates_exactly_its_work_and_stays_in_the_cone():
    """Lossless ground and elastic joints: the only loss is mu Fz |x_toe velocity| while the toe slides."""
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8], k2=[100.0, 50.0, 20.0])
    ground = lossless(HARD)
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.05, -1.0]), 0.0)
    mu = 0.8
    st = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, friction_coefficient=mu)
    assert st.end_reason == "take_off" and st.slid
    t = np.linspace(0, st.duration_s, 20001)
    fine = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=t, friction_coefficient=mu)
    fx, fz, xd = fine.grf_n[:, 0], fine.grf_n[:, 1], fine.gd[:, 0]
    assert np.all(np.abs(fx) <= mu * fz + FRICTION_TOLERANCE_N + 1e-6)  # never outside the friction cone
    assert np.all(fx * xd <= 1e-9)  # friction opposes the slide
    dissipated = np.trapezoid(-fx * xd, t)
    energy = stance_energy_j(CHAIN, law, ground, fine)
    assert dissipated > 1e-3
    assert energy[0] - energy[-1] == pytest.approx(dissipated, rel=1e-3)


def test_ground_damping_dissipates_exactly_its_viscous_work():
    ground = GroundLaw("viscous", 3.1e6, 2.0, 186.3)
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8])
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.0, -1.0]), 0.0)
    st = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, friction_coefficient=None)  # no sliding loss
    t = np.linspace(0, st.duration_s, 20001)
    fine = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=t, friction_coefficient=None)
    ydot = fine.gd[:, 1]
    dissipated = np.trapezoid(ground.damping_n_s_m * ydot**2, t)
    energy = stance_energy_j(CHAIN, law, lossless(ground), fine)
    assert energy[0] - energy[-1] == pytest.approx(dissipated, rel=1e-3)
    assert dissipated > 1.0


def test_stance_moments_match_independent_newton_euler_inverse_dynamics():
    inverse = pytest.importorskip("hop_impedance.biomech.inverse_dynamics")
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8], k3=[20.0, 10.0, 5.0], b0=0.5, b3=[2.0, 1.0, 1.0])
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.1, -1.1]), 0.0)
    st = simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6, sample_times_s=np.linspace(0, 0.6, 200))
    acc = np.array([np.einsum("iak,k->ia", com_jacobians(CHAIN, g[2:]), gdd) + _velocity_products(CHAIN, g[2:], gd[2:])
                    for g, gd, gdd in zip(st.g, st.gd, st.gdd)])
    # Wrench about the plate origin: force at the toe (x, z), ccw couple x Fz - z Fx.
    wrench = np.stack([st.grf_n[:, 0], st.grf_n[:, 1], st.g[:, 0] * st.grf_n[:, 1] - st.g[:, 1] * st.grf_n[:, 0]], 1)
    loads = inverse.inverse_dynamics_2d(joint_positions(CHAIN, st.g), segment_com_positions(CHAIN, st.g), acc,
                                        st.gdd[:, 2:], wrench, MODEL)
    assert np.abs(loads.moment_nm - st.moments_nm).max() < 1e-6 * np.abs(st.moments_nm).max()
    assert np.abs(loads.hip_residual_force_n).max() < 1e-6
    assert np.abs(st.moments_nm).max() > 100.0


def test_touchdown_with_toe_x_velocity_is_rejected():
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.0, -1.0]), 0.0)
    gd = td.gd.copy()
    gd[0] = 0.2
    with pytest.raises(ValueError, match="no-slip"):
        simulate_stance(CHAIN, Eq3Law(k0=300.0), HARD, type(td)(td.g, gd))


def test_too_soft_joints_collapse_with_a_reason_not_a_crash():
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.0, -0.5]), 0.0)
    st = simulate_stance(CHAIN, Eq3Law(k0=10.0), HARD, td, t_max_s=2.0)
    assert st.end_reason == "collapse"
    assert STANCE_FREE.sum() == 5


def test_closed_form_equations_of_motion_equal_the_jacobian_sums():
    """equations_of_motion's closed form (EomConstants) against M = sum m J^T J + diag(I), h = sum m J^T (dJ/dt g'),
    Q = -g sum m J_z assembled here from the COM Jacobians, at random states of two bodies (the contact at the toe
    marker and 6 cm ahead of it, which gives the foot's COM a perpendicular offset)."""
    from hop_impedance.simulation.dynamics import contact_ahead_of_toe_marker

    rng = np.random.default_rng(17)
    ahead = contact_ahead_of_toe_marker(CHAIN, 0.06)
    assert abs(ahead.com_perp_m[0]) > 1e-3  # the sine terms of the foot's own COM are exercised
    for chain in (CHAIN, ahead):
        for _ in range(50):
            g, gd = rng.normal(0, 2, 6), rng.normal(0, 5, 6)
            jac = com_jacobians(chain, g[2:])
            weighted = chain.mass_kg[:, None, None] * jac
            mass = np.einsum("iak,ial->kl", weighted, jac)
            mass[2:, 2:] += np.diag(chain.inertia_kgm2)
            bias = np.einsum("iak,ia->k", weighted, _velocity_products(chain, g[2:], gd[2:]))
            gravity = -chain.gravity_m_s2 * weighted[:, 1, :].sum(axis=0)
            for ours, summed in zip(equations_of_motion(chain, g, gd), (mass, bias, gravity)):
                np.testing.assert_allclose(ours, summed, rtol=0, atol=1e-12 * np.abs(summed).max())


def test_compiled_accelerations_equal_the_equations_solved_by_lapack():
    """accelerations' compiled elimination (numba, session 35) against M g'' = Q - h assembled from equations_of_motion and
    joint_generalized_forces and solved by LAPACK's gesv, at random states, moments and forces, in both friction
    modes (toe stuck: x_toe fixed, its constraint force returned; sliding: all six coordinates free)."""
    from scipy.linalg import solve

    from hop_impedance.simulation.dynamics import contact_ahead_of_toe_marker, joint_generalized_forces
    from hop_impedance.simulation.stance import SLIDE_FREE

    rng = np.random.default_rng(35)
    for chain in (CHAIN, contact_ahead_of_toe_marker(CHAIN, 0.06)):
        for free in (STANCE_FREE, SLIDE_FREE):
            for _ in range(50):
                g, gd = rng.normal(0, 2, 6), rng.normal(0, 5, 6)
                gd[~free] = 0.0
                moments, force = rng.normal(0, 200, 3), rng.normal(0, 900, 2)
                mass, bias, gravity = equations_of_motion(chain, g, gd)
                rhs = gravity + joint_generalized_forces(moments) - bias
                rhs[:2] += np.where(free[:2], force, 0.0)
                expected = np.zeros(6)
                expected[free] = solve(mass[np.ix_(free, free)], rhs[free])
                gdd, constraint = accelerations(chain, g, gd, moments, np.where(free[:2], force, 0.0), free)
                np.testing.assert_allclose(gdd, expected, rtol=0, atol=1e-10 * np.abs(expected).max())
                expected_constraint = np.where(free, 0.0, mass @ expected - rhs)
                np.testing.assert_allclose(constraint, expected_constraint, rtol=0, atol=1e-9 * np.abs(rhs).max())
                assert np.all(constraint[free] == 0.0)


def test_com_height_from_first_moments_equals_the_segment_sum():
    """com_height_above_contact (the collapse event's, from EomConstants' first moments) against body_com, which sums
    every segment's COM point, on two bodies (the second with a foot COM off the toe-heel line)."""
    from hop_impedance.simulation.dynamics import com_height_above_contact, contact_ahead_of_toe_marker

    rng = np.random.default_rng(36)
    for chain in (CHAIN, contact_ahead_of_toe_marker(CHAIN, 0.06)):
        for _ in range(50):
            g = rng.normal(0, 2, 6)
            assert com_height_above_contact(chain, g[2:]) == pytest.approx(body_com(chain, g)[1] - g[1], abs=1e-14)
