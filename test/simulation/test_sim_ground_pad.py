"""The shoe pad in series with the surface (issue 17 candidate): force balance, energy, and a stance that keeps it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.simulation.ground import HARD, SOFT, GroundLaw, PaddedGround, lossless, with_pad
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT, hopping_config, shoe_pad
from hop_impedance.simulation.stance import simulate_stance, stance_energy_j

CHAIN = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))


def test_linear_springs_in_series_give_the_textbook_stiffness():
    """Two linear springs in series: F = p k1 k2 / (k1 + k2), each compressed by F / k_i."""
    surface, pad = GroundLaw("s", 2.0e5, 1.0, 0.0), GroundLaw("p", 5.0e4, 1.0, 0.0)
    ground = PaddedGround(surface, pad)
    for p in (1e-4, 3e-3, 0.02):
        force = ground.elastic_force_n(p)
        assert force == pytest.approx(p * 2.0e5 * 5.0e4 / 2.5e5, rel=1e-12)
        s, d = ground.split_m(p)
        assert (s, d) == pytest.approx((force / 2.0e5, force / 5.0e4), rel=1e-10)


def test_quadratic_pad_on_seed_001_hard_surface_shares_force_and_penetration():
    """Both laws n = 2: s = p / (1 + sqrt(k_s / k_p)), F = k_s s^2; the pad softens the contact most at small force."""
    pad = shoe_pad(0.010, 2.0)
    assert pad.stiffness * 0.010**2 == pytest.approx(3 * 54.8 * 9.81, rel=1e-12)  # 10 mm at 3 body weights
    ground = with_pad(HARD, pad)
    p = 0.03
    s = p / (1.0 + np.sqrt(HARD.stiffness / pad.stiffness))
    assert ground.elastic_force_n(p) == pytest.approx(HARD.stiffness * s**2, rel=1e-10)
    force_s, force_p = HARD.stiffness * ground.split_m(p)[0] ** 2, pad.stiffness * ground.split_m(p)[1] ** 2
    assert force_s == pytest.approx(force_p, rel=1e-10)  # massless interface: equal forces
    # A stiffening pad with n_p > the surface's n: its share of the penetration falls as the force grows.
    steep = with_pad(HARD, shoe_pad(0.010, 3.0))
    shares = [steep.split_m(p)[1] / p for p in (0.002, 0.01, 0.03)]
    assert shares[0] > shares[1] > shares[2]


def test_stored_energy_is_the_integral_of_the_force():
    ground = with_pad(SOFT, shoe_pad(0.012, 2.5))
    for p in (0.004, 0.02):
        work, _ = quad(ground.elastic_force_n, 0.0, p, epsabs=1e-12, epsrel=1e-10)
        assert ground.stored_energy_j(-p) == pytest.approx(work, rel=1e-8)
    np.testing.assert_allclose(ground.stored_energy_j(np.array([0.01, -0.004])), [0.0, ground.stored_energy_j(-0.004)])


def test_a_stance_on_a_lossless_padded_surface_conserves_energy():
    """Elastic joints, the pad in series with seed 001's hard surface without damping: no energy is lost."""
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8])
    ground = with_pad(lossless(HARD), shoe_pad())
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.05, -1.0]), 0.0)
    st = simulate_stance(CHAIN, law, ground, td, t_max_s=0.6, sample_times_s=np.linspace(0, 0.6, 200))
    assert st.end_reason == "take_off"
    energy = stance_energy_j(CHAIN, law, ground, st)
    assert np.ptp(energy) / energy[0] < 1e-6
    assert ground.stored_energy_j(st.g[:, 1]).max() > 5.0  # the contact did store energy (not trivially flat)
    bare = simulate_stance(CHAIN, law, lossless(HARD), td, t_max_s=0.6)
    assert st.duration_s > bare.duration_s  # more compliance in series: a longer stance
    assert -st.g[:, 1].min() > -bare.g[:, 1].min()  # and the toe sinks further


def test_the_pad_is_on_every_surface_of_a_trial_and_in_its_truth():
    pad = shoe_pad()
    _, cfg = hopping_config(2.2, "hard", 2, unexpected_surface="soft", unexpected_hops=(1,), variability=False, pad=pad)
    assert isinstance(cfg.surface, PaddedGround) and isinstance(cfg.unexpected_surface, PaddedGround)
    assert cfg.surface.surface == HARD and cfg.unexpected_surface.surface == SOFT
    assert cfg.surface.to_dict()["pad_in_series"]["stiffness"] == pad.stiffness
    _, plain = hopping_config(2.2, "hard", 2, variability=False)
    assert plain.surface == HARD  # without a pad the trial's surface is unchanged
    with pytest.raises(ValueError, match="damping 0"):
        PaddedGround(HARD, GroundLaw("lossy_pad", 1e7, 2.0, 10.0))
