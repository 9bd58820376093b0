"""Impedance fits of every joint of every stance of an analysed recording.

Glue between the batch/streaming analysis (:mod:`hop_impedance.biomech.analysis`,
whose :class:`StanceResult` carries the stance's joint angles, velocities and
net moments) and :func:`fit_joint_stance`. Pure numpy/scipy/osqp: the ROS
impedance estimator node calls :func:`fit_stance_joints` per stance.

Noise bandwidth (choice): the fit's effective sample count is ``2 * B * T``
with ``B`` the low-pass cut-off of the data (see ``FitOptions``). Angles are
filtered at the marker cut-off and moments combine forces (force cut-off) and
segment accelerations (marker cut-off), so the residual's band reaches the
*larger* of the two; ``B = max(marker_cutoff_hz, force_cutoff_hz)``. The two
are equal by default (12 Hz).
"""

from __future__ import annotations

from dataclasses import replace

from hop_impedance.biomech.analysis import AnalysisOptions, RecordingAnalysis, StanceResult
from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.stance_fit import FitOptions, JointImpedanceFit, fit_joint_stance


def noise_bandwidth_hz(options: AnalysisOptions | None) -> float:
    """Noise bandwidth (Hz) of the joint data produced with ``options``.

    Parameters
    ----------
    options : AnalysisOptions or None
        None means the analysis defaults.

    Returns
    -------
    float
        ``max(marker_cutoff_hz, force_cutoff_hz)`` (see the module docstring).
    """
    options = options or AnalysisOptions()
    return float(max(options.marker_cutoff_hz, options.force_cutoff_hz))


def default_fit_options(analysis_options: AnalysisOptions | None = None) -> FitOptions:
    """:class:`FitOptions` with the noise bandwidth of the analysis that produced the data."""
    return FitOptions(noise_bandwidth_hz=noise_bandwidth_hz(analysis_options))


def _stance_reason(stance: StanceResult) -> str | None:
    if stance.rejection_reason is not None:
        return stance.rejection_reason
    if stance.joints is None:
        return "no joint data for this stance"
    return None


def fit_stance_joints(
    stance: StanceResult,
    options: FitOptions | None = None,
    solvers: dict[str, ConstrainedLeastSquares] | None = None,
) -> dict[str, JointImpedanceFit]:
    """Fit the impedance model to the ankle, knee and hip of one stance.

    Parameters
    ----------
    stance : StanceResult
        One stance of :func:`analyze_recording` or the streaming stage. Its
        ``joints`` series start at touchdown (t = 0) and end at take-off;
        angles rho (rad, flexion positive), omega (rad/s), net moments of
        both legs (N m, extensor positive).
    options : FitOptions, optional
        Default :func:`default_fit_options` (noise bandwidth = the default
        12 Hz analysis cut-off). Pass ``default_fit_options(analysis.options)``
        when the analysis used other cut-offs.
    solvers : dict, optional
        ``joint name -> ConstrainedLeastSquares`` reused across stances (warm
        start); missing joints are added to the dict, so pass ``{}`` once and
        keep it.

    Returns
    -------
    dict
        ``{"ankle": fit, "knee": fit, "hip": fit}``. A stance that is
        rejected by the analysis (incomplete, marker gap, ...) gives fits with
        ``status == "rejected"`` and the stance's ``rejection_reason``; a stance
        the fit itself cannot use gives the fit's reason. Never raises for
        bad stance data.
    """
    options = options or default_fit_options()
    reason = _stance_reason(stance)
    if reason is not None:
        return {name: JointImpedanceFit(status="rejected", rejection_reason=reason) for name in JOINT_NAMES}
    fits = {}
    for name in JOINT_NAMES:
        data = stance.joints.joint(name)
        solver = None
        if solvers is not None:
            solver = solvers.setdefault(name, ConstrainedLeastSquares(eps=options.osqp_eps))
        fits[name] = fit_joint_stance(
            data["time_s"], data["angle_rad"], data["angular_velocity_rad_s"], data["moment_nm"], options, solver
        )
    return fits


def fit_recording(analysis: RecordingAnalysis, options: FitOptions | None = None) -> list[dict[str, JointImpedanceFit]]:
    """Impedance fits of every stance of an analysed recording.

    Parameters
    ----------
    analysis : RecordingAnalysis
    options : FitOptions, optional
        Default: :func:`default_fit_options` of ``analysis.options`` (noise
        bandwidth = the analysis' cut-off). Given options are used as they
        are, except that a missing ``noise_bandwidth_hz`` (None, with the
        autocorrelation correction on) is filled in from the analysis (the pipeline knows it; estimating it from the
        residuals is the less reliable fallback for data of unknown origin).

    Returns
    -------
    list of dict
        One ``{joint: JointImpedanceFit}`` per stance, in the order of
        ``analysis.stances``; one OSQP workspace per joint is shared by all
        stances (warm start).
    """
    if options is None:
        options = default_fit_options(analysis.options)
    elif options.noise_bandwidth_hz is None and options.autocorrelation_correction:
        options = replace(options, noise_bandwidth_hz=noise_bandwidth_hz(analysis.options))
    solvers: dict[str, ConstrainedLeastSquares] = {}
    return [fit_stance_joints(stance, options, solvers) for stance in analysis.stances]


__all__ = ["default_fit_options", "fit_recording", "fit_stance_joints", "noise_bandwidth_hz"]
