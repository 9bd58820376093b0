"""Pooled coefficient (issue 21) against a direct inverse-variance computation and against known truth."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.impedance.pooling import StancePool, pooled_coefficient
from hop_impedance.impedance.stance_fit import JointImpedanceFit


def test_matches_direct_inverse_variance_computation():
    c = [310.0, 290.0, 355.0, 270.0]
    se = [20.0, 10.0, 40.0, 25.0]
    # by hand: w = 1/400, 1/100, 1/1600, 1/625 -> sum 0.0025 + 0.01 + 0.000625 + 0.0016 = 0.014725
    # sum w c = 0.775 + 2.9 + 0.221875 + 0.432 = 4.328875 -> 293.981..., SE = 1/sqrt(0.014725) = 8.2409...
    p = pooled_coefficient(c, se)
    assert p.value == pytest.approx(4.328875 / 0.014725, rel=1e-12)
    assert p.std_error == pytest.approx(1 / np.sqrt(0.014725), rel=1e-12)
    assert p.n_stances == 4
    q = sum((ci - p.value) ** 2 / s**2 for ci, s in zip(c, se))
    assert p.chi2_per_dof == pytest.approx(q / 3, rel=1e-12)


def test_unusable_entries_are_left_out():
    p = pooled_coefficient([1.0, 2.0, np.nan, 5.0, 7.0], [1.0, 0.0, 1.0, np.inf, 2.0])
    assert p.n_stances == 2
    assert p.value == pytest.approx((1.0 + 7.0 / 4) / 1.25)
    empty = pooled_coefficient([], [])
    assert empty.n_stances == 0 and np.isnan(empty.value)
    with pytest.raises(ValueError, match="differ in length"):
        pooled_coefficient([1.0], [1.0, 2.0])


def test_standard_error_matches_the_scatter_of_pooled_estimates():
    """Monte Carlo with a known truth: 4000 pools of 8 stances with unequal SEs; the pooled values scatter
    around the truth with the SD the formula predicts (within 3 %) and are unbiased."""
    rng = np.random.default_rng(21)
    truth, se = 250.0, np.array([10, 20, 30, 15, 50, 12, 25, 40], float)
    pooled = np.array([pooled_coefficient(truth + se * rng.standard_normal(se.size), se).value for _ in range(4000)])
    predicted = 1 / np.sqrt(np.sum(1 / se**2))
    assert np.std(pooled) == pytest.approx(predicted, rel=0.03)
    assert abs(np.mean(pooled) - truth) < 3 * predicted / np.sqrt(pooled.size)


def _fit(k0: float, se: float, ok: bool = True) -> JointImpedanceFit:
    return JointImpedanceFit("solved" if ok else "rejected", None if ok else "too short", terms=("k0",),
                             coefficients={"k0": k0}, std_errors={"k0": se})


def test_pool_keeps_the_last_n_accepted_stances():
    pool = StancePool(3)
    for k0, se in [(100, 1), (200, 2), (300, 3), (400, 4)]:
        assert pool.add(_fit(k0, se))
    assert not pool.add(_fit(9999, 1, ok=False))  # rejected: not an accepted stance, does not push one out
    assert len(pool) == 3
    p = pool.estimate("k0")
    expected = pooled_coefficient([200, 300, 400], [2, 3, 4])
    assert (p.value, p.std_error, p.n_stances) == (expected.value, expected.std_error, 3)
    assert pool.estimate("k1").n_stances == 0
    pool.clear()
    assert len(pool) == 0
    with pytest.raises(ValueError):
        StancePool(0)
