"""Multicollinearity diagnostics of the seed paper (Model section, criteria a-c).

For a regressor matrix X (N, p) of the moment model:

- the Hessian of Eq. 6, ``H = 2 X^T X`` (raw units), its determinant (as
  log10, the raw value spans hundreds of decades) and the ratio of its largest
  to smallest eigenvalue;
- the correlation matrix of the standardised regressors (each column minus its
  mean, divided by its standard deviation, as the seed paper describes), its
  determinant and eigenvalue ratio (a determinant near 0 and a large ratio mean
  near-singular, i.e. collinear, regressors; large off-diagonal elements name
  the pairs);
- variance inflation factors ``VIF_j = [R^-1]_jj`` (inf for exactly collinear
  or constant columns).

The constant intercept m0 is excluded from the standardised diagnostics (it
has zero variance; standardising is what removes it from the problem).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: ln(10), for log10 of the Hessian determinant from slogdet's natural log.
_LN_10 = float(np.log(10.0))


@dataclass(frozen=True)
class CollinearityDiagnostics:
    """Diagnostics of one regression problem.

    Attributes
    ----------
    terms : tuple of str
        Names of the standardised regressors (rows/columns of the matrices).
    hessian_log10_determinant : float
        log10 |det(2 X^T X)| of the raw design including the intercept
        (-inf when singular).
    hessian_eigenvalue_ratio : float
        Largest / smallest eigenvalue of 2 X^T X (raw units; inf when singular).
    correlation_matrix : ndarray, shape (p, p)
        Correlation matrix R of the standardised regressors (NaN rows for
        constant columns).
    correlation_determinant : float
        det(R), in [0, 1]; 1 = orthogonal regressors.
    correlation_eigenvalue_ratio : float
        Largest / smallest eigenvalue of R (the squared condition number of
        the standardised design).
    variance_inflation_factors : ndarray, shape (p,)
        VIF of each term.
    correlation_inverse : ndarray, shape (p, p), or None
        R^-1 (the VIFs are its diagonal) when every column is well defined
        and R is not singular, else None; not reported (not in
        :meth:`to_json`), kept so that the model reduction does not invert R
        again.
    """

    terms: tuple[str, ...]
    hessian_log10_determinant: float
    hessian_eigenvalue_ratio: float
    correlation_matrix: np.ndarray
    correlation_determinant: float
    correlation_eigenvalue_ratio: float
    variance_inflation_factors: np.ndarray
    correlation_inverse: np.ndarray | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict[str, Any]:
        """Plain-JSON form (:func:`hop_impedance.io.impedance_json.diagnostics_to_json`)."""
        from hop_impedance.io.impedance_json import diagnostics_to_json

        return diagnostics_to_json(self)


def _eigenvalue_ratio(symmetric: np.ndarray) -> float:
    eig = np.linalg.eigvalsh(symmetric)
    if eig.size == 0:
        return 1.0
    return float(eig[-1] / eig[0]) if eig[0] > 0.0 else float("inf")


def variance_inflation_factors(design: np.ndarray) -> np.ndarray:
    """VIF of each column of a design without its intercept.

    Parameters
    ----------
    design : ndarray, shape (N, p)
        Regressor columns (any units); a constant column gets VIF inf.

    Returns
    -------
    ndarray, shape (p,)
        ``VIF_j = 1 / (1 - R_j^2)`` with R_j^2 of column j regressed on the
        others plus a constant, computed as the diagonal of the inverse
        correlation matrix; inf when the correlation matrix is singular.
    """
    Z, ok = _standardise(design)
    if not ok.any():
        return np.full(design.shape[1], np.inf)
    R = Z[:, ok].T @ Z[:, ok]
    return _vifs_from_correlation(R, np.linalg.eigvalsh(R), ok)[0]


def _vifs_from_correlation(R: np.ndarray, eig: np.ndarray, ok: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """VIFs (diagonal of R^-1) of the ``ok`` columns, inf elsewhere or when R is singular; and R^-1 (or None).

    ``R`` is the correlation matrix of the ``ok`` columns and ``eig`` its
    ascending eigenvalues (shared with the other diagnostics).
    """
    vif = np.full(ok.size, np.inf)
    if eig.size == 0 or eig[0] <= 1e-13 * max(eig[-1], 1.0):
        return vif, None
    inverse = np.linalg.inv(R)
    vif[ok] = inverse.diagonal()
    return vif, inverse


def _standardise(design: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Columns minus mean over (sqrt(N-1) std): Z^T Z is the correlation matrix."""
    X = np.asarray(design, float)
    centred = X - X.mean(axis=0)
    norm = np.linalg.norm(centred, axis=0)
    scale_floor = 1e-12 * max(float(np.abs(X).max(initial=0.0)), 1e-300) * math.sqrt(X.shape[0])
    ok = norm > scale_floor
    if ok.all():
        return centred / norm, ok
    Z = np.zeros_like(centred)
    Z[:, ok] = centred[:, ok] / norm[ok]
    return Z, ok


def collinearity_diagnostics(
    design: np.ndarray, terms: tuple[str, ...] | list[str], intercept: np.ndarray | None = None
) -> CollinearityDiagnostics:
    """Multicollinearity diagnostics of the terms ``terms`` (criteria a-c of the seed).

    Parameters
    ----------
    design : ndarray, shape (N, p)
        Regressor columns of the Eq. 3 terms (no intercept), units of N m per
        coefficient unit.
    terms : sequence of str, length p
        Their names.
    intercept : ndarray, shape (N,), optional
        Intercept column to include in the raw Hessian (default: ones).

    Returns
    -------
    CollinearityDiagnostics
    """
    X = np.asarray(design, float)
    n = X.shape[0]
    ones = np.ones(n) if intercept is None else np.asarray(intercept, float)
    full = np.column_stack([ones, X])
    H = 2.0 * full.T @ full
    sign, logdet = np.linalg.slogdet(H)
    Z, ok = _standardise(X)
    R = Z.T @ Z
    # one eigen-decomposition of the well-defined block serves the
    # determinant, the eigenvalue ratio and the VIFs
    all_ok = bool(ok.all())
    R_ok = R if all_ok else R[ok][:, ok]
    eig = np.linalg.eigvalsh(R_ok) if ok.any() else np.zeros(0)
    vif, inverse = _vifs_from_correlation(R_ok, eig, ok)
    if not all_ok:
        R[~ok, :] = np.nan
        R[:, ~ok] = np.nan
    if all_ok and X.shape[1] > 0:
        corr_det = float(eig.prod())
        corr_ratio = float(eig[-1] / eig[0]) if eig[0] > 0.0 else float("inf")
    else:
        corr_det, corr_ratio = 0.0, float("inf")
    return CollinearityDiagnostics(
        terms=tuple(terms),
        hessian_log10_determinant=float(logdet / _LN_10) if sign > 0 else float("-inf"),
        hessian_eigenvalue_ratio=_eigenvalue_ratio(H),
        correlation_matrix=R,
        correlation_determinant=corr_det,
        correlation_eigenvalue_ratio=corr_ratio,
        variance_inflation_factors=vif,
        correlation_inverse=inverse if all_ok else None,
    )
