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

One model per trial (issue 15)
------------------------------
A coefficient whose meaning changes from stance to stance is of no use to a
controller or a trend plot, so a recording gets one model structure per
joint, as in the seed paper (diagnostics and F-tests over all jumps, then one
reduced model, k0 + k1 + b0, reported for every subject and frequency):

1. Every stance is fitted and reduced on its own as before (collinearity
   diagnostics, backward elimination by F-test); these per-stance fits stay
   in the output (:attr:`TrialFits.stance_fits`, ``stance_model`` in the
   ``analyze`` JSON).
2. Per joint, :func:`choose_structure` counts in how many of the stances
   that reached the F-tests each term was kept, and keeps a term kept in
   more than half of them (majority). In doubt, the seed's reduced model
   decides: a term kept in exactly half of the stances is kept if it is one
   of the seed's k0, k1, b0 and dropped otherwise; with fewer than
   ``min_stances`` (3) such stances the seed's k0, k1, b0 is used as it is.
   The structure always has a stiffness term (k0 when none reaches the
   rule). (Choice: the seed also kept its b0, "significant only in 30
   percent of the subjects' jumps"; a 30 % rule kept a spurious k1 at the
   knee of the outside generator's constant-stiffness recording none_1101,
   kept in 2 of 6 stances, so the tie is the only doubt.)
3. Every stance is refitted with that structure (no reduction), so k0, k1,
   b0 mean the same in every stance of the trial.

Live (``impedance_estimator``), :class:`StructureSelector` applies the same
rule to the first ``warmup_stances`` stances and keeps the result for the
session, or uses a structure given as a parameter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from hop_impedance.biomech.analysis import AnalysisOptions, RecordingAnalysis, StanceResult
from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import STIFFNESS_TERMS, TERM_NAMES, parameter_indices
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


#: A stance analysed on data reaching less than this past its take-off (s) is a short window
#: (``StanceResult.data_after_takeoff_s``, the low-latency mode): :func:`takeoff_exclusion_s` applies.
SHORT_WINDOW_LIMIT_S = 0.02
#: What a short window's hip fit leaves out before take-off (s): two frames of 100 Hz markers.
SHORT_WINDOW_HIP_EXCLUSION_S = 0.02


def takeoff_exclusion_s(joint: str, stance: StanceResult, options: FitOptions) -> float:
    """Time before take-off left out of ``joint``'s fit objective (s): ``options.exclude_takeoff_s``, or more.

    Choice (issue 15, docs/pipeline.md "Short windows offline and live"): when the stance was
    analysed on a short window (data ending less than :data:`SHORT_WINDOW_LIMIT_S` after
    take-off), the hip's last :data:`SHORT_WINDOW_HIP_EXCLUSION_S` are left out. Near take-off
    the ground force vanishes and the hip's net moment is mostly the inertia of the segments
    below it, whose accelerations there depend on marker frames after the take-off that a short
    window does not have yet (they are continued, ``analysis.extend_past_window``); the ankle's
    moment there is the force plate's, known at 1 kHz. Measured on the recovery trials
    (``bench/low_latency_windows.py 0.005``): without it, the clean hip cells moved up to 15.6 pp.
    """
    after = stance.data_after_takeoff_s
    if joint == "hip" and after is not None and after < SHORT_WINDOW_LIMIT_S:
        return max(options.exclude_takeoff_s, SHORT_WINDOW_HIP_EXCLUSION_S)
    return options.exclude_takeoff_s


