"""One call per joint per stance: reduce, fit (OSQP), compare with constant stiffness.

:func:`fit_joint_stance` is these steps in order, each a named function
(the equations are the seed paper's, ../shared/seeds/000_*.txt):

1. :func:`validate_stance`: finite samples, increasing time, enough samples
   and duration, a non-flat angle trajectory; failures give
   ``status="rejected"`` and a ``rejection_reason``, never an exception;
2. :func:`~hop_impedance.impedance.regression_model.stance_problem`: the
   regressors of Eqs. 3-5 (``stiffness_regressors``, ``damping_regressors``,
   ``spring_moment_regressors``, ``damper_moment_regressors``,
   ``joint_moment_regressors``) and the fit window;
3. :func:`select_model`: multicollinearity diagnostics of the full model
   (:func:`~hop_impedance.impedance.diagnostics.collinearity_diagnostics`)
   and F-test elimination of terms on the OLS path
   (:func:`~hop_impedance.impedance.model_reduction.reduce_model`, its F
   statistic :func:`~hop_impedance.impedance.model_reduction.partial_f_statistic`);
4. :func:`constrained_fit`: one fit of Eq. 6
   (:func:`~hop_impedance.impedance.qp_fit.least_squares_objective`) under
   Eqs. 7-9 (:mod:`~hop_impedance.impedance.constraints`) with OSQP; any
   OSQP status other than ``solved`` rejects the stance; then
   :func:`~hop_impedance.impedance.model_reduction.drop_terms_held_at_zero`
   removes terms the constraints hold at zero (the F-test on the
   constrained fit where its answer, F = 0, is known);
5. :func:`coefficient_inference`: standard errors and p-values of the
   surviving terms from the OLS covariance ``sigma^2 (X^T X)^-1`` at the
   constrained solution (approximate when a constraint is active), inflated
   by n / n_eff for serial correlation, t-test with n_eff - p degrees of
   freedom;
6. :func:`fit_result`: K(t), B(t), moment fit, RMSE, R^2, SSE of the
   variable and (:func:`constant_stiffness_comparison`) of the constant
   (overall) stiffness model, average stiffness.

The result is a :class:`JointImpedanceFit` dataclass; its JSON form is made
in :mod:`hop_impedance.io.impedance_json` (``fit_to_json`` is re-exported
here for existing callers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy import special

from hop_impedance.impedance.constant_stiffness import (
    constant_stiffness_moment,
    overall_stiffness,
    table3_error,
)
from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.diagnostics import CollinearityDiagnostics, collinearity_diagnostics
from hop_impedance.impedance.model_reduction import (
    EliminationSettings,
    ReductionResult,
    drop_terms_held_at_zero,
    reduce_model,
    well_conditioned,
)
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares, QpSolution
from hop_impedance.impedance.regression_model import (
    INTERCEPT_NAME,
    PARAMETER_NAMES,
    TERM_NAMES,
    StanceProblem,
    parameter_indices,
    stance_problem,
)
from hop_impedance.io.impedance_json import FIT_JSON_KEYS, fit_to_json  # re-exported: JSON is made in io/


@dataclass(frozen=True)
class FitOptions:
    """Settings of :func:`fit_joint_stance`.

    Attributes
    ----------
    alpha : float
        Significance level of the elimination F-tests and reported p-values.
    vif_limit : float
        VIF above which a non-significant term is "collinear".
    noise_bandwidth_hz : float or None
        Low-pass cutoff (Hz) applied upstream to angles and moments. When given,
        the effective sample count is ``2 * cutoff * duration`` (independent
        samples of band-limited noise); when None it is estimated from the
        residual autocorrelation (less reliable on short stances).
    autocorrelation_correction : bool
        False gives the textbook i.i.d. F-tests (n_eff = n).
    reduce : bool
        False fits the full Eq. 3 model (no elimination).
    min_samples : int
        Fewer samples reject the stance.
    min_duration_s : float
        Shorter stances are rejected (s).
    min_angle_range_rad : float
        Smaller flexion range (max - min of rho) is a flat trajectory: the
        stiffness regressors are singular and the stance is rejected (rad).
    osqp_eps : float
        OSQP eps_abs = eps_rel on the scaled problem.
    terms : tuple of str
        Starting model (default: all eight Eq. 3 terms); with ``reduce=False``
        exactly these terms are fitted (e.g. the reduced law k0, k1, b0).
    exclude_touchdown_s, exclude_takeoff_s : float
        Time (s) after touchdown / before take-off whose samples are left out
        of the least-squares objective (Eq. 6), the F-tests and the fit
        errors; the regressors are still built from touchdown (rho0, omega0,
        k0 = K at touchdown) and the constraints (Eqs. 7-9) still hold at
        every sample. Default 0 (the seed's whole stance). Choice for
        recordings: zero-lag low-pass filtering smears the force step at
        touchdown and take-off against the marker kinematics, which leaves a
        moment artefact in the last ~10-20 ms (see ``recording_fits``).
    """

    alpha: float = 0.05
    vif_limit: float = 10.0
    noise_bandwidth_hz: float | None = None
    autocorrelation_correction: bool = True
    reduce: bool = True
    min_samples: int = 10
    min_duration_s: float = 0.05
    min_angle_range_rad: float = 0.01
    osqp_eps: float = 1e-9
    terms: tuple[str, ...] = TERM_NAMES
    exclude_touchdown_s: float = 0.0
    exclude_takeoff_s: float = 0.0


@dataclass
class JointImpedanceFit:
    """Result for one joint and one stance (units SI, conventions of joint_angles).

    ``status`` is the OSQP status (``"solved"`` for a good fit) or
    ``"rejected"`` when the stance failed validation; ``rejection_reason`` is
    None exactly when the fit can be used. Arrays are sampled at ``time_s``.
    """

    status: str
    rejection_reason: str | None
    time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    terms: tuple[str, ...] = ()
    coefficients: dict[str, float] = field(default_factory=dict)
    std_errors: dict[str, float] = field(default_factory=dict)
    p_values: dict[str, float] = field(default_factory=dict)
    rho0: float = float("nan")
    omega0: float = float("nan")
    stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_fit: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_constant: np.ndarray = field(default_factory=lambda: np.zeros(0))
    angle_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    rmse: float = float("nan")
    r_squared: float = float("nan")
    sse_variable: float = float("nan")
    sse_constant: float = float("nan")
    table3_variable: float = float("nan")
    table3_constant: float = float("nan")
    overall_stiffness: float = float("nan")
    average_stiffness: float = float("nan")
    solver_iterations: int = 0
    active_constraints: int = 0
    effective_samples: float = float("nan")
    reduction: ReductionResult | None = None
    diagnostics: CollinearityDiagnostics | None = None

    @property
    def ok(self) -> bool:
        """True when the fit can be used (no rejection reason)."""
        return self.rejection_reason is None

    @property
    def initial_stiffness(self) -> float:
        """K at touchdown (N m/rad) = k0."""
        return float(self.stiffness[0]) if self.stiffness.size else float("nan")

    @property
    def max_stiffness(self) -> float:
        """Largest K over the stance (N m/rad)."""
        return float(self.stiffness.max()) if self.stiffness.size else float("nan")


def _rejected(reason: str, status: str = "rejected", **extra: Any) -> JointImpedanceFit:
    return JointImpedanceFit(status=status, rejection_reason=reason, **extra)


def validate_stance(
    time_s: np.ndarray, angle_rad: np.ndarray, angular_velocity_rad_s: np.ndarray, moment_nm: np.ndarray, options: FitOptions
) -> str | None:
    """Reason why a stance cannot be fitted, or None when it can.

    Parameters
    ----------
    time_s, angle_rad, angular_velocity_rad_s, moment_nm : ndarray, shape (N,)
        As in :func:`fit_joint_stance`.
    options : FitOptions

    Returns
    -------
    str or None
    """
    n = time_s.size
    for name, values in (
        ("time", time_s),
        ("angle", angle_rad),
        ("angular velocity", angular_velocity_rad_s),
        ("moment", moment_nm),
    ):
        finite = np.isfinite(values)
        if not finite.all():
            return f"{n - int(finite.sum())} of {n} {name} samples are NaN or infinite"
    if n < options.min_samples:
        return f"too few samples: {n} < {options.min_samples}"
    if (np.diff(time_s) <= 0.0).any():
        return "time stamps are not strictly increasing"
    duration = float(time_s[-1] - time_s[0])
    if duration < options.min_duration_s:
        return f"stance too short: {duration:.3f} s < {options.min_duration_s:.3f} s"
    window = fit_window(time_s, options)
    if np.count_nonzero(window) < options.min_samples:
        return (
            f"too few samples left after excluding {options.exclude_touchdown_s:.3f} s after touchdown and "
            f"{options.exclude_takeoff_s:.3f} s before take-off: {np.count_nonzero(window)} < {options.min_samples}"
        )
    angle = np.asarray(angle_rad)
    angle_range = float(angle.max() - angle.min())  # = np.ptp, without its wrapper
    if angle_range < options.min_angle_range_rad:
        return (
            f"flat angle trajectory: range {angle_range:.4f} rad < {options.min_angle_range_rad} rad, "
            "stiffness regressors are singular"
        )
    if not np.asarray(moment_nm)[window].any():
        return "moment is zero at every fitted sample: nothing to fit (force plate or inverse dynamics output missing?)"
    return None


def _zero_regressor_reason(X: np.ndarray, terms: tuple[str, ...]) -> str | None:
    """Why a given model cannot be fitted: term columns of the design ``X`` (intercept first) that are all zero.

    Happens with ``reduce=False`` when a term's regressor vanishes on this
    stance, e.g. every ``omega - omega0`` term when the angular velocity is
    constant; the reduction would remove such a term as singular.
    """
    zero = [name for name, column in zip(terms, X[:, 1:].T) if not column.any()]
    if not zero:
        return None
    return f"regressor of {', '.join(zero)} is zero at every sample: the given model is singular on this stance"


def fit_window(time_s: np.ndarray, options: FitOptions) -> np.ndarray:
    """Boolean mask, shape (N,), of the samples entering the objective (see ``FitOptions.exclude_*``)."""
    mask: np.ndarray = (time_s >= time_s[0] + options.exclude_touchdown_s) & (time_s <= time_s[-1] - options.exclude_takeoff_s)
    return mask


def _effective_samples(duration_s: float, n: int, options: FitOptions) -> float | None:
    if not options.autocorrelation_correction:
        return float(n)
    if options.noise_bandwidth_hz is None:
        return None
    return min(float(n), 2.0 * options.noise_bandwidth_hz * duration_s)


def _standard_errors(X: np.ndarray, sse: float, n_eff: float, variance_factors: np.ndarray | None = None) -> np.ndarray:
    """OLS standard errors sqrt(sigma^2 diag((X^T X)^-1) n / n_eff) of each column.

    ``variance_factors`` is ``diag((X^T X)^-1)`` when already known (the
    reduction's downdated OLS); otherwise it is computed from the
    column-scaled Gram matrix: its inverse when the design is well
    conditioned by the reduction's own rule (sigma_min / sigma_max bound at
    least 1e-6, :func:`~hop_impedance.impedance.model_reduction.well_conditioned`),
    else its pseudo-inverse. (The inverse is the cheaper LAPACK call of the
    two; where both apply they agree to round-off.)
    """
    n, p = X.shape
    sigma2 = sse / max(n - p, 1)
    if variance_factors is not None:
        known: np.ndarray = np.sqrt(np.maximum(variance_factors, 0.0) * sigma2 * n / n_eff)
        return known
    norms = np.linalg.norm(X, axis=0)
    Xs = X / norms
    gram = Xs.T @ Xs
    try:
        h = np.linalg.inv(gram).diagonal()
    except np.linalg.LinAlgError:
        h = None
    if h is None or not well_conditioned(p, float(h.sum()), 1e-6):
        h = np.linalg.pinv(gram).diagonal()
    errors: np.ndarray = np.sqrt(np.maximum(h, 0.0) * sigma2 * n / n_eff) / norms
    return errors


@dataclass(frozen=True)
class SelectedModel:
    """The model structure a stance is fitted with, and how it was chosen.

    Attributes
    ----------
    terms : tuple of str
        Eq. 3 terms of the model (the intercept m0 is always fitted).
    diagnostics : CollinearityDiagnostics
        Multicollinearity diagnostics of the starting model (``FitOptions.terms``).
    reduction : ReductionResult or None
        The F-test elimination (None with ``reduce=False``).
    effective_samples : float
        n_eff of the F-tests and standard errors.
    """

    terms: tuple[str, ...]
    diagnostics: CollinearityDiagnostics
    reduction: ReductionResult | None
    effective_samples: float


def select_model(problem: StanceProblem, options: FitOptions) -> SelectedModel:
    """Diagnostics of the starting model and, unless ``reduce=False``, its F-test elimination (:func:`reduce_model`)."""
    start = tuple(name for name in TERM_NAMES if name in options.terms)
    columns = problem.design(start)[:, 1:]
    diagnostics = collinearity_diagnostics(columns, start)
    n = problem.time_s.size
    n_eff_given = _effective_samples(float(problem.time_s[-1] - problem.time_s[0]), n, options)
    if not options.reduce:
        return SelectedModel(start, diagnostics, None, n_eff_given if n_eff_given is not None else float(n))
    settings = EliminationSettings(options.alpha, options.vif_limit, options.autocorrelation_correction)
    reduction = reduce_model(columns, problem.moment_nm, start, settings, effective_samples=n_eff_given,
                             diagnostics=diagnostics)
    return SelectedModel(reduction.terms, diagnostics, reduction, reduction.effective_samples)


def _unfittable_reason(problem: StanceProblem, model: SelectedModel, options: FitOptions) -> str | None:
    """Why the selected model cannot be fitted (no stiffness term, a zero regressor), or None."""
    if not any(name.startswith("k") for name in model.terms):
        # Nothing spring-like survived the F-tests: publishing a "solved" fit
        # would present an intercept (or a damper) as this joint's impedance.
        return f"model reduction kept no stiffness term (none of k0..k3 significant at alpha={options.alpha})"
    return _zero_regressor_reason(problem.design(model.terms), model.terms)


def constrained_fit(problem: StanceProblem, terms: tuple[str, ...], solver: ConstrainedLeastSquares) -> QpSolution:
    """Eq. 6 minimised under Eqs. 7-9 (OSQP) for the intercept and ``terms``."""
    columns = parameter_indices(terms)
    A, _ = constraint_rows(problem.regressors, columns)
    return solver.solve(problem.moment_rows[:, columns], problem.moment_nm, A)


@dataclass(frozen=True)
class CoefficientInference:
    """Standard errors and two-sided t-test p-values of the fitted parameters (intercept first), shapes (p,)."""

    std_errors: np.ndarray
    p_values: np.ndarray


def coefficient_inference(problem: StanceProblem, model: SelectedModel, solution: QpSolution) -> CoefficientInference:
    """Standard errors (:func:`_standard_errors`, n / n_eff inflated) and p-values on n_eff - p dof (module docstring, step 5)."""
    X = problem.design(model.terms)
    factors = model.reduction.ols_variance_factors if model.reduction is not None else None
    se = _standard_errors(X, solution.sse, model.effective_samples, factors)
    dof = model.effective_samples - X.shape[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_stat = solution.coefficients / se
    p_values = 2.0 * special.stdtr(dof, -np.abs(t_stat)) if dof > 0 else np.full(X.shape[1], np.nan)
    return CoefficientInference(se, p_values)


def _model_context(problem: StanceProblem, model: SelectedModel, tau: np.ndarray, rho: np.ndarray) -> dict[str, Any]:
    """The :class:`JointImpedanceFit` fields known once the model is selected (also on a rejection)."""
    regs = problem.regressors
    return dict(time_s=regs.time_s, angle_rad=rho, moment_nm=tau, rho0=regs.rho0_rad, omega0=regs.omega0_rad_s,
                terms=model.terms, reduction=model.reduction, diagnostics=model.diagnostics,
                effective_samples=model.effective_samples)


def fit_result(
    problem: StanceProblem, model: SelectedModel, solution: QpSolution, tau: np.ndarray, rho: np.ndarray
) -> JointImpedanceFit:
    """The :class:`JointImpedanceFit` of a solved model: K(t), B(t), moment fit, errors, constant-stiffness comparison.

    ``tau`` and ``rho`` are the whole stance's moment (N m) and angle (rad); errors are over the fit window.
    """
    regs = problem.regressors
    columns = parameter_indices(model.terms)
    names = [PARAMETER_NAMES[c] for c in columns]
    theta = np.zeros(len(PARAMETER_NAMES))
    theta[columns] = solution.coefficients
    inference = coefficient_inference(problem, model, solution)
    moment_fit = regs.moment_rows @ theta
    residual = problem.in_window(tau - moment_fit)
    sse = float(residual @ residual)  # Eq. 6's J at the solution (from the 9-parameter moment fit)
    stiffness = regs.stiffness_rows @ theta
    constant = constant_stiffness_comparison(problem, rho, tau)
    n, t = problem.time_s.size, regs.time_s
    frame_rate = (n - 1) / float(problem.time_s[-1] - problem.time_s[0])
    return JointImpedanceFit(
        status=solution.status,
        rejection_reason=None,
        coefficients={name: float(v) for name, v in zip(names, solution.coefficients)},
        std_errors={name: float(v) for name, v in zip(names, inference.std_errors)},
        p_values={name: float(v) for name, v in zip(names, inference.p_values)},
        stiffness=stiffness,
        damping=regs.damping_rows @ theta,
        moment_fit=moment_fit,
        moment_constant=constant.moment_nm,
        rmse=math.sqrt(sse / n),
        r_squared=_r_squared(sse, problem.moment_nm),
        sse_variable=sse,
        sse_constant=constant.sse,
        table3_variable=table3_error(sse, n, frame_rate),
        table3_constant=table3_error(constant.sse, n, frame_rate),
        overall_stiffness=constant.stiffness_nm_rad,
        average_stiffness=float(np.trapezoid(stiffness, t) / (t[-1] - t[0])),
        solver_iterations=solution.iterations,
        active_constraints=solution.n_active,
        **_model_context(problem, model, tau, rho),
    )


def _r_squared(sse: float, moment_nm: np.ndarray) -> float:
    sst = float(((moment_nm - moment_nm.mean()) ** 2).sum())
    return 1.0 - sse / sst if sst > 0 else float("nan")


@dataclass(frozen=True)
class ConstantStiffnessFit:
    """The seed's constant ("overall") stiffness model of one stance (Table 3's comparison).

    Attributes
    ----------
    stiffness_nm_rad : float
        Overall stiffness (N m/rad; NaN when the joint never flexes beyond touchdown).
    moment_nm : ndarray, shape (N,)
        Its moment prediction over the whole stance (0 stiffness when NaN).
    sse : float
        Its SSE over the fit window (N^2 m^2).
    """

    stiffness_nm_rad: float
    moment_nm: np.ndarray
    sse: float


def constant_stiffness_comparison(problem: StanceProblem, rho: np.ndarray, tau: np.ndarray) -> ConstantStiffnessFit:
    """Overall stiffness, its moment prediction and SSE (:mod:`constant_stiffness`) for the whole-stance ``rho``, ``tau``."""
    k_overall = overall_stiffness(rho, tau)
    moment = constant_stiffness_moment(rho, tau, k_overall if math.isfinite(k_overall) else 0.0)
    return ConstantStiffnessFit(k_overall, moment, float((problem.in_window(tau - moment) ** 2).sum()))


def _checked_arrays(*arrays: np.ndarray) -> list[np.ndarray]:
    """The four input series as float arrays; ValueError unless all are 1-D of one length (a caller bug)."""
    out = [np.asarray(a, float) for a in arrays]
    if any(a.ndim != 1 or a.shape != out[0].shape for a in out):
        raise ValueError(
            "fit_joint_stance: time_s, angle_rad, angular_velocity_rad_s and moment_nm must be 1-D arrays of one length, "
            f"got shapes {[a.shape for a in out]}"
        )
    return out


def fit_joint_stance(
    time_s: np.ndarray,
    angle_rad: np.ndarray,
    angular_velocity_rad_s: np.ndarray,
    moment_nm: np.ndarray,
    options: FitOptions | None = None,
    solver: ConstrainedLeastSquares | None = None,
) -> JointImpedanceFit:
    """Fit the seed's impedance model to one joint during one stance (the steps of the module docstring).

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        Sample instants (s), strictly increasing; sample 0 is touchdown.
    angle_rad : ndarray, shape (N,)
        Joint angle rho (rad), increasing with flexion (joint_angles convention).
    angular_velocity_rad_s : ndarray, shape (N,)
        omega = d(rho)/dt (rad/s), flexion positive.
    moment_nm : ndarray, shape (N,)
        Inverse-dynamics net joint moment tau (N m), extensor positive.
    options : FitOptions, optional
    solver : ConstrainedLeastSquares, optional
        Reusable OSQP workspace; pass one per joint to warm-start across stances.

    Returns
    -------
    JointImpedanceFit
        ``rejection_reason`` is None for a usable fit; otherwise it says why
        (bad input, or OSQP status). Never raises for bad stance data.

    Raises
    ------
    ValueError
        When the four arrays do not have the same 1-D shape (a caller bug).
    """
    options = options or FitOptions()
    solver = solver or ConstrainedLeastSquares(eps=options.osqp_eps)
    t, rho, omega, tau = _checked_arrays(time_s, angle_rad, angular_velocity_rad_s, moment_nm)
    reason = validate_stance(t, rho, omega, tau, options)  # 1. usable data
    if reason is not None:
        return _rejected(reason, time_s=t, angle_rad=rho, moment_nm=tau)
    problem = stance_problem(t, rho, omega, tau, fit_window(t, options))  # 2. Eqs. 3-5 regressors
    model = select_model(problem, options)  # 2-3. diagnostics, F-test elimination
    reason = _unfittable_reason(problem, model, options)
    if reason is not None:
        return _rejected(reason, **_model_context(problem, model, tau, rho))
    solution = constrained_fit(problem, model.terms, solver)  # 4. Eq. 6 under Eqs. 7-9
    if not solution.converged:
        return _rejected(f"OSQP did not converge: status '{solution.status}'", status=solution.status,
                         **_model_context(problem, model, tau, rho))
    if model.reduction is not None:  # 4b. terms the constraints hold at zero
        reduction, solution = drop_terms_held_at_zero(problem, model.reduction, solver, solution)
        model = replace(model, terms=reduction.terms, reduction=reduction)
    return fit_result(problem, model, solution, tau, rho)  # 5-6. inference, K(t), B(t), errors


__all__ = [
    "FIT_JSON_KEYS",
    "FitOptions",
    "INTERCEPT_NAME",
    "JointImpedanceFit",
    "fit_joint_stance",
    "fit_to_json",
    "fit_window",
    "validate_stance",
]
