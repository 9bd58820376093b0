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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import special

from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.diagnostics import CollinearityDiagnostics
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares, QpSolution
from hop_impedance.impedance.regression_model import TERM_NAMES, StanceProblem, parameter_indices

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
        constrained fit, :func:`drop_terms_held_at_zero` may add ``"held at
        zero by the constraints"`` (p = 1, F = 0, vif NaN).
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
    downdated: np.ndarray = H - h[:, None] * (h / h[j])  # np.outer without its wrapper: the same products
    return downdated


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
        if not well_conditioned(len(columns), float(h.sum()), min_ratio):
            return None
        factors: np.ndarray = h / self.norms[columns] ** 2
        return factors


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
    return ols if well_conditioned(design.shape[1], float(np.trace(ols.H)), 1e-8) else None


def well_conditioned(p: int, trace: float, limit: float) -> bool:
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
    correlation: np.ndarray = Z.T @ Z
    return correlation


@dataclass(frozen=True)
class EliminationSettings:
    """Rules of :func:`reduce_model`'s backward elimination.

    Attributes
    ----------
    alpha : float
        Significance level of the F-tests, in (0, 1).
    vif_limit : float
        VIF above which a non-significant term counts as collinear ("offending").
    autocorrelation_correction : bool
        Use the effective sample count (module docstring) in the F-tests.
    familywise : bool
        Test at alpha / (number of eligible terms) (Bonferroni) per step.
    """

    alpha: float = 0.05
    vif_limit: float = 10.0
    autocorrelation_correction: bool = True
    familywise: bool = False

    def __post_init__(self) -> None:
        if not 0.0 < self.alpha < 1.0:
            raise ValueError(f"alpha must be in (0, 1), got {self.alpha}")


def partial_f_statistic(sse_with: float, sse_without: float, n: int, p: int) -> float:
    """Partial F statistic of one term: ``F = ((SSE_without - SSE_with) / 1) / (SSE_with / (n - p))``.

    Parameters
    ----------
    sse_with, sse_without : float
        SSE (N^2 m^2) of the model with its p parameters and of the model
        without the tested term.
    n : int
        Samples.
    p : int
        Parameters of the model with the term (intercept included).

    Returns
    -------
    float
        F on (1, n - p) degrees of freedom (for OLS fits equal to the term's
        t^2, which :class:`_OlsDowndate` computes without refitting).
    """
    return (sse_without - sse_with) / max(sse_with / (n - p), 1e-300)


def f_test_p_values(f_statistics: list[float], effective_samples: float, n: int, p: int) -> tuple[list[float], list[float]]:
    """F statistics corrected for serial correlation and their p-values (module docstring, "Serial correlation").

    Parameters
    ----------
    f_statistics : list of float
        Plain partial F of each tested term (n samples).
    effective_samples : float
        n_eff.
    n, p : int
        Samples and parameters of the model (intercept included).

    Returns
    -------
    (f_eff, p_values) : lists of float
        ``F * n_eff / n`` and its upper tail on (1, n_eff - p) dof (1 when n_eff <= p).
    """
    f_eff = [value * effective_samples / n for value in f_statistics]
    dof = effective_samples - p
    p_values = special.fdtrc(1.0, dof, f_eff).tolist() if dof > 0 else [1.0] * len(f_eff)
    return f_eff, p_values


