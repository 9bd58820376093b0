"""What the per-stance views need, independent of where it came from.

The offline view builds these from :class:`StanceResult` and
:class:`JointImpedanceFit`; the live bridge builds them from the
``StanceSummary`` and ``ImpedanceProfile`` messages. The logging functions
only see these plain containers, so both paths draw the same thing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hop_impedance.biomech.joint_angles import JOINT_NAMES

#: Units of the model terms (seed Eqs. 3-5) for the table.
TERM_UNITS: dict[str, str] = {
    "m0": "N m",
    "k0": "N m/rad",
    "k1": "N m/rad²",
    "k2": "N m/rad³",
    "k3": "N m s/rad²",
    "b0": "N m s/rad",
    "b1": "N m s²/rad²",
    "b2": "N m s³/rad³",
    "b3": "N m s/rad²",
}


@dataclass
class JointFitView:
    """One joint of one stance, as drawn.

    Attributes
    ----------
    rejection_reason : str or None
        None for a usable fit; otherwise why there is none (arrays may be empty).
    time_s : ndarray, shape (n,)
        Time since touchdown (s).
    angle_rad : ndarray, shape (n,)
        rho (rad), increases with flexion.
    moment_nm, moment_fit_nm, moment_constant_nm : ndarray, shape (n,)
        Inverse-dynamics moment, variable-stiffness fit, constant-stiffness
        model (N m, extensor positive).
    stiffness_nm_per_rad : ndarray, shape (n,)
        K(t) of the fitted model (N m/rad).
    coefficients, std_errors, p_values : dict
        Kept terms (``m0`` intercept, ``k0``, ``k1``, ``b0`` ...), SI units of :data:`TERM_UNITS`.
    r_squared, rmse_nm, sse_variable, sse_constant, overall_stiffness_nm_per_rad : float
    """

    rejection_reason: str | None
    time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    angle_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_fit_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    moment_constant_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stiffness_nm_per_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))
    coefficients: dict[str, float] = field(default_factory=dict)
    std_errors: dict[str, float] = field(default_factory=dict)
    p_values: dict[str, float] = field(default_factory=dict)
    r_squared: float = float("nan")
    rmse_nm: float = float("nan")
    sse_variable: float = float("nan")
    sse_constant: float = float("nan")
    overall_stiffness_nm_per_rad: float = float("nan")

    @property
    def ok(self) -> bool:
        """True when the fit can be drawn."""
        return self.rejection_reason is None and self.time_s.size > 0

    def coefficient(self, name: str) -> float:
        """Coefficient ``name`` (0 when the term was eliminated, NaN when rejected).

        Choice: an eliminated term (e.g. k1 dropped by the F-test) is a
        coefficient of zero in the model, so the trend plots show 0 for it.
        """
        if not self.ok:
            return float("nan")
        return float(self.coefficients.get(name, 0.0))


@dataclass
class StanceView:
    """One stance, as drawn (times in s since the recording's first message)."""

    index: int
    touchdown_s: float
    takeoff_s: float
    rejection_reason: str | None = None
    contact_time_s: float = float("nan")
    peak_grf_bw: float = float("nan")
    hop_frequency_hz: float | None = None
    joints: dict[str, JointFitView] = field(default_factory=dict)


def joint_view_from_fit(fit) -> JointFitView:
    """:class:`JointFitView` of a :class:`hop_impedance.impedance.stance_fit.JointImpedanceFit`."""
    if not fit.ok:
        return JointFitView(rejection_reason=fit.rejection_reason or f"fit status {fit.status}")
    return JointFitView(
        rejection_reason=None,
        time_s=np.asarray(fit.time_s, float),
        angle_rad=np.asarray(fit.angle_rad, float),
        moment_nm=np.asarray(fit.moment_nm, float),
        moment_fit_nm=np.asarray(fit.moment_fit, float),
        moment_constant_nm=np.asarray(fit.moment_constant, float),
        stiffness_nm_per_rad=np.asarray(fit.stiffness, float),
        coefficients=dict(fit.coefficients),
        std_errors=dict(fit.std_errors),
        p_values=dict(fit.p_values),
        r_squared=fit.r_squared,
        rmse_nm=fit.rmse,
        sse_variable=fit.sse_variable,
        sse_constant=fit.sse_constant,
        overall_stiffness_nm_per_rad=fit.overall_stiffness,
    )


def stance_view_from_result(stance, fits: dict | None) -> StanceView:
    """:class:`StanceView` of an analysed stance and its fits (``{joint: JointImpedanceFit}`` or None)."""
    view = StanceView(
        index=stance.index,
        touchdown_s=stance.touchdown_s,
        takeoff_s=stance.takeoff_s,
        rejection_reason=stance.rejection_reason,
        contact_time_s=stance.contact_time_s,
        peak_grf_bw=stance.peak_grf_bw,
        hop_frequency_hz=stance.hop_frequency_hz,
    )
    reason = stance.rejection_reason or ("no impedance fit" if not fits else None)
    for joint in JOINT_NAMES:
        fit = (fits or {}).get(joint)
        view.joints[joint] = JointFitView(rejection_reason=reason) if fit is None or reason else joint_view_from_fit(fit)
    return view


def _num(value: float | None, fmt: str = ".3g") -> str:
    if value is None or not math.isfinite(value):
        return "–"
    return format(value, fmt)


def _term_cell(j: JointFitView, name: str) -> str:
    p = j.p_values.get(name, float("nan"))
    p_text = "p<0.001" if math.isfinite(p) and p < 0.001 else f"p={_num(p, '.3f')}"
    return f"{name} = {_num(j.coefficients[name], '.4g')} ± {_num(j.std_errors.get(name), '.2g')} ({p_text})"


def fit_table_markdown(view: StanceView) -> str:
    """Markdown table of one stance: events, and per joint the kept terms and fit statistics.

    Parameters
    ----------
    view : StanceView

    Returns
    -------
    str
        A heading line, a summary line, and a table with one row per joint:
        terms ``name = value ± SE (p)``, R², RMSE (N m), SSE of the variable
        and constant-stiffness models (N² m²), overall stiffness (N m/rad);
        a rejected joint shows its reason instead.
    """
    freq = _num(view.hop_frequency_hz, ".2f") if view.hop_frequency_hz is not None else "–"
    lines = [
        f"### Stance {view.index}: {view.touchdown_s:.3f}–{view.takeoff_s:.3f} s",
        f"contact {_num(view.contact_time_s, '.3f')} s · peak GRF {_num(view.peak_grf_bw, '.2f')} BW · hop {freq} Hz",
        "",
    ]
    if view.rejection_reason:
        lines.append(f"**Rejected:** {view.rejection_reason}")
        return "\n".join(lines)
    lines += [
        "| joint | kept terms (SI) | R² | RMSE N m | SSE var / const | K overall N m/rad |",
        "|---|---|---|---|---|---|",
    ]
    for name, j in view.joints.items():
        if not j.ok:
            lines.append(f"| {name} | rejected: {j.rejection_reason} | | | | |")
            continue
        terms = "<br>".join(_term_cell(j, t) for t in j.coefficients if t != "m0")
        lines.append(
            f"| {name} | {terms} | {_num(j.r_squared, '.3f')} | {_num(j.rmse_nm, '.3g')} | "
            f"{_num(j.sse_variable, '.4g')} / {_num(j.sse_constant, '.4g')} | {_num(j.overall_stiffness_nm_per_rad, '.4g')} |"
        )
    return "\n".join(lines)
