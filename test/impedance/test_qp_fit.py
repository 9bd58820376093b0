"""OSQP constrained fit (Eqs. 6-9): optimality, constraints, workspace reuse, status."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.impedance.constraints import constraint_rows, constraint_violations
from hop_impedance.impedance.cross_check import fit_by_slsqp
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import TERM_NAMES, parameter_indices, stance_regressors
from hop_impedance.impedance.synthetic import synthetic_stance


def problem(stance, terms=TERM_NAMES):
    regs = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    cols = parameter_indices(terms)
    A, _ = constraint_rows(regs, cols)
    return regs, cols, regs.moment_rows[:, cols], A


def test_unconstrained_optimum_when_feasible():
    stance = synthetic_stance("ankle", 1.87, np.random.default_rng(2), realistic_noise=True)
    _, _, X, A = problem(stance, ("k0", "k1", "b0"))
    ols = np.linalg.lstsq(X, stance.moment_nm, rcond=None)[0]
    assert (A @ ols).min() >= 0.0  # precondition: the unconstrained optimum is feasible
    sol = ConstrainedLeastSquares().solve(X, stance.moment_nm, A)
    assert sol.converged and sol.status == "solved"
    np.testing.assert_allclose(sol.coefficients, ols, rtol=1e-6)


def test_active_constraints_are_respected_and_optimal():
    """Full model on noisy data: unconstrained OLS breaks Eqs. 7-9, OSQP must not."""
    stance = synthetic_stance("ankle", 2.20, np.random.default_rng(1), realistic_noise=True)
    regs, cols, X, A = problem(stance)
    ols = np.linalg.lstsq(X, stance.moment_nm, rcond=None)[0]
    assert (A @ ols).min() < 0.0  # the test is only meaningful if OLS is infeasible
    sol = ConstrainedLeastSquares().solve(X, stance.moment_nm, A)
    assert sol.converged and sol.n_active > 0
    theta = np.zeros(9)
    theta[cols] = sol.coefficients
    worst = constraint_violations(regs, theta)
    scale = {"stiffness_nonnegative": 1e3, "damping_nonnegative": 1.0, "spring_energy_nonnegative": 1e2, "damper_power_nonpositive": 1e2}
    for name, value in worst.items():
        assert value <= 1e-6 * scale[name], name
    reference = fit_by_slsqp(X, stance.moment_nm, A)
    sse_ref = float(np.sum((stance.moment_nm - X @ reference) ** 2))
    assert sol.sse <= sse_ref * (1 + 1e-6)
    np.testing.assert_allclose(X @ sol.coefficients, X @ reference, atol=1e-3 * np.ptp(stance.moment_nm))


def test_workspace_reuse_gives_the_same_answer_as_a_fresh_solver():
    solver = ConstrainedLeastSquares()
    stances = [synthetic_stance("knee", 2.20, np.random.default_rng(s), realistic_noise=True) for s in range(3)]
    reused = [solver.solve(*problem(st)[2:3], st.moment_nm, problem(st)[3]).coefficients for st in stances]
    for st, coef in zip(stances, reused):
        _, _, X, A = problem(st)
        fresh = ConstrainedLeastSquares().solve(X, st.moment_nm, A).coefficients
        np.testing.assert_allclose(coef, fresh, rtol=1e-5, atol=1e-6 * np.abs(fresh).max())


def test_iteration_limit_is_reported_not_hidden():
    stance = synthetic_stance("ankle", 2.20, np.random.default_rng(1), realistic_noise=True)
    _, _, X, A = problem(stance)
    sol = ConstrainedLeastSquares(max_iter=2).solve(X, stance.moment_nm, A)
    assert not sol.converged
    assert "maximum iterations" in sol.status


def test_zero_moment_is_a_value_error():
    stance = synthetic_stance("ankle", 2.20)
    _, _, X, A = problem(stance, ("k0",))
    with pytest.raises(ValueError, match="non-zero"):
        ConstrainedLeastSquares().solve(X, np.zeros(X.shape[0]), A)
