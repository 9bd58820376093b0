"""F-test model reduction: ends in the seed's reduced model on data from Eqs. 10-11."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import NOISE_BANDWIDTH_HZ

from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.diagnostics import collinearity_diagnostics
from hop_impedance.impedance.model_reduction import (
    HIGHER_ORDER_TERMS,
    EliminationSettings,
    effective_sample_count,
    reduce_model,
)
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import TERM_NAMES, parameter_indices, stance_regressors
from hop_impedance.impedance.synthetic import synthetic_stance

SEEDS = range(20)
REDUCED = {("k0", "k1"), ("k0", "k1", "b0")}


def reduce_stance(stance, **kw):
    r = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    n_eff = 2 * NOISE_BANDWIDTH_HZ * (stance.time_s[-1] - stance.time_s[0])
    return r, reduce_model(r.moment_rows[:, 1:], stance.moment_nm, effective_samples=n_eff, **kw)


# Measured rates (seeds 0-19, realistic noise, alpha = 0.05): ankle 14/17/19
# and knee 12/11/17 of 20 at 1.53/1.87/2.20 Hz end in exactly {k0, k1} (+ b0);
# the others keep one or two spurious terms (type-I errors of ~6 tests at
# alpha = 0.05 on ~7-11 effective samples). k0 and k1 always survive.
# Hip: see the next test.
@pytest.mark.parametrize("joint", ["ankle", "knee"])
@pytest.mark.parametrize("freq", [1.53, 1.87, 2.20])
def test_reduction_ends_in_k0_k1_plus_b0(joint, freq):
    hits = 0
    for seed in SEEDS:
        st = synthetic_stance(joint, freq, np.random.default_rng(seed), realistic_noise=True)
        _, result = reduce_stance(st)
        hits += result.terms in REDUCED
        assert {"k0", "k1"} <= set(result.terms)  # the true terms always survive
    assert hits >= 11, f"{hits}/20 stances reduced to exactly k0, k1 (+b0)"


def test_hip_low_frequency_reduction_rate():
    """Hip at 1.53 Hz: weak signal, measured 11/20 exact (k1 is lost at 1.87 and 2.20 Hz)."""
    hits = sum(
        reduce_stance(synthetic_stance("hip", 1.53, np.random.default_rng(s), realistic_noise=True))[1].terms in REDUCED
        for s in SEEDS
    )
    assert hits >= 10


def test_white_noise_iid_test_is_calibrated():
    """With white moment noise and no correction the textbook test holds its level.

    Data: exact law plus i.i.d. 2 N m noise (no filtering, exact angles). With
    about six terms tested at alpha = 0.05 the exact-reduction rate should be
    roughly 0.95**6 ~ 0.74 or better; k0 and k1 must always survive.
    """
    hits = 0
    for seed in range(40):
        st = synthetic_stance("ankle", 1.87, rate_hz=200.0)
        noise = np.random.default_rng(seed).normal(0.0, 2.0, st.moment_nm.size)
        r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
        res = reduce_model(r.moment_rows[:, 1:], st.moment_nm + noise,
                           settings=EliminationSettings(autocorrelation_correction=False))
        assert {"k0", "k1"} <= set(res.terms)
        hits += res.terms in REDUCED
    assert hits >= 26  # >= 65 % of 40


def test_significant_quadratic_stiffness_is_kept():
    """Power: a real k2 (3x the k1 effect) survives the elimination."""
    st = synthetic_stance("ankle", 1.53, np.random.default_rng(0), realistic_noise=True)
    r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
    k2 = 3000.0
    moment = st.moment_nm + k2 * r.delta_angle_rad**3 / 3
    res = reduce_model(r.moment_rows[:, 1:], moment, effective_samples=2 * NOISE_BANDWIDTH_HZ * 0.458)
    assert "k2" in res.terms and "k1" in res.terms


def test_hierarchy_is_respected_along_the_path():
    st = synthetic_stance("knee", 2.20, np.random.default_rng(4), realistic_noise=True)
    _, res = reduce_stance(st)
    removed = [step.term for step in res.steps]
    for i, term in enumerate(removed):
        for higher in HIGHER_ORDER_TERMS[term]:
            assert higher in removed[:i], f"{term} removed before {higher}"
    assert all(step.p_value > 0.05 for step in res.steps)


def test_constrained_sse_path_agrees_with_ols_path():
    """Documented shortcut: OLS F-tests vs OSQP-based F-tests.

    Measured: identical term sets in 6 of these 12 stances; both paths always
    keep k0 and k1 - they differ in the small spurious/damping terms, whose
    constrained SSE changes when Eqs. 7-9 are active. Reported, not hidden.
    """
    solver = ConstrainedLeastSquares()
    agree = 0
    cases = [(j, f, s) for j in ("ankle", "knee") for f in (1.53, 2.20) for s in range(3)]
    for joint, freq, seed in cases:
        st = synthetic_stance(joint, freq, np.random.default_rng(seed), realistic_noise=True)
        r, ols_path = reduce_stance(st)

        def constrained_sse(terms, r=r, st=st):
            cols = parameter_indices(terms)
            A, _ = constraint_rows(r, cols)
            return solver.solve(r.moment_rows[:, cols], st.moment_nm, A).sse

        _, qp_path = reduce_stance(st, sse_function=constrained_sse)
        agree += ols_path.terms == qp_path.terms
        assert {"k0", "k1"} <= set(ols_path.terms) and {"k0", "k1"} <= set(qp_path.terms)
    assert agree >= 6, f"{agree}/{len(cases)}"


def test_duplicate_column_is_removed_as_singular():
    st = synthetic_stance("ankle", 2.20, np.random.default_rng(0), realistic_noise=True)
    r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
    cols = r.moment_rows[:, 1:].copy()
    cols[:, 3] = cols[:, 1]  # k3 column made identical to k1's
    res = reduce_model(cols, st.moment_nm, effective_samples=10.0)
    assert (res.steps[0].term, res.steps[0].reason) == ("k3", "singular")
    assert {"k0", "k1"} <= set(res.terms) and "k3" not in res.terms


def test_effective_sample_count_of_white_and_smooth_noise():
    rng = np.random.default_rng(0)
    white = rng.normal(size=2000)
    assert effective_sample_count(white, 1.0) > 1500
    smooth = np.convolve(rng.normal(size=2100), np.ones(20) / 20, mode="valid")[:2000]
    # moving average of 20: integral time scale ~ 20 samples -> n_eff ~ 100
    assert 50 < effective_sample_count(smooth, 1.0) < 200


def test_alpha_is_validated():
    with pytest.raises(ValueError, match="alpha"):
        reduce_model(np.ones((10, 1)), np.ones(10), terms=("k0",), settings=EliminationSettings(alpha=1.5))


def test_final_f_statistics_and_variance_factors_equal_a_fresh_ols_of_the_reduced_model():
    """The downdated path (one QR, partitioned-inverse removals) against a refit with lstsq.

    Partial F of each kept term = t^2 of a fresh OLS of the reduced design,
    times n_eff / n; the masked downdates must not leak removed terms into it.
    """
    st = synthetic_stance("ankle", 1.87, np.random.default_rng(2), realistic_noise=True)
    r, res = reduce_stance(st)
    assert len(res.steps) >= 3  # several downdates happened
    X = r.moment_rows[:, parameter_indices(res.terms)]
    y = st.moment_nm
    beta, sse, *_ = np.linalg.lstsq(X, y, rcond=None)
    n, p = X.shape
    cov = sse[0] / (n - p) * np.linalg.inv(X.T @ X)
    t_squared = beta**2 / np.diag(cov)
    want = t_squared[1:] * res.effective_samples / n
    np.testing.assert_allclose([res.f_statistics[t] for t in res.terms], want, rtol=1e-7)
    # and the variance factors that the stance fit's standard errors use
    np.testing.assert_allclose(res.ols_variance_factors, np.diag(np.linalg.inv(X.T @ X)), rtol=1e-8)


def test_given_diagnostics_give_the_same_reduction():
    """Reusing the diagnostics' correlation matrix and inverse changes nothing (also with a constant column)."""
    st = synthetic_stance("knee", 1.53, np.random.default_rng(5), realistic_noise=True)
    r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
    n_eff = 2 * NOISE_BANDWIDTH_HZ * 0.458
    for cols in (r.moment_rows[:, 1:], np.column_stack([r.moment_rows[:, 1:8], np.full(st.time_s.size, 2.0)])):
        given = collinearity_diagnostics(cols, TERM_NAMES)
        reused = reduce_model(cols, st.moment_nm, effective_samples=n_eff, diagnostics=given)
        computed = reduce_model(cols, st.moment_nm, effective_samples=n_eff)
        assert repr(reused) == repr(computed)  # repr: the singular step's p-value is NaN
