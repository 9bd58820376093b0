"""The identified law at one instant (what the stance simulator calls at every step: a plain time column, the
activation integrals' view built only where a tangent-form activation reads them) against the same law called with a
batch of one (the broadcasting call): bit-identical moments and state rates for every joint-law effect, alone and
together, with both activation forms and shapes and both rate forms, at random states."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hop_impedance.discovery.model import (
    ELASTIC_ALL,
    JOINT_EFFECTS,
    FittedLaw,
    ModelSpec,
    activation_modulation,
    angle_column,
    feature_names,
)
from hop_impedance.simulation.impedance_laws import TouchdownReference

ALL_STATES = 6 + 3 * len(ELASTIC_ALL)

SPECS = [ModelSpec(effects=combo, activation_form=form, activation_shape=shape, rate_form=rate, tau_s=0.05,
                   onset_s=0.08, duration_s=0.12)
         for n in range(len(JOINT_EFFECTS) + 1) for combo in itertools.combinations(JOINT_EFFECTS, n)
         for form, shape, rate in (("secant", "exp", "signed"), ("tangent", "bell", "speed"), ("tangent", "bell", "abs_speed"))]


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: "+".join(s.effects) or "baseline")
def test_one_instant_equals_the_broadcast_path(spec):
    rng = np.random.default_rng(len(spec.effects) * 7 + len(spec.activation_form))
    law = FittedLaw(spec, rng.normal(0, 300, (3, len(feature_names(spec)))), rng.normal(0, 20, 3))
    ref = TouchdownReference(rng.normal(0.5, 0.3, 3), rng.normal(-3, 2, 3))
    for _ in range(20):
        t = float(rng.uniform(0, 0.3))
        rho, omega, states = rng.normal(0.6, 0.3, 3), rng.normal(0, 5, 3), rng.normal(0, 2, law.n_states)
        one = law.moments_nm(np.float64(t), rho, omega, states, ref)
        broadcast = law.moments_nm(np.array([t]), rho[None], omega[None], states[None], ref)[0]
        assert one.shape == (3,)
        np.testing.assert_array_equal(one, broadcast)
        rates = law.state_rates(np.float64(t), rho, omega, states, ref)
        assert rates.shape == (law.n_states,)
        np.testing.assert_array_equal(rates, law.state_rates(np.array([t]), rho[None], omega[None], states[None], ref)[0])


def test_angle_hold_keeps_the_law_in_the_range_and_the_edge_stiffness_past_it():
    """``FittedLaw.angle_range`` (session 29's ANGLE_HOLD): inside the range the moments are the polynomial law's to the
    last bit; past an edge the moment goes on at the stiffness ``k0 + k1 c + k2 c^2`` of that edge (worked out here from
    the coefficients, not from the regressors); the tangent-form state rates are the held columns' time derivatives."""
    spec = ModelSpec(effects=("angle_dependent_stiffness",))
    names = feature_names(spec)
    rng = np.random.default_rng(29)
    coefs = rng.normal(0, 300, (3, len(names)))
    ref = TouchdownReference(np.array([0.4, 0.5, 0.6]), np.zeros(3))
    span = np.array([[-0.05, 0.30], [-0.02, 0.50], [-0.10, 0.25]])
    free, held = FittedLaw(spec, coefs, np.zeros(3), ref), FittedLaw(spec, coefs, np.zeros(3), ref, span)
    zero = np.zeros(ALL_STATES)  # what the tangent-form law below integrates; the others read none of them
    for dr in (span[:, 0] + 1e-3, span[:, 1] - 1e-3, 0.5 * span.sum(axis=1)):
        np.testing.assert_array_equal(held.moments_nm(0.1, ref.rho0_rad + dr, zero[:3], zero, ref),
                                      free.moments_nm(0.1, ref.rho0_rad + dr, zero[:3], zero, ref))
    for edge, beyond in ((span[:, 1], 0.2), (span[:, 0], -0.15)):
        k_edge = sum(coefs[:, names.index(k)] * edge**p for p, k in enumerate(("k0", "k1", "k2")) if k in names)
        m_edge = free.moments_nm(0.1, ref.rho0_rad + edge, zero[:3], zero, ref)
        m_past = held.moments_nm(0.1, ref.rho0_rad + edge + beyond, zero[:3], zero, ref)
        np.testing.assert_allclose(m_past, m_edge + k_edge * beyond, rtol=1e-12, atol=1e-9)
        assert np.all(np.abs(m_past - free.moments_nm(0.1, ref.rho0_rad + edge + beyond, zero[:3], zero, ref)) > 1e-3)
    tangent = ModelSpec(effects=("angle_dependent_stiffness", "time_dependent_activation"), activation_form="tangent",
                        activation_shape="bell", tau_s=0.2)
    law = FittedLaw(tangent, rng.normal(0, 300, (3, len(feature_names(tangent)))), np.zeros(3), ref, span)
    t = np.linspace(0, 0.3, 3001)
    rho = ref.rho0_rad + np.outer(np.sin(20 * t), [0.6, 0.7, 0.5])
    omega = np.gradient(rho, t, axis=0)
    rates = law.state_rates(t, rho, omega, np.zeros((t.size, law.n_states)), ref)
    dr = rho - ref.rho0_rad
    column = angle_column("k1", dr, np.clip(dr, span[:, 0], span[:, 1]))
    g = activation_modulation(tangent, t)[:, None]
    k1_state = rates[:, 6 + 3 * ELASTIC_ALL.index("k1"): 9 + 3 * ELASTIC_ALL.index("k1")]
    np.testing.assert_allclose(k1_state[1:-1], (g * np.gradient(column, t, axis=0))[1:-1], rtol=0, atol=1e-2)
    one = law.moments_nm(np.float64(0.2), rho[2000], omega[2000], zero, ref)
    np.testing.assert_array_equal(one, law.moments_nm(np.array([0.2]), rho[2000][None], omega[2000][None], zero[None], ref)[0])


def test_a_law_without_rate_or_tangent_terms_integrates_no_states_and_hops_as_the_seed_law():
    """Session 35: FittedLaw integrates ``S``, ``S_speed`` and the activation integrals only when its moment reads
    them (a ``k3`` term or a tangent-form activation). Without them its stance ODE has no law states, and a stance
    simulated with the reduced law ``K = k0 + k1 (rho - rho0)`` as a FittedLaw is the same stance as with the simulator's
    own Eq3Law (which integrates its ``S``): the same take-off time, ground force and angles to the solver's tolerance."""
    from hop_impedance.biomech.body_model import body_model_from_stature
    from hop_impedance.simulation.dynamics import chain_from_body_model
    from hop_impedance.simulation.ground import HARD
    from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
    from hop_impedance.simulation.impedance_laws import Eq3Law
    from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT
    from hop_impedance.simulation.stance import simulate_stance

    assert FittedLaw(ModelSpec(effects=("angle_dependent_stiffness", "joint_damping"))).n_states == 0
    assert FittedLaw(ModelSpec(effects=("time_dependent_activation",), activation_form="secant")).n_states == 0
    assert FittedLaw(ModelSpec(effects=("rate_dependent_stiffness",))).n_states == ALL_STATES
    assert FittedLaw(ModelSpec(effects=("time_dependent_activation",), activation_form="tangent")).n_states == ALL_STATES
    chain = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))
    td = touchdown_state(chain, touchdown_posture(chain, np.array(DEFAULT_TOUCHDOWN_RHO)), np.array([0.05, -1.0]), 0.0)
    k0, k1, m_td = np.array([301.4, 230.9, 175.4]), np.array([948.2, 884.8, 894.8]), np.array([5.0, -3.0, 2.0])
    fitted = FittedLaw(ModelSpec(effects=("angle_dependent_stiffness",)), np.c_[k0, k1], m_td)
    times = np.linspace(0.0, 0.2, 201)
    ours, seed = (simulate_stance(chain, law, HARD, td, t_max_s=0.6, sample_times_s=times)
                  for law in (fitted, Eq3Law(m0=m_td, k0=k0, k1=k1)))
    assert ours.law_states.shape == (201, 0) and seed.law_states.shape == (201, 3)
    assert ours.end_reason == seed.end_reason == "take_off"
    assert ours.duration_s == pytest.approx(seed.duration_s, abs=1e-6)
    np.testing.assert_allclose(ours.grf_n[:, 1], seed.grf_n[:, 1], rtol=0, atol=1e-4 * seed.grf_n[:, 1].max())
    np.testing.assert_allclose(ours.rho_rad, seed.rho_rad, rtol=0, atol=1e-6)
