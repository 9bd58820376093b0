"""JSON forms of the impedance fit's results (the core returns dataclasses; documents are made here).

``fit_to_json`` is the per-joint ``fit`` object of ``hop-impedance analyze``
JSON; ``diagnostics_to_json`` and ``structure_to_json`` the collinearity
diagnostics and a trial's model structure. Non-finite numbers become None
(JSON has no NaN or inf).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # the core imports this module for its re-exports: no import cycle at run time
    from hop_impedance.impedance.diagnostics import CollinearityDiagnostics
    from hop_impedance.impedance.recording_fits import TrialStructure
    from hop_impedance.impedance.stance_fit import JointImpedanceFit

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


def json_float(value: float) -> float | None:
    """``float(value)``, or None when it is NaN or infinite."""
    value = float(value)
    return value if math.isfinite(value) else None


def _mapping(values: dict[str, float]) -> dict[str, float | None]:
    return {k: json_float(v) for k, v in values.items()}


def _samples(values: np.ndarray) -> list[float | None]:
    return [json_float(v) for v in np.asarray(values, float)]


def fit_to_json(fit: JointImpedanceFit) -> dict[str, Any]:
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
    return {
        "terms": list(fit.terms),
        "coefficients": _mapping(fit.coefficients),
        "std_errors": _mapping(fit.std_errors),
        "p_values": _mapping(fit.p_values),
        "rho0": json_float(fit.rho0),
        "omega0": json_float(fit.omega0),
        "stiffness": _samples(fit.stiffness),
        "damping": _samples(fit.damping),
        "moment_fit": _samples(fit.moment_fit),
        "rmse": json_float(fit.rmse),
        "r_squared": json_float(fit.r_squared),
        "sse_variable": json_float(fit.sse_variable),
        "sse_constant": json_float(fit.sse_constant),
        "overall_stiffness": json_float(fit.overall_stiffness),
        "average_stiffness": json_float(fit.average_stiffness),
        "status": fit.status,
        "rejection_reason": fit.rejection_reason,
    }


def _clean(value: Any) -> Any:
    """Floats and nested lists of an array-like, None for NaN and inf."""
    out = np.asarray(value, float).tolist()
    if isinstance(out, list):
        return [_clean(v) for v in out]
    return json_float(out)


def diagnostics_to_json(diagnostics: CollinearityDiagnostics) -> dict[str, Any]:
    """Plain-JSON form of :class:`CollinearityDiagnostics` (lists and floats; inf/NaN become None)."""
    d = diagnostics
    return {
        "terms": list(d.terms),
        "hessian_log10_determinant": _clean(d.hessian_log10_determinant),
        "hessian_eigenvalue_ratio": _clean(d.hessian_eigenvalue_ratio),
        "correlation_matrix": _clean(d.correlation_matrix),
        "correlation_determinant": _clean(d.correlation_determinant),
        "correlation_eigenvalue_ratio": _clean(d.correlation_eigenvalue_ratio),
        "variance_inflation_factors": dict(zip(d.terms, _clean(d.variance_inflation_factors))),
    }


def structure_to_json(structure: TrialStructure) -> dict[str, Any]:
    """Plain-JSON form of a trial's :class:`TrialStructure` (terms, kept-in counts, stances, reason)."""
    return {"terms": list(structure.terms), "kept_in": dict(structure.kept_in), "stances": structure.stances,
            "reason": structure.reason}