def fit_stance_joints(
    stance: StanceResult,
    options: FitOptions | None = None,
    solvers: dict[str, ConstrainedLeastSquares] | None = None,
    joints: tuple[str, ...] = JOINT_NAMES,
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
    series = stance.joints
    if reason is not None or series is None:
        reason = reason or "no joint data for this stance"
        return {name: JointImpedanceFit(status="rejected", rejection_reason=reason) for name in joints}
    fits = {}
    for name in joints:
        data = series.joint(name)
        solver = None
        if solvers is not None:
            solver = solvers.setdefault(name, ConstrainedLeastSquares(eps=options.osqp_eps))
        excluded = takeoff_exclusion_s(name, stance, options)
        joint_options = options if excluded == options.exclude_takeoff_s else replace(options, exclude_takeoff_s=excluded)
        fits[name] = fit_joint_stance(
            data["time_s"], data["angle_rad"], data["angular_velocity_rad_s"], data["moment_nm"], joint_options, solver
        )
    return fits


#: The seed paper's reduced model (its Eq. 10): linearly variable stiffness and a constant damping.
SEED_TERMS: tuple[str, ...] = ("k0", "k1", "b0")
#: A term kept in more than this share of the stances is in the trial's structure (exactly this share: a seed term).
MAJORITY = 0.5


@dataclass(frozen=True)
class TrialStructure:
    """The model structure of one joint for a whole trial.

    Attributes
    ----------
    terms : tuple of str
        Kept terms, in Eq. 3 order (the intercept m0 is always fitted).
    kept_in : dict
        ``term -> number of stances whose own reduction kept it``.
    stances : int
        Stances whose fit reached the F-tests (the denominator of ``kept_in``).
    reason : str
        One sentence: which rule chose the structure.
    """

    terms: tuple[str, ...]
    kept_in: dict[str, int] = field(default_factory=dict)
    stances: int = 0
    reason: str = ""

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types (:func:`hop_impedance.io.impedance_json.structure_to_json`)."""
        from hop_impedance.io.impedance_json import structure_to_json

        return structure_to_json(self)


def given_structure(terms: Sequence[str], why: str = "given") -> TrialStructure:
    """A structure fixed in advance (a parameter, a command-line option); checks the names."""
    terms = tuple(terms)
    unknown = [t for t in terms if t not in TERM_NAMES]
    if unknown or not any(t in STIFFNESS_TERMS for t in terms):
        raise ValueError(f"model terms {list(terms)}: need names from {list(TERM_NAMES)} and at least one stiffness term")
    return TrialStructure(tuple(t for t in TERM_NAMES if t in terms), reason=why)


def choose_structure(stance_fits: list[JointImpedanceFit], min_stances: int = 3) -> TrialStructure:
    """One joint's structure for a trial from its per-stance reduced fits (module docstring, "One model per trial").

    Parameters
    ----------
    stance_fits : list of JointImpedanceFit
        The joint's fit in each stance, reduced stance by stance; stances
        whose fit did not reach the F-tests (rejected data) do not count.
    min_stances : int
        With fewer counted stances the seed's k0, k1, b0 is used.
    """
    reduced = [f for f in stance_fits if f.reduction is not None]
    n = len(reduced)
    kept_in = {t: sum(t in f.terms for f in reduced) for t in TERM_NAMES}
    kept_in = {t: c for t, c in kept_in.items() if c}
    if n < min_stances:
        return TrialStructure(SEED_TERMS, kept_in, n, f"the seed's k0, k1, b0: only {n} stance(s) reached the F-tests "
                                                      f"(fewer than {min_stances})")
    terms = [t for t in TERM_NAMES
             if kept_in.get(t, 0) > MAJORITY * n or (t in SEED_TERMS and kept_in.get(t, 0) == MAJORITY * n)]
    notes = [f"{t} {kept_in.get(t, 0)}/{n}" for t in TERM_NAMES if t in terms or kept_in.get(t, 0)]
    reason = (f"kept by the per-stance F-tests in more than half of the stances, a tie for the seed's k0, k1, b0 "
              f"({', '.join(notes) or 'none kept'})")
    if not any(t in STIFFNESS_TERMS for t in terms):
        terms = ["k0"] + terms
        reason += "; no stiffness term reached the rule: k0 added"
    return TrialStructure(tuple(t for t in TERM_NAMES if t in terms), kept_in, n, reason)


def structured_options(options: FitOptions, structure: TrialStructure) -> FitOptions:
    """Fit options that fit exactly ``structure`` (no reduction)."""
    return replace(options, reduce=False, terms=structure.terms)


@dataclass
class TrialFits:
    """Result of :func:`fit_recording_trial`.

    Attributes
    ----------
    fits : list of dict
        Per stance ``{joint: fit}`` with the trial's structure (what is reported).
    stance_fits : list of dict
        Per stance ``{joint: fit}`` reduced stance by stance (diagnostics, F-tests).
    structures : dict
        ``joint -> TrialStructure``.
    """

    fits: list[dict[str, JointImpedanceFit]]
    stance_fits: list[dict[str, JointImpedanceFit]]
    structures: dict[str, TrialStructure]


def fit_recording_trial(
    analysis: RecordingAnalysis,
    options: FitOptions | None = None,
    structures: dict[str, TrialStructure] | None = None,
) -> TrialFits:
    """Per-stance reduced fits, one structure per joint for the trial, and every stance refitted with it.

    Parameters
    ----------
    analysis : RecordingAnalysis
    options : FitOptions, optional
        As in :func:`fit_recording`. With ``reduce=False`` the given terms
        are the structure (nothing is chosen).
    structures : dict, optional
        ``joint -> TrialStructure`` given in advance (e.g.
        :func:`given_structure`); missing joints are chosen from the data.
    """
    options = _recording_options(analysis, options)
    solvers: dict[str, ConstrainedLeastSquares] = {}
    stance_fits = [fit_stance_joints(stance, options, solvers) for stance in analysis.stances]
    if not options.reduce:
        fixed = {j: TrialStructure(tuple(options.terms), reason="given (no reduction)") for j in JOINT_NAMES}
        return TrialFits(stance_fits, stance_fits, fixed)
    chosen = {j: (structures or {}).get(j) or choose_structure([f[j] for f in stance_fits]) for j in JOINT_NAMES}
    fits = [fit_structured(stance, options, chosen, solvers) for stance in analysis.stances]
    return TrialFits(fits, stance_fits, chosen)


def solver_key(joint: str, structure: TrialStructure) -> str:
    """Key of a joint's OSQP workspace for one structure in a ``solvers`` dict of :func:`fit_structured`."""
    return f"{joint} {' '.join(structure.terms)}"


def fit_structured(
    stance: StanceResult,
    options: FitOptions,
    structures: dict[str, TrialStructure],
    solvers: dict[str, ConstrainedLeastSquares] | None = None,
) -> dict[str, JointImpedanceFit]:
    """One stance fitted with each joint's given structure (no reduction)."""
    out = {}
    for joint in JOINT_NAMES:
        sub = None
        if solvers is not None:  # one workspace per joint and structure, shared by the trial's stances
            sub = {joint: solvers.setdefault(solver_key(joint, structures[joint]), ConstrainedLeastSquares(eps=options.osqp_eps))}
        out[joint] = _fit_one_joint(stance, joint, structured_options(options, structures[joint]), sub)
    return out


def _fit_one_joint(
    stance: StanceResult, joint: str, options: FitOptions, solvers: dict[str, ConstrainedLeastSquares] | None
) -> JointImpedanceFit:
    return fit_stance_joints(stance, options, solvers, joints=(joint,))[joint]


def _recording_options(analysis: RecordingAnalysis, options: FitOptions | None) -> FitOptions:
    if options is None:
        return default_fit_options(analysis.options)
    if options.noise_bandwidth_hz is None and options.autocorrelation_correction:
        return replace(options, noise_bandwidth_hz=noise_bandwidth_hz(analysis.options))
    return options


def fit_recording(analysis: RecordingAnalysis, options: FitOptions | None = None) -> list[dict[str, JointImpedanceFit]]:
    """Impedance fits of every stance of an analysed recording, with one model structure per joint for the trial.

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
        ``analysis.stances``, fitted with the trial's structure
        (:func:`fit_recording_trial`, which also returns the per-stance
        reductions and the structures); one OSQP workspace per joint and
        structure is shared by all stances (warm start).
    """
    return fit_recording_trial(analysis, options).fits



class StructureSelector:
    """Live counterpart of :func:`fit_recording_trial`: one structure per joint for the session.

    Parameters
    ----------
    options : FitOptions
    terms : dict or None
        ``joint -> sequence of term names`` given in advance; None chooses
        the structures after the warm-up.
    warmup_stances : int
        Stances (reaching the F-tests) over which :func:`choose_structure`
        runs; until then each stance is fitted with the seed's k0, k1, b0
        (the rule's "in doubt" default) and the structure is reported as
        provisional.
    """

    def __init__(self, options: FitOptions, terms: dict[str, Sequence[str]] | None = None, warmup_stances: int = 5,
                 given_reason: str = "given as a parameter") -> None:
        if terms is None and warmup_stances < 1:
            raise ValueError(f"warmup_stances must be >= 1 without given terms, got {warmup_stances}")
        self.options = options
        self.warmup_stances = int(warmup_stances)
        self.fixed = terms is not None
        self.structures: dict[str, TrialStructure] = (
            {j: given_structure(terms[j], given_reason) for j in JOINT_NAMES} if terms is not None else
            {j: TrialStructure(SEED_TERMS, reason=f"provisional: the seed's k0, k1, b0 until {warmup_stances} stances "
                                                  "are in") for j in JOINT_NAMES})
        self._warmup: dict[str, list[JointImpedanceFit]] = {j: [] for j in JOINT_NAMES}
        self._solvers: dict[str, ConstrainedLeastSquares] = {}

    def fit(self, stance: StanceResult) -> tuple[dict[str, JointImpedanceFit], dict[str, JointImpedanceFit] | None]:
        """Fit one stance; returns (fits with the session's structure, per-stance reduced fits or None once fixed)."""
        stance_fits = None
        if not self.fixed:
            stance_fits = fit_stance_joints(stance, self.options, self._solvers)
            for j in JOINT_NAMES:
                self._warmup[j].append(stance_fits[j])
            if all(sum(f.reduction is not None for f in self._warmup[j]) >= self.warmup_stances for j in JOINT_NAMES):
                self.structures = {j: choose_structure(self._warmup[j]) for j in JOINT_NAMES}
                self.structures = {j: replace(s, reason=f"fixed after {self.warmup_stances} stances: {s.reason}")
                                   for j, s in self.structures.items()}
                self.fixed = True
        return fit_structured(stance, self.options, self.structures, self._solvers), stance_fits

    def warm_up(self) -> None:
        """Fit a made-up stance once, thrown away, so the first real stance does not pay the first-call costs.

        The first fit in a process (OSQP's set-up, the regressors', diagnostics' and F-tests'
        first calls) takes several ms more than the later ones; a live estimator calls this at
        start, before any stance. The stance obeys the seed's law at 2.2 Hz
        (:func:`~hop_impedance.impedance.synthetic.synthetic_stance`, every joint on its time
        base); it is fitted with the session's structures (the seed's when not chosen yet) and
        reduced stance by stance; of this selector only the OSQP workspaces are set up.
        """
        import numpy as np

        from hop_impedance.biomech.analysis import JointSeries
        from hop_impedance.impedance.synthetic import synthetic_stance

        parts = [synthetic_stance(j, 2.2, rate_hz=1000.0) for j in JOINT_NAMES]
        t = parts[0].time_s
        angle, omega, moment = (np.column_stack([getattr(p, name) for p in parts])
                                for name in ("angle_rad", "angular_velocity_rad_s", "moment_nm"))
        stance = StanceResult(0, 0.0, float(t[-1]), True, None, float(t[-1]), 1500.0, 2.8, None, None, 2.2,
                              joints=JointSeries(t, angle, omega, moment, moment * omega))
        structures = self.structures if self.fixed else {j: given_structure(SEED_TERMS) for j in JOINT_NAMES}
        # the selector's own workspaces: their OSQP set-up is most of the first fit's extra cost; every solve
        # sets its data and warm start anew, so the made-up stance leaves no trace in later results
        fit_structured(stance, self.options, structures, self._solvers)
        for j, structure in structures.items():
            self._solvers[solver_key(j, structure)].prepare(len(parameter_indices(structure.terms)))
        fit_stance_joints(stance, self.options, {})


__all__ = [
    "SEED_TERMS", "StructureSelector", "TrialFits", "TrialStructure", "choose_structure", "default_fit_options",
    "fit_recording", "fit_recording_trial", "fit_stance_joints", "fit_structured", "given_structure", "noise_bandwidth_hz",
    "takeoff_exclusion_s",
]
