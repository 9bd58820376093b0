"""Constrained least squares of Eq. 6 under Eqs. 7-9, solved with OSQP.

Problem (one joint, one stance, p active parameters)::

    minimise   J = sum_l (tau_l - X_l theta)**2          (Eq. 6)
    subject to A theta >= 0                              (Eqs. 7-9)

Scaling: the columns of X differ by orders of magnitude (k2 multiplies rad^3,
b2 (rad/s)^3), so the QP is solved in ``theta_s = s * theta / |tau|`` with
``s`` the column norms of X, and each constraint row is normalised to unit
norm. OSQP then sees an objective of order 1 and unit-norm rows, converges to
``eps_abs = eps_rel = 1e-9`` or is polished (exact solution of the KKT system
of the identified active set). The solution is unscaled before it is returned. Only OSQP status ``solved`` counts as converged; anything else
("solved inaccurate", "maximum iterations reached", "primal infeasible", ...)
is reported so the caller can reject the stance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import osqp
from scipy import sparse


@dataclass(frozen=True)
class QpSolution:
    """Result of one constrained fit.

    Attributes
    ----------
    coefficients : ndarray, shape (p,)
        Parameters in the caller's column order and units.
    status : str
        OSQP status text (``"solved"`` when converged).
    converged : bool
        True only for status ``"solved"``.
    sse : float
        Sum of squared residuals J (N^2 m^2).
    iterations : int
        ADMM iterations.
    polished : bool
        True when OSQP's polishing step succeeded.
    n_active : int
        Constraints active at the solution (scaled slack below 1e-7).
    """

    coefficients: np.ndarray
    status: str
    converged: bool
    sse: float
    iterations: int
    polished: bool
    n_active: int


def _upper_csc(matrix: np.ndarray) -> sparse.csc_matrix:
    """Upper triangle of a dense square matrix as CSC with a full, fixed pattern."""
    p = matrix.shape[0]
    rows = np.concatenate([np.arange(j + 1) for j in range(p)])
    cols = np.concatenate([np.full(j + 1, j) for j in range(p)])
    indptr = np.concatenate([[0], np.cumsum(np.arange(1, p + 1))])
    return sparse.csc_matrix((matrix[rows, cols], rows, indptr), shape=(p, p))


def _dense_csc(matrix: np.ndarray) -> sparse.csc_matrix:
    """Dense matrix as CSC keeping explicit zeros (fixed pattern for OSQP updates)."""
    m, p = matrix.shape
    indptr = np.arange(0, m * p + 1, m)
    indices = np.tile(np.arange(m), p)
    return sparse.csc_matrix((matrix.ravel(order="F"), indices, indptr), shape=(m, p))


class ConstrainedLeastSquares:
    """Reusable OSQP solver for Eq. 6 under ``A theta >= 0``.

    Keep one instance per joint: when consecutive problems have the same shape
    (same number of parameters and constraint rows) the OSQP workspace is
    updated instead of rebuilt, and every solve is warm-started from the last
    scaled solution of the same number of parameters.

    Parameters
    ----------
    eps : float
        OSQP ``eps_abs`` and ``eps_rel`` on the scaled problem.
    max_iter : int
        OSQP iteration limit; reaching it is reported as not converged.
    coarse_eps : float
        Tolerance of the first ADMM stage, whose result is accepted only when
        OSQP's polishing succeeds (exact active-set solution) or no
        constraint is active; otherwise ADMM continues to ``eps``.
    """

    def __init__(self, eps: float = 1e-9, max_iter: int = 20000, coarse_eps: float = 1e-5) -> None:
        self.coarse_eps = coarse_eps
        self.settings = dict(
            eps_abs=eps,
            eps_rel=eps,
            max_iter=max_iter,
            polish_refine_iter=5,
            verbose=False,
        )
        self._solver: osqp.OSQP | None = None
        self._shape: tuple[int, int] | None = None
        self._last_x: dict[int, np.ndarray] = {}

    def solve(self, design: np.ndarray, target: np.ndarray, constraints: np.ndarray) -> QpSolution:
        """Minimise ``|target - design @ theta|^2`` subject to ``constraints @ theta >= 0``.

        Parameters
        ----------
        design : ndarray, shape (N, p)
            Regressor matrix X (columns with zero norm are not allowed).
        target : ndarray, shape (N,)
            Measured moment tau (N m).
        constraints : ndarray, shape (m, p)
            Rows a with ``a @ theta >= 0``; m may be 0.

        Returns
        -------
        QpSolution
        """
        X = np.asarray(design, float)
        y = np.asarray(target, float)
        col_norm = np.linalg.norm(X, axis=0)
        y_norm = float(np.linalg.norm(y))
        if np.any(col_norm == 0.0) or y_norm == 0.0:
            raise ValueError("constrained fit needs non-zero regressor columns and a non-zero moment")
        Xs = X / col_norm
        ys = y / y_norm
        P = Xs.T @ Xs
        q = -(Xs.T @ ys)
        p = X.shape[1]
        A = np.asarray(constraints, float).reshape(-1, p) / col_norm
        if A.shape[0] == 0:
            A = np.zeros((1, p))  # keep OSQP's interface: one void row 0 <= 0 <= inf
        row_norm = np.linalg.norm(A, axis=1)
        A = A / np.where(row_norm > 0.0, row_norm, 1.0)[:, None]
        lower = np.zeros(A.shape[0])
        upper = np.full(A.shape[0], np.inf)

        # The unconstrained optimum: if it is feasible it is the QP optimum
        # (KKT with zero multipliers); OSQP then only confirms it and polishing
        # (which needs an active set) is switched off.
        x_ols = np.linalg.lstsq(Xs, ys, rcond=None)[0]
        ols_feasible = bool(np.all(A @ x_ols >= -1e-9))
        P_csc, A_csc = _upper_csc(P), _dense_csc(A)
        shape = (p, A.shape[0])
        if self._solver is not None and self._shape == shape:
            self._solver.update(Px=P_csc.data, q=q, Ax=A_csc.data, l=lower, u=upper)
            self._solver.update_settings(polishing=not ols_feasible)
        else:
            self._solver = osqp.OSQP()
            self._solver.setup(P_csc, q, A_csc, lower, upper, **{**self.settings, "polishing": not ols_feasible})
            self._shape = shape
        if ols_feasible or p not in self._last_x:
            self._solver.warm_start(x=x_ols)
        else:
            self._solver.warm_start(x=self._last_x[p])
        # Two stages: a coarse ADMM solve identifies the active set and OSQP's
        # polishing then solves the reduced KKT system exactly (fast, exact);
        # only if polishing fails is ADMM continued (warm) to the tight tolerance.
        self._solver.update_settings(eps_abs=self.coarse_eps, eps_rel=self.coarse_eps)
        result = self._solver.solve(raise_error=False)
        exact = ols_feasible or int(result.info.status_polish) == 1
        if str(result.info.status) != "solved" or not exact:
            self._solver.update_settings(eps_abs=self.settings["eps_abs"], eps_rel=self.settings["eps_rel"])
            result = self._solver.solve(raise_error=False)
        status = str(result.info.status)
        xs = np.asarray(result.x, float)
        converged = status == "solved" and np.all(np.isfinite(xs))
        if converged:
            self._last_x[p] = xs.copy()
        theta = xs * y_norm / col_norm
        residual = y - X @ theta if np.all(np.isfinite(theta)) else np.full_like(y, np.nan)
        slack = A @ xs
        return QpSolution(
            coefficients=theta,
            status=status,
            converged=bool(converged),
            sse=float(residual @ residual),
            iterations=int(result.info.iter),
            polished=int(result.info.status_polish) == 1,
            n_active=int(np.sum(slack < 1e-7)) if converged else 0,
        )
