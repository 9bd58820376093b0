"""Independent solvers for the constrained fit, to cross-check OSQP.

The seed compared quadratic programming with a genetic algorithm and found
the same coefficients. Here the same problem (Eq. 6 under ``A theta >= 0``) is
solved by

- :func:`fit_by_differential_evolution`: scipy's evolutionary global optimiser
  (population based, like the seed's GA), constraints handled by scipy's
  feasibility rules, followed by scipy's own local polish;
- :func:`fit_by_slsqp`: a dense sequential least-squares QP (SLSQP).

Both work on column-scaled coefficients (unit-norm columns, unit-norm target)
for conditioning and share no code with :mod:`qp_fit`. They are slow (tens of
ms to seconds) and meant for tests and audits, not the live path.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize


def _scaled(
    design: np.ndarray, target: np.ndarray, constraints: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Unit-norm columns Xs, unit-norm target ys, unit-norm constraint rows in scaled coefficients, column norms, target norm."""
    X = np.asarray(design, float)
    y = np.asarray(target, float)
    col = np.linalg.norm(X, axis=0)
    ynorm = float(np.linalg.norm(y))
    A = np.asarray(constraints, float).reshape(-1, X.shape[1]) / col
    rows = np.linalg.norm(A, axis=1)
    A = A[rows > 0] / rows[rows > 0, None]
    return X / col, y / ynorm, A, col, ynorm


def fit_by_differential_evolution(
    design: np.ndarray, target: np.ndarray, constraints: np.ndarray, seed: int = 0, maxiter: int = 3000
) -> np.ndarray:
    """Constrained least squares by differential evolution.

    Parameters
    ----------
    design : ndarray, shape (N, p)
        Regressor matrix X.
    target : ndarray, shape (N,)
        Measured moment tau (N m).
    constraints : ndarray, shape (m, p)
        Rows a with ``a @ theta >= 0``.
    seed : int
        Seed of the optimiser's random generator.
    maxiter : int
        Generation limit.

    Returns
    -------
    ndarray, shape (p,)
        Coefficients in the units of ``design``'s columns.

    Notes
    -----
    The search box is +-(2 max|theta_ols| + 1) in scaled coordinates, i.e.
    generously around the unconstrained least-squares solution.
    """
    Xs, ys, A, col, ynorm = _scaled(design, target, constraints)
    ols = np.linalg.lstsq(Xs, ys, rcond=None)[0]
    half = 2.0 * float(np.max(np.abs(ols))) + 1.0
    bounds = [(-half, half)] * Xs.shape[1]

    def objective(x: np.ndarray) -> float:
        r = ys - Xs @ x
        return float(r @ r)

    cons = optimize.LinearConstraint(A, 0.0, np.inf) if A.shape[0] else ()
    result = optimize.differential_evolution(
        objective, bounds, constraints=cons, seed=seed, maxiter=maxiter, tol=1e-12, atol=0.0, polish=True
    )
    theta: np.ndarray = result.x * ynorm / col  # scipy.optimize has no type information
    return theta


def fit_by_slsqp(design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> np.ndarray:
    """Constrained least squares by SLSQP from a zero start.

    Parameters
    ----------
    design, target, constraints
        As in :func:`fit_by_differential_evolution`.

    Returns
    -------
    ndarray, shape (p,)
        Coefficients in the units of ``design``'s columns.
    """
    Xs, ys, A, col, ynorm = _scaled(design, target, constraints)
    H = Xs.T @ Xs
    g = Xs.T @ ys
    result = optimize.minimize(
        lambda x: float(x @ H @ x - 2.0 * g @ x + ys @ ys),
        np.zeros(Xs.shape[1]),
        jac=lambda x: 2.0 * (H @ x - g),
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": lambda x: A @ x, "jac": lambda x: A}] if A.shape[0] else [],
        options={"ftol": 1e-15, "maxiter": 2000},
    )
    if not result.success:
        raise RuntimeError(f"SLSQP failed: {result.message}")
    theta: np.ndarray = result.x * ynorm / col  # scipy.optimize has no type information
    return theta
