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

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from scipy import special

from hop_impedance.impedance.diagnostics import variance_inflation_factors
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
        ``"not significant"``, ``"collinear"`` or ``"singular"``.
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
    """

    terms: tuple[str, ...]
    p_values: dict[str, float]
    f_statistics: dict[str, float]
    steps: tuple[EliminationStep, ...]
    effective_samples: float
    alpha: float


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


def _ols_t_squared(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """OLS coefficients, partial F (= t^2) of every column and SSE, via QR."""
    norms = np.linalg.norm(X, axis=0)
    Q, R = np.linalg.qr(X / norms)
    R_inv = np.linalg.inv(R)
    beta_s = R_inv @ (Q.T @ y)
    resid = y - (X / norms) @ beta_s
    sse = float(resid @ resid)
    n, p = X.shape
    sigma2 = sse / max(n - p, 1)
    var_s = sigma2 * np.sum(R_inv**2, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(var_s > 0, beta_s**2 / var_s, np.inf)
    return beta_s / norms, f, sse


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
    machine epsilon x condition number squared).
    """

    def __init__(self, X: np.ndarray, y: np.ndarray) -> None:
        norms = np.linalg.norm(X, axis=0)
        Q, R = np.linalg.qr(X / norms)
        R_inv = np.linalg.inv(R)
        self.beta = R_inv @ (Q.T @ y)
        resid = y - (X / norms) @ self.beta
        self.sse = float(resid @ resid)
        self.H = R_inv @ R_inv.T
        self.n = X.shape[0]

    def t_squared(self) -> np.ndarray:
        """Partial F (= t^2) of every current column, shape (p,)."""
        p = self.beta.size
        sigma2 = self.sse / max(self.n - p, 1)
        var = sigma2 * np.diag(self.H)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(var > 0, self.beta**2 / var, np.inf)

    def remove(self, j: int) -> None:
        """Drop current column j (0 = intercept column)."""
        h = self.H[:, j]
        hjj = h[j]
        self.sse += float(self.beta[j] ** 2 / hjj)
        keep = np.arange(self.beta.size) != j
        self.beta = (self.beta - h * (self.beta[j] / hjj))[keep]
        self.H = (self.H - np.outer(h, h / hjj))[keep][:, keep]


def _is_singular(X: np.ndarray) -> bool:
    norms = np.linalg.norm(X, axis=0)
    if np.any(norms == 0.0):
        return True
    s = np.linalg.svd(X / norms, compute_uv=False)
    return bool(s[-1] < 1e-10 * s[0])


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
    design = {name: columns[:, i] for i, name in enumerate(terms)}
    active = [name for name in terms]
    steps: list[EliminationStep] = []

    def build(names: Sequence[str]) -> np.ndarray:
        return np.column_stack([ones] + [design[name] for name in names])

    # 1. exact collinearity (or zero columns): remove until the design has full rank,
    #    the highest-order exactly-explained term first (respecting the hierarchy).
    while active and _is_singular(build(active)):
        explained = _exactly_explained(build(active))
        dependent = [name for name, flag in zip(active, explained) if flag]
        if not dependent:  # ill-conditioned but no column is an exact combination: keep all
            break
        eligible = [t for t in dependent if not any(h in active for h in HIGHER_ORDER_TERMS[t])]
        worst = (eligible or dependent)[-1]
        steps.append(EliminationStep(worst, "singular", float("nan"), 0.0, float("inf")))
        active.remove(worst)

    start_design = build(active) if active else None  # built once for the n_eff and OLS set-up
    n_eff = float(n)
    if effective_samples is not None:
        n_eff = float(np.clip(effective_samples, 1.0, n))
    elif autocorrelation_correction and active:
        beta, _, _ = _ols_t_squared(start_design, y)
        n_eff = effective_sample_count(y - start_design @ beta, minimum=len(active) + 3.0)

    if sse_function is None:
        ols = _OlsDowndate(start_design, y) if active else None

    def partial_tests(names: list[str]) -> dict[str, tuple[float, float]]:
        p = len(names) + 1
        dof = n_eff - p
        if sse_function is None:
            f_all = ols.t_squared()
            f = {name: float(f_all[i + 1]) for i, name in enumerate(names)}
        else:
            sse_full = sse_function(tuple(names))
            f = {}
            for name in names:
                reduced = tuple(other for other in names if other != name)
                f[name] = (sse_function(reduced) - sse_full) / max(sse_full / (n - p), 1e-300)
        f_eff = np.array(list(f.values())) * n_eff / n
        p_values = special.fdtrc(1.0, dof, f_eff) if dof > 0 else np.ones(len(f))
        return {name: (float(fe), float(pv)) for name, fe, pv in zip(f, f_eff, p_values)}

    Z = columns - columns.mean(axis=0)
    Z = Z / np.where(np.linalg.norm(Z, axis=0) > 0, np.linalg.norm(Z, axis=0), 1.0)
    correlation = Z.T @ Z
    position = {name: i for i, name in enumerate(terms)}

    # Inverse correlation matrix of the active terms: one inverse, then the
    # same partitioned-inverse downdate as the OLS path per removed term.
    inverse: dict[str, np.ndarray | None] = {"matrix": None}

    def vifs(names: list[str]) -> dict[str, float]:
        if inverse["matrix"] is None:
            idx = [position[name] for name in names]
            try:
                inverse["matrix"] = np.linalg.inv(correlation[idx][:, idx])
            except np.linalg.LinAlgError:
                return {name: float("inf") for name in names}
        return dict(zip(names, np.diag(inverse["matrix"])))

    def remove_from_inverse(j: int) -> None:
        H = inverse["matrix"]
        if H is None:
            return
        h = H[:, j]
        keep = np.arange(h.size) != j
        inverse["matrix"] = (H - np.outer(h, h / h[j]))[keep][:, keep]

    tests = partial_tests(active) if active else {}
    while active:
        eligible = [t for t in active if not any(h in active for h in HIGHER_ORDER_TERMS[t])]
        level = alpha / len(eligible) if familywise else alpha
        candidates = [t for t in eligible if tests[t][1] > level]
        if not candidates:
            break
        vif = vifs(active)
        collinear = [t for t in candidates if vif[t] > vif_limit]
        # Smallest partial F = smallest loss of fit (equal to the largest p when
        # the test has degrees of freedom; still defined when n_eff <= p).
        if collinear:
            worst = min(collinear, key=lambda t: tests[t][0])
            reason = "collinear"
        else:
            worst = min(candidates, key=lambda t: tests[t][0])
            reason = "not significant"
        steps.append(EliminationStep(worst, reason, tests[worst][1], tests[worst][0], float(vif[worst])))
        if sse_function is None:
            ols.remove(active.index(worst) + 1)
        remove_from_inverse(active.index(worst))
        active.remove(worst)
        tests = partial_tests(active) if active else {}

    kept = tuple(t for t in TERM_NAMES if t in active)
    return ReductionResult(
        terms=kept,
        p_values={t: tests[t][1] for t in kept},
        f_statistics={t: tests[t][0] for t in kept},
        steps=tuple(steps),
        effective_samples=n_eff,
        alpha=alpha,
    )