class _InverseCorrelation:
    """VIFs of the terms still in the model: one inverse of their correlation matrix, then downdates.

    The inverse is built on first use (taken from the diagnostics of the
    same columns when they have it) and every removal applies the
    partitioned-inverse downdate of the OLS path (:func:`_downdate_inverse`).
    """

    def __init__(self, columns: np.ndarray, n_terms: int, diagnostics: CollinearityDiagnostics | None) -> None:
        self.columns, self.n_terms, self.diagnostics = columns, n_terms, diagnostics
        self.matrix: np.ndarray | None = None
        self.positions: list[int] = []

    def _correlation(self) -> np.ndarray:
        given = self.diagnostics
        if given is not None and np.isfinite(given.correlation_matrix).all():
            return given.correlation_matrix
        return _correlation_matrix(self.columns)

    def vifs(self, active: list[int]) -> dict[int, float]:
        """VIF of each active term position (inf for all when their correlation matrix is singular)."""
        if self.matrix is None:
            given = self.diagnostics
            if given is not None and given.correlation_inverse is not None and len(active) == self.n_terms:
                self.matrix = given.correlation_inverse  # never modified: downdates make new arrays
            else:
                try:
                    self.matrix = np.linalg.inv(self._correlation()[active][:, active])
                except np.linalg.LinAlgError:
                    return dict.fromkeys(active, math.inf)
            self.positions = list(active)
        return dict(zip(self.positions, self.matrix.diagonal().tolist()))

    def remove(self, position: int) -> None:
        """Drop a term position (nothing to do before the first :meth:`vifs`)."""
        if self.matrix is not None:
            self.matrix = _downdate_inverse(self.matrix, self.positions.index(position))


@dataclass
class _Elimination:
    """State of one backward elimination: the terms left, their OLS path and their latest F-tests."""

    terms: tuple[str, ...]
    active: list[int]
    ols: _OlsDowndate | None
    ols_column: dict[int, int]
    n: int
    effective_samples: float
    sse_function: Callable[[tuple[str, ...]], float] | None
    f_eff: dict[int, float] = field(default_factory=dict)
    p_values: dict[int, float] = field(default_factory=dict)

    def test(self) -> None:
        """Partial F-test of every active term (n_eff-corrected F and p-value)."""
        if not self.active:
            self.f_eff, self.p_values = {}, {}
            return
        p = len(self.active) + 1
        if self.sse_function is not None:
            names = tuple(self.terms[i] for i in self.active)
            sse_full = self.sse_function(names)
            f = [partial_f_statistic(sse_full, self.sse_function(tuple(o for o in names if o != name)), self.n, p)
                 for name in names]
        elif self.ols is not None:  # None only when no term is left (returned above)
            f = self.ols.t_squared()[1:]
        f_eff, p_values = f_test_p_values(f, self.effective_samples, self.n, p)
        self.f_eff, self.p_values = dict(zip(self.active, f_eff)), dict(zip(self.active, p_values))

    def remove(self, position: int) -> None:
        """Drop a term position from the model (and from its OLS path)."""
        if self.sse_function is None and self.ols is not None:
            self.ols.remove(self.ols_column[position])
        self.active.remove(position)


def _candidates(state: _Elimination, higher: list[frozenset[int]], alpha: float, familywise: bool) -> list[int]:
    """Term positions that may be removed now: eligible under the hierarchy and not significant."""
    eligible = [i for i in state.active if higher[i].isdisjoint(state.active)]
    level = alpha / len(eligible) if familywise else alpha
    return [i for i in eligible if state.p_values[i] > level]


def _next_removal(
    candidates: list[int], f_eff: dict[int, float], vif: dict[int, float], vif_limit: float
) -> tuple[int, str]:
    """(position, reason) of the term to remove: the collinear candidate with the smallest partial F, else any candidate's.

    Smallest partial F = smallest loss of fit (equal to the largest p when
    the test has degrees of freedom; still defined when n_eff <= p).
    """
    collinear = [i for i in candidates if vif[i] > vif_limit]
    if collinear:
        return min(collinear, key=f_eff.__getitem__), "collinear"
    return min(candidates, key=f_eff.__getitem__), "not significant"


