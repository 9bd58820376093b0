"""One leg at a time (issue 21): each leg's stances, inverse dynamics and impedance fits on its own plate.

The lumped analysis (:func:`~hop_impedance.biomech.analysis.analyze_recording`
on the summed plate with both legs as one) stays the default. Here each leg of
a contract v2 recording (:class:`~hop_impedance.bilateral.BilateralRecording`)
is analysed by the *same* code on a v1 view of that leg
(:meth:`BilateralRecording.leg`): its stances found by the project's one
detector on its own plate's vertical force, its 2D sagittal Newton-Euler
bottom-up from its own foot's wrench (force and centre of pressure) to its own
hip with its own markers, its impedance fitted by the existing fit.

Body-segment parameters per leg (:func:`leg_model`): foot, shank and thigh are
half the lumped (two-leg) segments, i.e. de Leva's one-side rows; lengths come
from that leg's markers. The HAT is not part of a leg: it is kept in the model
only because the v1 model has four segments, and the top-down HAT residual
(``hip_residual_rms_nm``) is meaningless for one leg, so it is set to NaN.

Single-leg hopping: the plate of the leg in the air never passes the touchdown
level, so that leg has no stance and the other is analysed alone. The
detector's levels scale with the *whole* body weight (6 % to touch down),
which one foot carrying half of it passes just as well.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hop_impedance.bilateral import SIDES, BilateralRecording
from hop_impedance.biomech.analysis import AnalysisOptions, RecordingAnalysis, analyze_recording, calibration_markers
from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.biomech.kinematics import body_model_from_markers

#: The segments of one leg (the HAT belongs to neither).
LEG_SEGMENTS = ("foot", "shank", "thigh")


def leg_model(lumped: BodyModel) -> BodyModel:
    """One leg's model from a lumped (two-leg) one: foot, shank and thigh mass and inertia halved.

    Lengths, centre-of-mass positions and the foot's shape are unchanged (they
    are per leg already: the lumped model is two identical legs on top of each
    other). The HAT is left as it is; it is not part of a leg's inverse dynamics.
    """
    halves = {name: replace(getattr(lumped, name), mass_kg=getattr(lumped, name).mass_kg / 2,
                            inertia_kgm2=getattr(lumped, name).inertia_kgm2 / 2) for name in LEG_SEGMENTS}
    return replace(lumped, **halves)


def analyze_leg(bilateral: BilateralRecording, side: str, options: AnalysisOptions | None = None) -> RecordingAnalysis:
    """Stances and per-stance inverse dynamics of one leg (see the module docstring).

    ``options.body_model``, when given, is taken as that leg's model as is;
    otherwise the lumped de Leva model is scaled from that leg's markers by
    the lumped analysis' rule (the calibration frames of
    :func:`~hop_impedance.biomech.analysis.calibration_markers`,
    ``options.overrides`` applied) and halved by :func:`leg_model`.
    """
    options = options or AnalysisOptions()
    rec = bilateral.leg(side)
    if rec.subject is None:
        raise ValueError(f"{rec.source or 'recording'}: no /subject message; give the subject's mass and height")
    model = options.body_model
    if model is None and rec.markers is not None:
        # the lumped analysis' scaling rule (same calibration frames), then halved
        model = leg_model(body_model_from_markers(rec.subject, calibration_markers(rec.markers, options.calibration_s), options.overrides))
    analysis = analyze_recording(rec, replace(options, body_model=model))
    for stance in analysis.stances:
        stance.hip_residual_rms_nm = float("nan")  # the HAT is not part of one leg: no top-down check
    return analysis


def analyze_legs(bilateral: BilateralRecording, options: AnalysisOptions | None = None) -> dict[str, RecordingAnalysis]:
    """:func:`analyze_leg` for both sides, ``{"left": ..., "right": ...}``."""
    if not bilateral.is_bilateral:
        raise ValueError(
            f"{bilateral.recording.source or 'recording'}: per-leg analysis needs contract v2 "
            "(one wrench topic per plate and both legs' markers); this is a v1 recording: use the lumped analysis"
        )
    return {side: analyze_leg(bilateral, side, options) for side in SIDES}


def fit_legs(analyses: dict[str, RecordingAnalysis], options=None) -> dict[str, list[dict]]:
    """Impedance fits per leg, stance and joint with the existing fit
    (:func:`~hop_impedance.impedance.recording_fits.fit_recording`): ``{side: [{joint: JointImpedanceFit}]}``."""
    from hop_impedance.impedance.recording_fits import fit_recording

    return {side: fit_recording(analysis, options) for side, analysis in analyses.items()}


def moments_on_common_time(analyses: dict[str, RecordingAnalysis], t_s: np.ndarray) -> dict[str, np.ndarray]:
    """Each leg's joint moments (N m, ankle/knee/hip) on times ``t_s`` (s since the recording's start).

    Zero where the leg has no accepted stance (a foot in the air carries no
    moment from the ground up apart from its own segments' inertia, which the
    stance-based analysis does not report); used to add the legs and compare
    with the lumped analysis.
    """
    out = {}
    for side, analysis in analyses.items():
        m = np.zeros((len(t_s), 3))
        for s in analysis.stances:
            if s.joints is None:
                continue
            ts = s.joints.time_s + s.touchdown_s
            sel = (t_s >= ts[0] - 1e-9) & (t_s <= ts[-1] + 1e-9)
            for j in range(3):
                m[sel, j] = np.interp(t_s[sel], ts, s.joints.moment_nm[:, j])
        out[side] = m
    return out


def analyses_to_json(analyses: dict[str, RecordingAnalysis], add_fits=None) -> dict:
    """The ``hop-impedance analyze --per-leg`` JSON: one document, each stance tagged with its ``side``.

    Each leg's part is :func:`~hop_impedance.biomech.analysis.analysis_to_json`
    (schema docs/analyze_json.md) of that leg's analysis; ``add_fits(doc,
    analysis)``, when given, adds the fits to it first (the CLI's
    ``add_fits_to_json``). ``legs[side]`` holds that leg's segments (one leg's
    foot, shank and thigh) and model structure; ``stances`` are the left leg's
    then the right leg's, each with ``"side"``.
    """
    from hop_impedance.biomech.analysis import analysis_to_json

    legs, stances, doc = {}, [], {}
    for side, analysis in analyses.items():
        doc = analysis_to_json(analysis)
        if add_fits is not None:
            add_fits(doc, analysis)
        legs[side] = {"segments": doc["subject"]["segments"], "model_structure": doc.get("model_structure")}
        stances += [{**stance, "side": side} for stance in doc["stances"]]
    subject = {k: v for k, v in doc["subject"].items() if k != "segments"}
    return {"schema": "hop_impedance.analyze_per_leg/1", "subject": subject, "recording": doc["recording"],
            "warnings": doc["warnings"], "legs": legs, "stances": stances}
