"""Issue 17: the seed-like law whose per-stance Eq. 3 fit returns seed Table 2 (simulation/fit_calibration.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.simulation.fit_calibration import CALIBRATED_JOINTS, next_scale, table2_k, worst_deviation
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import Effects, build_law, law_scale_at, seed_stiffness


def test_law_scale_multiplies_table2_and_interpolates_like_it():
    """The law simulated is Table 2 times the factors; between the table's frequencies linear, clamped outside."""
    table = {1.53: ((2.0, 1.0, 1.0), (0.5, 1.0, 1.0)), 2.2: ((1.0, 3.0, 1.0), (1.0, 0.25, 1.0))}
    s0, s1 = law_scale_at(table, 1.865)  # half-way
    np.testing.assert_allclose(s0, [1.5, 2.0, 1.0])
    np.testing.assert_allclose(s1, [0.75, 0.625, 1.0])
    np.testing.assert_allclose(law_scale_at(table, 2.4)[1], [1.0, 0.25, 1.0])  # clamped like seed_stiffness
    np.testing.assert_allclose(law_scale_at(None, 2.2), np.ones((2, 3)))
    law = build_law(2.2, Effects(push_off=False), 0.0, 1.0, law_scale=table)
    eq3 = law.parts[0]
    assert isinstance(eq3, Eq3Law)
    k0, k1 = seed_stiffness(2.2)
    np.testing.assert_allclose(eq3.k0, k0 * [1.0, 3.0, 1.0])
    np.testing.assert_allclose(eq3.k1, k1 * [1.0, 0.25, 1.0])
    assert eq3.to_dict()["k0"][1] == pytest.approx(3 * 230.9)  # the truth file's law is the scaled one


def test_next_scale_solves_a_coupled_affine_fit_map_where_the_plain_ratio_oscillates():
    """On a known affine map like the 1.87 Hz ankle's (fitted k0 = 1.57 s0 + 0.36 s1 - 1.38, k1 = -0.69 s0 +
    0.60 s1 + 1.65, in Table 2 units; the least-squares map of six measured steps), the rule reaches Table 2
    to 1e-6, while ``scale x Table 2 / fitted`` alone does not settle (its last steps still > 20 % off)."""
    a = np.array([[1.57, 0.36], [-0.69, 0.60]])
    c = np.array([-1.38, 1.65])
    target = table2_k(1.87)

    def fit(scale):  # (2, 3) -> fitted (2, 3): the ankle through the map, knee and hip at Table 2 x scale
        out = target * scale
        out[:, 0] = target[:, 0] * (a @ scale[:, 0] + c)
        return out

    history = []
    scale = np.ones((2, 3))
    for _ in range(12):
        fitted = fit(scale)
        history.append((scale.copy(), fitted))
        if worst_deviation(fitted, target) < 1e-6:
            break
        for j in CALIBRATED_JOINTS:
            scale[:, j] = next_scale(history, target, j, target[:, j] / fitted[:, j])
    assert worst_deviation(history[-1][1], target) < 1e-6
    plain = np.ones((2, 3))
    devs = []
    for _ in range(12):
        fitted = fit(plain)
        devs.append(worst_deviation(fitted, target))
        plain = plain * np.where(fitted > 0, target / fitted, 1.0)
    assert min(devs[-3:]) > 0.2


def test_seed_like_trial_fits_back_to_table2_at_ankle_and_knee_and_table2_itself_does_not():
    """Issue 17: the seed-like 2.2 Hz trial (seed_like_options with the law SEED_LIKE_LAW_SCALE x Table 2, the
    truth file stating it) analysed from markers and plate and fitted per stance (k0, k1, b0; medians after the first
    stance) returns Table 2's ankle and knee k0, k1 within 15 %; with Table 2 itself as the law under the bell the
    fit misses it (ankle k0 -48 %, k1 +63 %, bench/simulator_realism.py --seed-like --fits before the scale)."""
    from hop_impedance.simulation.fit_calibration import fitted_k0_k1
    from hop_impedance.simulation.scenarios import SEED_LIKE_LAW_SCALE, seed_like_options
    from hop_impedance.simulation.sensors import SensorConfig, noise_free
    from hop_impedance.simulation.simulate import simulate_recording

    target = table2_k(2.2)
    options = {**seed_like_options(), "law_scale": SEED_LIKE_LAW_SCALE}
    rec, truth = simulate_recording(2.2, "hard", 6, seed=1, sensors=noise_free(SensorConfig()), **options)
    eq3 = truth["law"]["parts"][0]
    assert eq3["activation"]["a_min"] == 0.7
    np.testing.assert_allclose(np.array([eq3["k0"], eq3["k1"]]), target * np.array(SEED_LIKE_LAW_SCALE[2.2]), rtol=1e-9)
    assert worst_deviation(fitted_k0_k1(rec), target) < 0.15
    plain = {k: v for k, v in options.items() if k != "law_scale"}
    rec, _ = simulate_recording(2.2, "hard", 6, seed=1, sensors=noise_free(SensorConfig()), **plain)
    assert worst_deviation(fitted_k0_k1(rec), target) > 0.3