@dataclass
class _StartingModel:
    """The full-rank model the elimination starts from (after any ``"singular"`` removals).

    ``ols`` is None only when no term is left; ``positions`` are the term
    positions in it; ``design`` its (N, 1 + len(positions)) design.
    """

    ols: _OlsDowndate | None
    positions: list[int]
    steps: list[EliminationStep]
    design: np.ndarray

    @classmethod
    def of(cls, design: np.ndarray, y: np.ndarray, terms: tuple[str, ...]) -> _StartingModel:
        """OLS of ``design`` when full rank, else of what is left after removing exactly collinear terms."""
        ols = _certainly_full_rank_ols(design, y)
        if ols is not None:
            return cls(ols, list(range(len(terms))), [], design)
        active, steps, start_design, scaled = _drop_exactly_collinear(design, terms)
        ols = _OlsDowndate(scaled, y, np.linalg.norm(start_design, axis=0)) if active else None
        return cls(ols, active, steps, start_design)

    def effective_samples(self, given: float | None, correction: bool, y: np.ndarray) -> float:
        """n_eff of the F-tests: ``given`` clipped to [1, n], else from this model's OLS residual (or n)."""
        n = y.size
        if given is not None:
            return float(np.clip(given, 1.0, n))
        if correction and self.positions and self.ols is not None:
            beta = self.ols.beta / self.ols.norms  # unscaled OLS coefficients
            return effective_sample_count(y - self.design @ beta, minimum=len(self.positions) + 3.0)
        return float(n)


def reduce_model(
    term_columns: np.ndarray,
    moment_nm: np.ndarray,
    terms: Sequence[str] = TERM_NAMES,
    settings: EliminationSettings = EliminationSettings(),
    *,
    effective_samples: float | None = None,
    diagnostics: CollinearityDiagnostics | None = None,
    sse_function: Callable[[tuple[str, ...]], float] | None = None,
) -> ReductionResult:
    """Backward elimination of Eq. 3 terms by partial F-tests (module docstring).

    Parameters
    ----------
    term_columns : ndarray, shape (N, len(terms))
        Moment regressor column of each term (N m per coefficient unit), e.g.
        from ``StanceRegressors.moment_rows``; an intercept (ones, the
        touchdown moment m0) is always kept.
    moment_nm : ndarray, shape (N,)
        Measured joint moment tau (N m).
    terms : sequence of str
        Names of the columns, a subset of :data:`TERM_NAMES`.
    settings : EliminationSettings
    effective_samples : float, optional
        n_eff of the tests (clipped to [1, N]); else estimated from the full
        OLS model's residual autocorrelation.
    diagnostics : CollinearityDiagnostics, optional
        ``collinearity_diagnostics(term_columns, terms)``: its correlation
        matrix and inverse are reused for the VIFs (same numbers).
    sse_function : callable, optional
        ``sse_function(kept_terms) -> SSE`` to test with another fit (e.g.
        constrained OSQP fits) instead of OLS; one fit per candidate.
    """
    terms = tuple(terms)
    columns = np.asarray(term_columns, float)
    y = np.asarray(moment_nm, float)
    design = np.empty((y.size, 1 + len(terms)))  # C order whatever the layout of term_columns
    design[:, 0], design[:, 1:] = 1.0, columns
    start = _StartingModel.of(design, y, terms)
    steps = start.steps
    n_eff = start.effective_samples(effective_samples, settings.autocorrelation_correction, y)
    state = _Elimination(terms, list(start.positions), start.ols, {pos: k + 1 for k, pos in enumerate(start.positions)},
                         y.size, n_eff, sse_function)
    inverse = _InverseCorrelation(columns, len(terms), diagnostics)
    position = {name: i for i, name in enumerate(terms)}
    higher = [frozenset(position[h] for h in HIGHER_ORDER_TERMS[name] if h in position) for name in terms]
    state.test()
    while state.active:
        candidates = _candidates(state, higher, settings.alpha, settings.familywise)
        if not candidates:
            break
        vif = inverse.vifs(state.active)
        worst, reason = _next_removal(candidates, state.f_eff, vif, settings.vif_limit)
        steps.append(EliminationStep(terms[worst], reason, state.p_values[worst], state.f_eff[worst], float(vif[worst])))
        state.remove(worst)
        inverse.remove(worst)
        state.test()
    return _reduction_result(state, position, steps, settings.alpha)


