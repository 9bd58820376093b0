"""Multicollinearity diagnostics against direct regressions and known designs."""

from __future__ import annotations

import numpy as np

from hop_impedance.impedance.diagnostics import collinearity_diagnostics, variance_inflation_factors
from hop_impedance.impedance.regression_model import TERM_NAMES, stance_regressors
from hop_impedance.impedance.synthetic import synthetic_stance


def vif_by_regression(X: np.ndarray) -> np.ndarray:
    """1 / (1 - R^2) of each column on the others plus a constant (independent route)."""
    out = []
    for j in range(X.shape[1]):
        others = np.column_stack([np.ones(len(X)), np.delete(X, j, axis=1)])
        beta = np.linalg.lstsq(others, X[:, j], rcond=None)[0]
        resid = X[:, j] - others @ beta
        r2 = 1 - resid @ resid / np.sum((X[:, j] - X[:, j].mean()) ** 2)
        out.append(1 / (1 - r2))
    return np.array(out)


def test_vif_matches_auxiliary_regressions():
    rng = np.random.default_rng(0)
    base = rng.normal(size=(200, 3))
    X = np.column_stack([base, base[:, 0] + 0.3 * base[:, 1] + 0.1 * rng.normal(size=200)])
    np.testing.assert_allclose(variance_inflation_factors(X), vif_by_regression(X), rtol=1e-8)


def test_orthogonal_design_has_unit_diagnostics():
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    X = np.column_stack([np.sin(t), np.cos(t), np.sin(2 * t)])
    d = collinearity_diagnostics(X, ("a", "b", "c"))
    np.testing.assert_allclose(d.correlation_matrix, np.eye(3), atol=1e-12)
    assert d.correlation_determinant == np.float64(1.0) or abs(d.correlation_determinant - 1) < 1e-12
    np.testing.assert_allclose(d.variance_inflation_factors, 1.0, atol=1e-12)
    H = 2 * np.column_stack([np.ones(400), X]).T @ np.column_stack([np.ones(400), X])
    log_det = np.log10(np.linalg.det(H))
    assert d.hessian_log10_determinant == log_det or abs(d.hessian_log10_determinant - log_det) < 1e-9


def test_full_seed_model_is_collinear_and_constant_column_is_flagged():
    """The seed's motivation: the 8-term model on a hop is highly collinear."""
    st = synthetic_stance("ankle", 2.20)
    r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
    d = collinearity_diagnostics(r.moment_rows[:, 1:], TERM_NAMES)
    assert d.variance_inflation_factors.max() > 100
    assert d.correlation_determinant < 1e-6
    assert d.correlation_eigenvalue_ratio > 1e4
    X = np.column_stack([np.linspace(0, 1, 50), np.full(50, 2.0)])
    flat = collinearity_diagnostics(X, ("x", "const"))
    assert np.isinf(flat.variance_inflation_factors[1])
    assert flat.to_json()["variance_inflation_factors"]["const"] is None
    assert flat.correlation_inverse is None  # R has an undefined (constant) column


def test_correlation_inverse_is_the_inverse_and_its_diagonal_the_auxiliary_regression_vifs():
    rng = np.random.default_rng(1)
    base = rng.normal(size=(150, 3))
    X = np.column_stack([base, base[:, 2] - 0.5 * base[:, 0] + 0.2 * rng.normal(size=150)])
    d = collinearity_diagnostics(X, ("a", "b", "c", "d"))
    np.testing.assert_allclose(d.correlation_inverse @ d.correlation_matrix, np.eye(4), atol=1e-10)
    np.testing.assert_allclose(np.diag(d.correlation_inverse), vif_by_regression(X), rtol=1e-8)
    assert "correlation_inverse" not in d.to_json()
