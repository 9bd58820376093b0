"""The hip-over-COM drop bound (issue 17's hip excursion) against the chain's own COM under a small sink."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import body_com, chain_from_body_model, hip_over_com_drop_bound, joint_positions
from hop_impedance.simulation.hopping_trial import touchdown_posture
from hop_impedance.simulation.scenarios import SEED_LIKE_TOUCHDOWN_RHO, SEED_SUBJECT

CHAIN = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))


def test_bound_is_the_ratio_of_a_sink_about_a_still_knee_with_the_trunk_upright():
    """Turn the thigh about the knee (foot, shank still; HAT angle unchanged, so it translates with the hip):
    the hip's drop over body_com's drop tends to the bound as the sink goes to zero."""
    g0 = np.r_[0.0, 0.0, touchdown_posture(CHAIN, np.array(SEED_LIKE_TOUCHDOWN_RHO))]
    g1 = g0.copy()
    g1[4] -= 1e-4 * np.sign(np.cos(g0[4]))  # the thigh turns about the knee so that the hip falls
    hip_drop = joint_positions(CHAIN, g0)[3, 1] - joint_positions(CHAIN, g1)[3, 1]
    com_drop = body_com(CHAIN, g0)[1] - body_com(CHAIN, g1)[1]
    assert hip_drop > 0 and com_drop > 0
    assert hip_drop / com_drop == pytest.approx(hip_over_com_drop_bound(CHAIN), rel=1e-3)


def test_bound_for_the_seed_subject_is_below_the_seed_tables_ratio_at_1_87_and_2_2_hz():
    """de Leva's female masses: HAT 31.9 kg, thigh 16.2 kg with its COM 0.639 of its length from the knee."""
    expected = CHAIN.total_mass_kg / (CHAIN.mass_kg[3] + CHAIN.mass_kg[2] * 0.22115182 / 0.34619885)
    assert hip_over_com_drop_bound(CHAIN) == pytest.approx(expected, rel=1e-6)
    assert 1.29 < hip_over_com_drop_bound(CHAIN) < 1.31  # the seed's Table 1 implies 1.35 / 1.39 (docs/simulator.md)
