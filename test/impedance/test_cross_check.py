"""OSQP and two independent solvers converge to the same coefficients (seed: QP vs GA)."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.cross_check import fit_by_differential_evolution, fit_by_slsqp
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import TERM_NAMES, parameter_indices, stance_regressors
from hop_impedance.impedance.synthetic import synthetic_stance


def build(stance, terms):
    regs = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    cols = parameter_indices(terms)
    A, _ = constraint_rows(regs, cols)
    return regs.moment_rows[:, cols], A


# 15-50 s per case on the shared 2-core machine (scipy's DE to tol 1e-12 with
# ~250 linear constraint rows); a vectorised population run converged slower.
# The fast suite keeps the SLSQP cross-check below and the KKT certificate in
# test_qp_fit.
@pytest.mark.slow
@pytest.mark.parametrize("joint,freq,seed", [("ankle", 2.20, 0), ("knee", 1.53, 1), ("hip", 1.87, 2)])
def test_differential_evolution_matches_osqp_on_reduced_model(joint, freq, seed):
    stance = synthetic_stance(joint, freq, np.random.default_rng(seed), realistic_noise=True)
    X, A = build(stance, ("k0", "k1", "b0"))
    osqp_coef = ConstrainedLeastSquares().solve(X, stance.moment_nm, A).coefficients
    de_coef = fit_by_differential_evolution(X, stance.moment_nm, A, seed=seed)
    np.testing.assert_allclose(de_coef, osqp_coef, rtol=1e-4, atol=1e-6 * np.abs(osqp_coef).max())


# Seeds 3 and 8 of this family hit OSQP's iteration limit on the 9-term model
# (degenerate active set); they are reported as not converged, see test_qp_fit.
@pytest.mark.parametrize("seed", [0, 1, 2, 4])
def test_slsqp_matches_osqp_on_full_model_with_active_constraints(seed):
    stance = synthetic_stance("ankle", 2.20, np.random.default_rng(seed), realistic_noise=True)
    X, A = build(stance, TERM_NAMES)
    sol = ConstrainedLeastSquares().solve(X, stance.moment_nm, A)
    assert sol.converged and sol.n_active > 0
    ref = fit_by_slsqp(X, stance.moment_nm, A)
    sse_ref = float(np.sum((stance.moment_nm - X @ ref) ** 2))
    # same optimum: objectives agree and the fitted moments coincide
    assert sol.sse == pytest.approx(sse_ref, rel=1e-8)
    np.testing.assert_allclose(X @ sol.coefficients, X @ ref, atol=1e-3)
