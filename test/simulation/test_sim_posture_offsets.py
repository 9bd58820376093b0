"""simulate_hopping's posture_offsets (session 25; bench/simulator_posture_sensitivity.py): one hop's touchdown joint
angles moved by exactly the offset, everything before that hop and every other draw unchanged."""

from __future__ import annotations

import numpy as np

from hop_impedance.simulation.hopping_trial import simulate_hopping
from hop_impedance.simulation.scenarios import hopping_config


def test_an_offset_moves_exactly_its_hops_touchdown_angles():
    chain, config = hopping_config(2.2, "hard", 3)
    plain = simulate_hopping(chain, config, seed=4)
    same = simulate_hopping(chain, config, seed=4, posture_offsets={})
    moved = simulate_hopping(chain, config, seed=4, posture_offsets={1: np.array([0.0, 0.02, 0.0])})
    for a, b in zip(plain.stances, same.stances):
        np.testing.assert_array_equal(a.stance.g, b.stance.g)
    np.testing.assert_array_equal(plain.stances[0].stance.g, moved.stances[0].stance.g)  # hop 0 lands before it
    rho_plain, rho_moved = plain.stances[1].stance.rho_rad[0], moved.stances[1].stance.rho_rad[0]
    np.testing.assert_allclose(rho_moved - rho_plain, [0.0, 0.02, 0.0], atol=1e-9)
    # the knee landing more flexed flexes it further in the stance (a softer, deeper landing)
    assert moved.stances[1].stance.rho_rad[:, 1].max() > plain.stances[1].stance.rho_rad[:, 1].max()