def _reduction_result(
    state: _Elimination, position: dict[str, int], steps: list[EliminationStep], alpha: float
) -> ReductionResult:
    kept = tuple(t for t in TERM_NAMES if t in position and position[t] in state.active)
    factors = None
    if state.sse_function is None and state.ols is not None:
        factors = state.ols.variance_factors([0] + [state.ols_column[position[t]] for t in kept])
    return ReductionResult(
        terms=kept,
        p_values={t: state.p_values[position[t]] for t in kept},
        f_statistics={t: state.f_eff[position[t]] for t in kept},
        steps=tuple(steps),
        effective_samples=state.effective_samples,
        alpha=alpha,
        ols_variance_factors=factors,
    )


# -- the second elimination rule: after the constrained fit ----------------------------------------------------
#: Reason of an :class:`EliminationStep` that removes a term the constraints hold at zero.
HELD_AT_ZERO = "held at zero by the constraints"
#: A term's largest moment contribution, relative to the largest |moment|, below which it counts as zero.
_ZERO_CONTRIBUTION = 1e-7


def terms_held_at_zero(problem: StanceProblem, terms: tuple[str, ...], coefficients: np.ndarray) -> list[str]:
    """Kept terms whose constrained coefficient contributes nothing to the moment, removable under the hierarchy.

    A term counts as held at zero when ``|coefficient| * max|column|`` is at
    most 1e-7 of the largest |moment| (N m) in the fit window.
    """
    scale = float(np.max(np.abs(problem.moment_nm))) or 1.0
    X = problem.design(terms)
    contribution = np.abs(coefficients[1:]) * np.max(np.abs(X[:, 1:]), axis=0)
    return [
        name
        for name, c in zip(terms, contribution)
        if c <= _ZERO_CONTRIBUTION * scale and not any(h in terms for h in HIGHER_ORDER_TERMS[name])
    ]


def drop_terms_held_at_zero(
    problem: StanceProblem, reduction: ReductionResult, solver: ConstrainedLeastSquares, solution: QpSolution
) -> tuple[ReductionResult, QpSolution]:
    """Remove reduced-model terms that the constraints (Eqs. 7-9) hold at zero; refit each time.

    Why a second rule next to :func:`reduce_model`: the F-tests run on the
    unconstrained (OLS) fit, because nested OLS fits cost one QR per stance
    where constrained ones cost one QP per candidate. When muscles put
    energy in during stance (a push-off), the OLS damping is significantly
    *negative*; the F-test keeps it and the constraint B >= 0 then holds it
    at exactly 0. In the constrained fit such a term contributes nothing:
    removing it leaves the constrained SSE unchanged, i.e. its partial F
    (:func:`partial_f_statistic` on constrained SSEs) is 0 and p = 1. This
    rule is that F-test, run on the constrained fit only for the terms where
    its answer is known in advance. Removed one at a time, last-eligible
    first under the polynomial hierarchy, as long as the refit's SSE stays
    the same (1e-6 relative) and a stiffness term remains; each removal is
    an :class:`EliminationStep` with reason :data:`HELD_AT_ZERO` (p = 1, F = 0).

    Returns
    -------
    (reduction, solution) after the removals (the given ones when none).
    """
    while True:
        terms = reduction.terms
        held = terms_held_at_zero(problem, terms, solution.coefficients)
        if not held:
            return reduction, solution
        term = held[-1]
        remaining = tuple(t for t in terms if t != term)
        if not any(t.startswith("k") for t in remaining):
            return reduction, solution
        columns = parameter_indices(remaining)
        A, _ = constraint_rows(problem.regressors, columns)
        refit = solver.solve(problem.moment_rows[:, columns], problem.moment_nm, A)
        if not refit.converged or refit.sse > solution.sse * (1.0 + 1e-6) + 1e-12:
            return reduction, solution
        reduction = replace(
            reduction,
            terms=remaining,
            steps=reduction.steps + (EliminationStep(term, HELD_AT_ZERO, 1.0, 0.0, float("nan")),),
            p_values={k: v for k, v in reduction.p_values.items() if k != term},
            f_statistics={k: v for k, v in reduction.f_statistics.items() if k != term},
            ols_variance_factors=None,
        )
        solution = refit
