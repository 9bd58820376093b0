"""Iterative elimination of Eq. 3 terms with F-tests (the seed's model reduction).

Algorithm (choices documented in ``docs/impedance_model.md``)
--------------------------------------------------------------
Start from all eight terms (the intercept m0 is always kept). Repeat:

1. Fit the current model by ordinary least squares (OLS).
2. Eligible terms respect the polynomial hierarchy: a lower-order term of a
   family is only tested once its higher-order terms are gone (k2 before k1;
   k1, k2, k3 before k0; b2 before b1; b1, b2, b3 before b0). A polynomial
   without its lower-order terms is not invariant to the touchdown origin
   (rho0, omega0), so it is not a meaningful reduced model.
3. For each eligible term the partial F statistic for dropping it,
   ``F = ((SSE_without - SSE_with) / 1) / (SSE_with / (n - p))`` (= t^2 for OLS),
   gives a p-value from F(1, n_eff - p).
4. Candidates are the eligible terms with p > alpha (default 0.05). If some
   candidates have a variance inflation factor above ``vif_limit`` (the seed's
   "offending", collinear predictors) the one among them whose removal costs
   least fit (smallest partial F) is removed, otherwise the candidate with the
   smallest partial F. Stop when no candidate is left. (Smallest F rather than
   largest VIF or largest p: when the model has at least as many parameters as
   effective samples every p is 1, and removing the most collinear term first
   would throw out k1, which is collinear with k2 and k3 but carries the fit.)

Exactly collinear terms (rank-deficient design) are removed first, largest VIF
first, with reason ``"singular"``.

Serial correlation: residuals of inverse-dynamics moments are low-pass
filtered, so consecutive samples are not independent and the plain F-test
would call almost anything significant. The F statistic and its denominator
degrees of freedom use an effective sample count
``n_eff = n / (1 + 2 sum_k (1 - k/n) r_k)`` (r_k: residual autocorrelation of
the full OLS model, summed up to the first non-positive lag), i.e.
``F_eff = F * n_eff / n`` on ``(1, n_eff - p)`` dof. Set
``autocorrelation_correction=False`` for the textbook i.i.d. test.

Why OLS for the path: the F-tests compare nested least-squares fits; doing
them with unconstrained OLS costs one QR per step instead of one QP per
candidate, and the constrained (OSQP) fit is then run once on the reduced
model. ``sse_function`` lets a caller run the same elimination with any other
SSE (e.g. constrained fits); the tests show both paths end in the same terms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from scipy import special

from hop_impedance.impedance.diagnostics import CollinearityDiagnostics
from hop_impedance.impedance.regression_model import TERM_NAMES

#: Terms that must be eliminated before a term may be tested (polynomial hierarchy).
HIGHER_ORDER_TERMS: dict[str, tuple[str, ...]] = {
    "k0": ("k1", "k2", "k3"),
    "k1": ("k2",),
    "k2": (),
    "k3": (),
    "b0": ("b1", "b2", "b3"),
    "b1": ("b2",),
    "b2": (),
    "b3": (),
}


@dataclass(frozen=True)
class EliminationStep:
    """One removal of the elimination path.

    Attributes
    ----------
    term : str
        Removed term.
    reason : str
        ``"not significant"``, ``"collinear"`` or ``"singular"``; after the
        constrained fit, ``fit_joint_stance`` may add ``"held at zero by the
        constraints"`` (p = 1, F = 0, vif NaN).
    p_value, f_statistic : float
        Partial F-test of the term in the model it was removed from.
    vif : float
        Its variance inflation factor in that model.
    """

    term: str
    reason: str
    p_value: float
    f_statistic: float
    vif: float


@dataclass(frozen=True)
class ReductionResult:
    """Outcome of :func:`reduce_model`.

    Attributes
    ----------
    terms : tuple of str
        Surviving terms, in :data:`TERM_NAMES` order.
    p_values, f_statistics : dict
        Partial F-test (term -> value) of each surviving term in the final model.
    steps : tuple of EliminationStep
        The removals in order.
    effective_samples : float
        n_eff used by the tests (= n without autocorrelation correction).
    alpha : float
        Significance level used.
    ols_variance_factors : ndarray, shape (1 + len(terms),), or None
        ``diag((X^T X)^-1)`` of the final OLS design (intercept first, then
        ``terms``; units 1 / (N m per coefficient unit)^2), from the
        downdated OLS path, so that standard errors need no new
        factorisation. None with ``sse_function`` or when the final design
        is not well conditioned (sigma_min / sigma_max bound below 1e-6).
        Not reported.
    """

    terms: tuple[str, ...]
    p_values: dict[str, float]
    f_statistics: dict[str, float]
    steps: tuple[EliminationStep, ...]
    effective_samples: float
    alpha: float
    ols_variance_factors: np.ndarray | None = field(default=None, repr=False, compare=False)


def effective_sample_count(residuals: np.ndarray, minimum: float) -> float:
    """Effective number of independent samples of a serially correlated residual.

    Parameters
    ----------
    residuals : ndarray, shape (N,)
        Residual series in time order (any unit).
    minimum : float
        Lower clip (e.g. number of parameters + 2).

    Returns
    -------
    float
        ``n / (1 + 2 sum_{k>=1} (1 - k/n) r_k)`` with the sample autocorrelation
        r_k summed until its first non-positive value; clipped to [minimum, n].
    """
    e = np.asarray(residuals, float) - np.mean(residuals)
    n = e.size
    denom = float(e @ e)
    if n < 3 or denom == 0.0:
        return float(n)
    acf = np.correlate(e, e, mode="full")[n - 1 :] / denom
    total = 0.0
    for k in range(1, n - 1):
        if acf[k] <= 0.0:
            break
        total += (1.0 - k / n) * acf[k]
    return float(np.clip(n / (1.0 + 2.0 * total), minimum, n))


def _downdate_inverse(H: np.ndarray, j: int) -> np.ndarray:
    """Inverse Gram (or correlation) matrix after removing variable j, same shape as ``H``.

    Partitioned-inverse identity ``H' = H_{-j,-j} - H_{-j,j} H_{j,-j} / H_jj``
    applied to the whole matrix: row and column j (and those of variables
    removed earlier) are left in place with meaningless values and must be
    ignored; every other entry is the same number as deleting row and column
    j first, because it only reads itself, row j and column j.
    """
    h = H[:, j]
    return H - h[:, None] * (h / h[j])  # np.outer without its wrapper: the same products


class _OlsDowndate:
    """OLS of a design and of the designs left after removing columns one at a time.

    One QR of the column-scaled design gives the scaled coefficients beta,
    H = (X^T X)^-1 = R^-1 R^-T and the SSE. Removing column j uses the exact
    partitioned-inverse identities (Frisch-Waugh-Lovell)::

        beta' = beta_{-j} - H_{-j,j} beta_j / H_jj
        H'    = H_{-j,-j} - H_{-j,j} H_{j,-j} / H_jj
        SSE'  = SSE + beta_j**2 / H_jj

    so each elimination step costs a few 9x9 operations instead of a new QR
    (the same numbers as refitting, up to rounding of order
    machine epsilon x condition number squared). Removed columns stay in the
    arrays, masked by ``kept`` (see :func:`_downdate_inverse`).

    Parameters
    ----------
    scaled_design : ndarray, shape (N, p)
        Design divided by its column norms (unit columns).
    y : ndarray, shape (N,)
        Target.
    norms : ndarray, shape (p,)
        The column norms of the unscaled design.
    """

    def __init__(self, scaled_design: np.ndarray, y: np.ndarray, norms: np.ndarray) -> None:
        self.norms = norms
        Q, R = np.linalg.qr(scaled_design)
        R_inv = np.linalg.inv(R)
        self.beta = R_inv @ (Q.T @ y)
        resid = y - scaled_design @ self.beta
        self.sse = float(resid @ resid)
        self.H = R_inv @ R_inv.T
        self.n = scaled_design.shape[0]
        self.kept = list(range(self.beta.size))

    def t_squared(self) -> list[float]:
        """Partial F (= t^2) of every kept column, in column order (inf for a zero variance)."""
        sigma2 = self.sse / max(self.n - len(self.kept), 1)
        beta, h = self.beta.tolist(), self.H.diagonal().tolist()
        variances = [sigma2 * h[j] for j in self.kept]
        return [beta[j] * beta[j] / var if var > 0 else math.inf for j, var in zip(self.kept, variances)]

    def remove(self, j: int) -> None:
        """Drop column j of the starting design (0 = intercept column)."""
        h = self.H[:, j]
        hjj = h[j]
        self.sse += float(self.beta[j] ** 2 / hjj)
        self.beta = self.beta - h * (self.beta[j] / hjj)
        self.H = _downdate_inverse(self.H, j)
        self.kept.remove(j)

    def variance_factors(self, columns: list[int], min_ratio: float = 1e-6) -> np.ndarray | None:
        """``diag((X^T X)^-1)`` of the unscaled kept ``columns``, or None when not well conditioned.

        Condition guard as in :func:`_certainly_full_rank_ols`: the
        sigma_min / sigma_max bound of the kept scaled design,
        ``1 / sqrt(p trace(H_kept))``, must be at least ``min_ratio``.
        """
        h = self.H.diagonal()[columns]
        if not _ratio_bound_at_least(len(columns), float(h.sum()), min_ratio):
            return None
        return h / self.norms[columns] ** 2


def _scale_columns(X: np.ndarray) -> tuple[np.ndarray, bool]:
    """``X`` divided by its column norms, and whether ``X`` is numerically singular.

    Singular: a zero column, or smallest / largest singular value of the
    column-scaled design below 1e-10.
    """
    norms = np.linalg.norm(X, axis=0)
    if (norms == 0.0).any():
        with np.errstate(divide="ignore", invalid="ignore"):
            return X / norms, True
    scaled = X / norms
    s = np.linalg.svd(scaled, compute_uv=False)
    return scaled, bool(s[-1] < 1e-10 * s[0])


def _exactly_explained(X: np.ndarray) -> np.ndarray:
    """For each non-intercept column: is it (numerically) a combination of the others?"""
    flags = []
    for j in range(1, X.shape[1]):
        col = X[:, j]
        if not np.any(col):
            flags.append(True)
            continue
        others = np.delete(X, j, axis=1)
        beta = np.linalg.lstsq(others, col, rcond=None)[0]
        flags.append(bool(np.linalg.norm(col - others @ beta) <= 1e-8 * np.linalg.norm(col)))
    return np.array(flags)


def _certainly_full_rank_ols(design: np.ndarray, y: np.ndarray) -> _OlsDowndate | None:
    """OLS of the whole design when its QR proves full rank, else None (then check with an SVD).

    With unit columns, ``sigma_max <= ||X_s||_F = sqrt(p)`` and
    ``sigma_min = 1 / ||R^-1||_2 >= 1 / sqrt(trace((X_s^T X_s)^-1))``, so a
    ratio bound of at least 1e-8 (100 times the singularity threshold of
    :func:`_scale_columns`) means the SVD check would pass: it is skipped.
    """
    norms = np.linalg.norm(design, axis=0)
    if (norms == 0.0).any():
        return None
    try:
        ols = _OlsDowndate(design / norms, y, norms)
    except np.linalg.LinAlgError:
        return None
    return ols if _ratio_bound_at_least(design.shape[1], float(np.trace(ols.H)), 1e-8) else None


def _ratio_bound_at_least(p: int, trace: float, limit: float) -> bool:
    """Whether ``1 / sqrt(p trace)``, a lower bound of sigma_min / sigma_max of a unit-column design
    whose ``(X_s^T X_s)^-1`` has this trace, is at least ``limit`` (False for a non-finite or non-positive trace)."""
    return math.isfinite(trace) and trace > 0.0 and p * trace <= limit**-2


def _drop_exactly_collinear(
    design: np.ndarray, terms: tuple[str, ...]
) -> tuple[list[int], list[EliminationStep], np.ndarray, np.ndarray]:
    """Remove exactly collinear (or zero) term columns until the design has full rank.

    The highest-order exactly-explained term goes first (respecting the
    hierarchy). ``design`` is (N, 1 + len(terms)) with the intercept first.

    Returns
    -------
    active : list of int
        Positions (into ``terms``) of the remaining terms.
    steps : list of EliminationStep
        The ``"singular"`` removals.
    X, scaled : ndarray, shape (N, 1 + len(active))
        The remaining design, and divided by its column norms.
    """
    active = list(range(len(terms)))
    steps: list[EliminationStep] = []
    X = design
    scaled, singular = _scale_columns(X)
    while active and singular:
        explained = _exactly_explained(X)
        dependent = [i for i, flag in zip(active, explained) if flag]
        if not dependent:  # ill-conditioned but no column is an exact combination: keep all
            break
        names = [terms[i] for i in active]
        eligible = [i for i in dependent if not any(h in names for h in HIGHER_ORDER_TERMS[terms[i]])]
        worst = (eligible or dependent)[-1]
        steps.append(EliminationStep(terms[worst], "singular", float("nan"), 0.0, float("inf")))
        active.remove(worst)
        X = np.ascontiguousarray(design[:, [0] + [i + 1 for i in active]])
        scaled, singular = _scale_columns(X)
    return active, steps, X, scaled


def _correlation_matrix(columns: np.ndarray) -> np.ndarray:
    """Correlation matrix of the columns (centred, unit-norm; a constant column gives a zero row), (p, p)."""
    Z = columns - columns.mean(axis=0)
    Z = Z / np.where(np.linalg.norm(Z, axis=0) > 0, np.linalg.norm(Z, axis=0), 1.0)
    return Z.T @ Z


def reduce_model(
    term_columns: np.ndarray,
    moment_nm: np.ndarray,
    terms: Sequence[str] = TERM_NAMES,
    alpha: float = 0.05,
    vif_limit: float = 10.0,
    autocorrelation_correction: bool = True,
    intercept: np.ndarray | None = None,
    sse_function: Callable[[tuple[str, ...]], float] | None = None,
    effective_samples: float | None = None,
    familywise: bool = False,
    diagnostics: CollinearityDiagnostics | None = None,
) -> ReductionResult:
    """Backward elimination of Eq. 3 terms by partial F-tests.

    Parameters
    ----------
    term_columns : ndarray, shape (N, len(terms))
        Moment regressor column of each term (N m per coefficient unit), from
        ``StanceRegressors.moment_rows``.
    moment_nm : ndarray, shape (N,)
        Measured (inverse-dynamics) joint moment tau (N m).
    terms : sequence of str
        Names of the columns, a subset of :data:`TERM_NAMES`.
    alpha : float
        Significance level of the F-tests (default 0.05).
    vif_limit : float
        VIF above which a non-significant term counts as collinear ("offending").
    autocorrelation_correction : bool
        Use the effective sample count (module docstring) in the F-tests.
    intercept : ndarray, shape (N,), optional
        Always-kept column (default: ones, the touchdown moment m0).
    sse_function : callable, optional
        ``sse_function(kept_terms) -> SSE`` to test with another fit (e.g. the
        constrained OSQP fit) instead of OLS; slower (one fit per candidate).
    effective_samples : float, optional
        n_eff of the tests (clipped to [1, N]); estimated from the residual
        autocorrelation of the full OLS model when None.
    familywise : bool
        Test at alpha / (number of eligible terms) (Bonferroni) per step.
    diagnostics : CollinearityDiagnostics, optional
        ``collinearity_diagnostics(term_columns, terms)`` of the same columns:
        its correlation matrix and inverse are reused for the VIFs instead of
        being computed again (same numbers).

    Returns
    -------
    ReductionResult
    """
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    terms = tuple(terms)
    columns = np.asarray(term_columns, float)
    y = np.asarray(moment_nm, float)
    n = y.size
    ones = np.ones(n) if intercept is None else np.asarray(intercept, float)
    design = np.empty((n, 1 + len(terms)))  # C order whatever the layout of term_columns
    design[:, 0], design[:, 1:] = ones, columns
    ols = _certainly_full_rank_ols(design, y)
    if ols is not None:
        active_positions, steps, start_design = list(range(len(terms))), [], design
    else:
        active_positions, steps, start_design, scaled = _drop_exactly_collinear(design, terms)
        ols = _OlsDowndate(scaled, y, np.linalg.norm(start_design, axis=0)) if active_positions else None
    active = list(active_positions)  # term positions still in the model, in term order
    # design column of each term position in the OLS object (after any singular removals)
    ols_column = {position: k + 1 for k, position in enumerate(active_positions)}
    n_eff = float(n)
    if effective_samples is not None:
        n_eff = float(np.clip(effective_samples, 1.0, n))
    elif autocorrelation_correction and active:
        beta = ols.beta / ols.norms  # unscaled OLS coefficients
        n_eff = effective_sample_count(y - start_design @ beta, minimum=len(active) + 3.0)

    def partial_tests() -> tuple[dict[int, float], dict[int, float]]:
        """F (n_eff-corrected) and p-value of each active term position."""
        dof = n_eff - (len(active) + 1)
        if sse_function is None:
            f = ols.t_squared()[1:]
        else:
            names = tuple(terms[i] for i in active)
            sse_full = sse_function(names)
            f = [
                (sse_function(tuple(other for other in names if other != name)) - sse_full)
                / max(sse_full / (n - len(names) - 1), 1e-300)
                for name in names
            ]
        f_eff = [value * n_eff / n for value in f]
        p_values = special.fdtrc(1.0, dof, f_eff).tolist() if dof > 0 else [1.0] * len(f)
        return dict(zip(active, f_eff)), dict(zip(active, p_values))

    # Inverse correlation matrix of the active terms: one inverse, then the
    # same partitioned-inverse downdate as the OLS path per removed term.
    inverse: dict = {"matrix": None, "positions": None, "correlation": None}

    def vifs() -> dict[int, float]:
        """VIF of each active term position."""
        if inverse["matrix"] is None:
            given = diagnostics
            if given is not None and given.correlation_inverse is not None and len(active) == len(terms):
                inverse["matrix"] = given.correlation_inverse  # never modified: downdates make new arrays
            else:
                if inverse["correlation"] is None:
                    inverse["correlation"] = (
                        given.correlation_matrix
                        if given is not None and np.isfinite(given.correlation_matrix).all()
                        else _correlation_matrix(columns)
                    )
                try:
                    inverse["matrix"] = np.linalg.inv(inverse["correlation"][active][:, active])
                except np.linalg.LinAlgError:
                    return dict.fromkeys(active, math.inf)
            inverse["positions"] = list(active)
        return dict(zip(inverse["positions"], inverse["matrix"].diagonal().tolist()))

    position = {name: i for i, name in enumerate(terms)}
    higher = [frozenset(position[h] for h in HIGHER_ORDER_TERMS[name] if h in position) for name in terms]
    f_eff, p_values = partial_tests() if active else ({}, {})
    while active:
        eligible = [i for i in active if higher[i].isdisjoint(active)]
        level = alpha / len(eligible) if familywise else alpha
        candidates = [i for i in eligible if p_values[i] > level]
        if not candidates:
            break
        vif = vifs()
        collinear = [i for i in candidates if vif[i] > vif_limit]
        # Smallest partial F = smallest loss of fit (equal to the largest p when
        # the test has degrees of freedom; still defined when n_eff <= p).
        if collinear:
            worst = min(collinear, key=f_eff.__getitem__)
            reason = "collinear"
        else:
            worst = min(candidates, key=f_eff.__getitem__)
            reason = "not significant"
        steps.append(EliminationStep(terms[worst], reason, p_values[worst], f_eff[worst], float(vif[worst])))
        if sse_function is None:
            ols.remove(ols_column[worst])
        if inverse["matrix"] is not None:
            inverse["matrix"] = _downdate_inverse(inverse["matrix"], inverse["positions"].index(worst))
        active.remove(worst)
        f_eff, p_values = partial_tests() if active else ({}, {})

    kept = tuple(t for t in TERM_NAMES if t in position and position[t] in active)
    return ReductionResult(
        terms=kept,
        p_values={t: p_values[position[t]] for t in kept},
        f_statistics={t: f_eff[position[t]] for t in kept},
        steps=tuple(steps),
        effective_samples=n_eff,
        alpha=alpha,
        ols_variance_factors=(
            ols.variance_factors([0] + [ols_column[position[t]] for t in kept])
            if sse_function is None and ols is not None
            else None
        ),
    )
