"""One call per joint per stance: reduce, fit (OSQP), compare with constant stiffness.

Pipeline of :func:`fit_joint_stance`:

1. validate the stance (finite samples, increasing time, enough samples and
   duration, a non-flat angle trajectory); failures give ``status="rejected"``
   and a ``rejection_reason``, never an exception;
2. regressors of Eqs. 3-5 and multicollinearity diagnostics of the full model;
3. F-test elimination of terms (OLS path, :mod:`model_reduction`);
4. one constrained fit of the reduced model under Eqs. 7-9 with OSQP; any
   OSQP status other than ``solved`` rejects the stance;
5. standard errors and p-values of the surviving terms from the OLS covariance
   ``sigma^2 (X^T X)^-1`` at the constrained solution (approximate when a
   constraint is active), inflated by n / n_eff for serial correlation,
   t-test with n_eff - p degrees of freedom;
6. K(t), B(t), moment fit, RMSE, R^2, SSE of the variable and of the constant
   (overall) stiffness model, average stiffness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import special

from hop_impedance.impedance.constant_stiffness import (
    constant_stiffness_moment,
    overall_stiffness,
    table3_error,
)
from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.diagnostics import CollinearityDiagnostics, collinearity_diagnostics
from hop_impedance.impedance.model_reduction import HIGHER_ORDER_TERMS, EliminationStep, ReductionResult, reduce_model
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import (
    INTERCEPT_NAME,
    PARAMETER_NAMES,
    TERM_NAMES,
    parameter_indices,
    stance_regressors,
)

#: Keys of the per-joint ``fit`` object in ``hop-impedance analyze`` JSON.
FIT_JSON_KEYS: tuple[str, ...] = (
    "terms",
    "coefficients",
    "std_errors",
    "p_values",
    "rho0",
    "omega0",
    "stiffness",
    "damping",
    "moment_fit",
    "rmse",
    "r_squared",
    "sse_variable",
    "sse_constant",
    "overall_stiffness",
    "average_stiffness",
    "status",
    "rejection_reason",
)


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


def _rejected(reason: str, status: str = "rejected", **extra) -> JointImpedanceFit:
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
    return (time_s >= time_s[0] + options.exclude_touchdown_s) & (time_s <= time_s[-1] - options.exclude_takeoff_s)


def _effective_samples(duration_s: float, n: int, options: FitOptions) -> float | None:
    if not options.autocorrelation_correction:
        return float(n)
    if options.noise_bandwidth_hz is None:
        return None
    return min(float(n), 2.0 * options.noise_bandwidth_hz * duration_s)


def _standard_errors(X: np.ndarray, sse: float, n_eff: float, variance_factors: np.ndarray | None = None) -> np.ndarray:
    """OLS standard errors sqrt(sigma^2 diag((X^T X)^-1) n / n_eff) of each column.

    ``variance_factors`` is ``diag((X^T X)^-1)`` when already known (the
    reduction's downdated OLS); otherwise it is computed (pseudo-inverse of
    the column-scaled Gram matrix).
    """
    n, p = X.shape
    sigma2 = sse / max(n - p, 1)
    if variance_factors is not None:
        return np.sqrt(np.maximum(variance_factors, 0.0) * sigma2 * n / n_eff)
    norms = np.linalg.norm(X, axis=0)
    Xs = X / norms
    cov_s = np.linalg.pinv(Xs.T @ Xs)
    return np.sqrt(np.maximum(np.diag(cov_s), 0.0) * sigma2 * n / n_eff) / norms


#: Reason of an :class:`EliminationStep` that removes a term the constraints hold at zero.
HELD_AT_ZERO = "held at zero by the constraints"
#: A term's largest moment contribution, relative to the largest |moment|, below which it counts as zero.
_ZERO_CONTRIBUTION = 1e-7


def _drop_terms_held_at_zero(terms, moment_rows, tau, regs, solver, solution, reduction):
    """Remove reduced-model terms that the constraints (Eqs. 7-9) hold at zero; refit.

    The F-tests run on the unconstrained (OLS) fit. When muscles put energy
    in during stance (a push-off), the OLS damping is significantly
    *negative*; the F-test keeps it and the constraint B >= 0 then holds it
    at exactly 0. Such a term contributes nothing to the constrained fit:
    removing it leaves the constrained SSE unchanged (its constrained partial
    F is 0, p = 1), so it is removed, one at a time, last-eligible first
    under the polynomial hierarchy, as long as the refit's SSE stays the
    same (1e-6 relative) and a stiffness term remains.

    Returns
    -------
    (terms, solution, reduction) after the removals (unchanged when none).
    """
    scale = float(np.max(np.abs(tau))) or 1.0
    while True:
        columns = parameter_indices(terms)
        X = moment_rows[:, columns]
        contribution = np.abs(solution.coefficients[1:]) * np.max(np.abs(X[:, 1:]), axis=0)
        held = [
            name
            for name, c in zip(terms, contribution)
            if c <= _ZERO_CONTRIBUTION * scale and not any(h in terms for h in HIGHER_ORDER_TERMS[name])
        ]
        if not held:
            return terms, solution, reduction
        term = held[-1]
        remaining = tuple(t for t in terms if t != term)
        if not any(t.startswith("k") for t in remaining):
            return terms, solution, reduction
        new_columns = parameter_indices(remaining)
        A, _ = constraint_rows(regs, new_columns)
        refit = solver.solve(moment_rows[:, new_columns], tau, A)
        if not refit.converged or refit.sse > solution.sse * (1.0 + 1e-6) + 1e-12:
            return terms, solution, reduction
        reduction = replace(
            reduction,
            terms=remaining,
            steps=reduction.steps + (EliminationStep(term, HELD_AT_ZERO, 1.0, 0.0, float("nan")),),
            p_values={k: v for k, v in reduction.p_values.items() if k != term},
            f_statistics={k: v for k, v in reduction.f_statistics.items() if k != term},
            ols_variance_factors=None,
        )
        terms, solution = remaining, refit


def fit_joint_stance(
    time_s: np.ndarray,
    angle_rad: np.ndarray,
    angular_velocity_rad_s: np.ndarray,
    moment_nm: np.ndarray,
    options: FitOptions | None = None,
    solver: ConstrainedLeastSquares | None = None,
) -> JointImpedanceFit:
    """Fit the seed's impedance model to one joint during one stance.

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
    arrays = [np.asarray(a, float) for a in (time_s, angle_rad, angular_velocity_rad_s, moment_nm)]
    if any(a.ndim != 1 or a.shape != arrays[0].shape for a in arrays):
        raise ValueError(
            "fit_joint_stance: time_s, angle_rad, angular_velocity_rad_s and moment_nm must be 1-D arrays of one length, "
            f"got shapes {[a.shape for a in arrays]}"
        )
    t, rho, omega, tau = arrays
    reason = validate_stance(t, rho, omega, tau, options)
    if reason is not None:
        return _rejected(reason, time_s=t, angle_rad=rho, moment_nm=tau)

    regs = stance_regressors(t, rho, omega)
    window = fit_window(t, options)
    whole = bool(window.all())  # the default: nothing excluded, no windowed copies needed

    def in_window(values: np.ndarray) -> np.ndarray:
        return values if whole else values[window]

    tw, tauw = in_window(t), in_window(tau)
    n = tw.size
    start = tuple(name for name in TERM_NAMES if name in options.terms)
    moment_rows = in_window(regs.moment_rows)  # (n, 9): every candidate model takes a column subset
    full_columns = moment_rows[:, parameter_indices(start)[1:]]
    diagnostics = collinearity_diagnostics(full_columns, start)
    n_eff_given = _effective_samples(float(tw[-1] - tw[0]), n, options)
    if options.reduce:
        reduction = reduce_model(
            full_columns,
            tauw,
            terms=start,
            alpha=options.alpha,
            vif_limit=options.vif_limit,
            autocorrelation_correction=options.autocorrelation_correction,
            effective_samples=n_eff_given,
            diagnostics=diagnostics,
        )
        terms = reduction.terms
        n_eff = reduction.effective_samples
    else:
        reduction, terms = None, start
        n_eff = n_eff_given if n_eff_given is not None else float(n)
    common = dict(
        time_s=t,
        angle_rad=rho,
        moment_nm=tau,
        rho0=regs.rho0_rad,
        omega0=regs.omega0_rad_s,
        reduction=reduction,
        diagnostics=diagnostics,
        effective_samples=n_eff,
    )

    if not any(name.startswith("k") for name in terms):
        # Nothing spring-like survived the F-tests: publishing a "solved" fit
        # would present an intercept (or a damper) as this joint's impedance.
        return _rejected(
            f"model reduction kept no stiffness term (none of k0..k3 significant at alpha={options.alpha})",
            terms=terms,
            **common,
        )
    columns = parameter_indices(terms)
    X = moment_rows[:, columns]
    singular = _zero_regressor_reason(X, terms)
    if singular is not None:
        return _rejected(singular, terms=terms, **common)
    A, _ = constraint_rows(regs, columns)
    solution = solver.solve(X, tauw, A)
    if not solution.converged:
        return _rejected(
            f"OSQP did not converge: status '{solution.status}'", status=solution.status, terms=terms, **common
        )
    if reduction is not None:
        terms, solution, reduction = _drop_terms_held_at_zero(terms, moment_rows, tauw, regs, solver, solution, reduction)
        common["reduction"] = reduction
        columns = parameter_indices(terms)
        X = moment_rows[:, columns]

    theta = np.zeros(len(PARAMETER_NAMES))
    theta[columns] = solution.coefficients
    names = [PARAMETER_NAMES[c] for c in columns]
    se = _standard_errors(X, solution.sse, n_eff, reduction.ols_variance_factors if reduction is not None else None)
    dof = n_eff - X.shape[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_stat = solution.coefficients / se
    p_values = 2.0 * special.stdtr(dof, -np.abs(t_stat)) if dof > 0 else np.full(len(names), np.nan)

    moment_fit = regs.moment_rows @ theta
    residual = in_window(tau - moment_fit)
    sse = float(residual @ residual)
    sst = float(((tauw - tauw.mean()) ** 2).sum())
    stiffness = regs.stiffness_rows @ theta
    k_overall = overall_stiffness(rho, tau)
    moment_constant = constant_stiffness_moment(rho, tau, k_overall if math.isfinite(k_overall) else 0.0)
    sse_constant = float((in_window(tau - moment_constant) ** 2).sum())
    frame_rate = (n - 1) / float(tw[-1] - tw[0])
    return JointImpedanceFit(
        status=solution.status,
        rejection_reason=None,
        terms=terms,
        coefficients={name: float(v) for name, v in zip(names, solution.coefficients)},
        std_errors={name: float(v) for name, v in zip(names, se)},
        p_values={name: float(v) for name, v in zip(names, p_values)},
        stiffness=stiffness,
        damping=regs.damping_rows @ theta,
        moment_fit=moment_fit,
        moment_constant=moment_constant,
        rmse=math.sqrt(sse / n),
        r_squared=1.0 - sse / sst if sst > 0 else float("nan"),
        sse_variable=sse,
        sse_constant=sse_constant,
        table3_variable=table3_error(sse, n, frame_rate),
        table3_constant=table3_error(sse_constant, n, frame_rate),
        overall_stiffness=k_overall,
        average_stiffness=float(np.trapezoid(stiffness, t) / (t[-1] - t[0])),
        solver_iterations=solution.iterations,
        active_constraints=solution.n_active,
        **common,
    )


def _json_float(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def fit_to_json(fit: JointImpedanceFit) -> dict:
    """The ``fit`` object of one joint of one stance, with exactly :data:`FIT_JSON_KEYS`.

    Parameters
    ----------
    fit : JointImpedanceFit

    Returns
    -------
    dict
        Plain JSON types. ``coefficients``/``std_errors``/``p_values`` map the
        intercept ``m0`` (N m) and each kept term to its value (k: N m/rad,
        k1: N m/rad^2, k2: N m/rad^3, k3: N m s/rad^2, b0: N m s/rad, ...);
        ``stiffness`` (N m/rad), ``damping`` (N m s/rad) and ``moment_fit``
        (N m) are sampled at the stance samples; non-finite numbers are None.
    """

    def mapping(values: dict[str, float]) -> dict[str, float | None]:
        return {k: _json_float(v) for k, v in values.items()}

    def samples(values: np.ndarray) -> list[float | None]:
        return [_json_float(v) for v in np.asarray(values, float)]

    return {
        "terms": list(fit.terms),
        "coefficients": mapping(fit.coefficients),
        "std_errors": mapping(fit.std_errors),
        "p_values": mapping(fit.p_values),
        "rho0": _json_float(fit.rho0),
        "omega0": _json_float(fit.omega0),
        "stiffness": samples(fit.stiffness),
        "damping": samples(fit.damping),
        "moment_fit": samples(fit.moment_fit),
        "rmse": _json_float(fit.rmse),
        "r_squared": _json_float(fit.r_squared),
        "sse_variable": _json_float(fit.sse_variable),
        "sse_constant": _json_float(fit.sse_constant),
        "overall_stiffness": _json_float(fit.overall_stiffness),
        "average_stiffness": _json_float(fit.average_stiffness),
        "status": fit.status,
        "rejection_reason": fit.rejection_reason,
    }


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
