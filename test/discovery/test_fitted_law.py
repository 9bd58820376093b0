"""The identified law at one instant (what the stance simulator calls at every step: a plain time column, the
activation integrals' view built only where a tangent-form activation reads them) against the same law called with a
batch of one (the broadcasting call): bit-identical moments and state rates for every joint-law effect, alone and
together, with both activation forms and shapes and both rate forms, at random states."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hop_impedance.discovery.model import JOINT_EFFECTS, FittedLaw, ModelSpec, feature_names
from hop_impedance.simulation.impedance_laws import TouchdownReference

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
        rho, omega, states = rng.normal(0.6, 0.3, 3), rng.normal(0, 5, 3), rng.normal(0, 2, FittedLaw.n_states)
        one = law.moments_nm(np.float64(t), rho, omega, states, ref)
        broadcast = law.moments_nm(np.array([t]), rho[None], omega[None], states[None], ref)[0]
        assert one.shape == (3,)
        np.testing.assert_array_equal(one, broadcast)
        rates = law.state_rates(np.float64(t), rho, omega, states, ref)
        assert rates.shape == (FittedLaw.n_states,)
        np.testing.assert_array_equal(rates, law.state_rates(np.array([t]), rho[None], omega[None], states[None], ref)[0])
