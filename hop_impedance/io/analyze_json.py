"""The ``hop-impedance analyze`` JSON documents, made from the core's dataclasses (schema: docs/analyze_json.md).

Issue 20: the core returns dataclasses (:class:`~hop_impedance.biomech.analysis.RecordingAnalysis`,
:class:`~hop_impedance.biomech.analysis.StanceResult`); JSON is made here, in ``io/``, as the impedance fits'
is in :mod:`hop_impedance.io.impedance_json`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from hop_impedance.biomech.analysis import RecordingAnalysis, StanceResult
from hop_impedance.biomech.joint_angles import JOINT_NAMES


def _num(x: float | None) -> float | None:
    return None if x is None or not np.isfinite(x) else float(x)


def stance_to_json(s: StanceResult, start_ns: int) -> dict[str, Any]:
    """One stance as a JSON-ready dict (schema in docs/analyze_json.md)."""
    out: dict[str, Any] = {
        "index": s.index,
        "touchdown_s": s.touchdown_s,
        "takeoff_s": s.takeoff_s,
        "touchdown_stamp_ns": int(start_ns + round(s.touchdown_s * 1e9)),
        "complete": s.complete,
        "rejection_reason": s.rejection_reason,
        "contact_time_s": s.contact_time_s,
        "flight_before_s": _num(s.flight_before_s),
        "flight_after_s": _num(s.flight_after_s),
        "peak_grf_N": _num(s.peak_grf_n),
        "peak_grf_bw": _num(s.peak_grf_bw),
        "hop_frequency_hz": _num(s.hop_frequency_hz),
        "leg_stiffness_n_per_m": _num(s.leg_stiffness_n_per_m),
        "leg_stiffness_kinematic_n_per_m": _num(s.leg_stiffness_kinematic_n_per_m),
        "com_drop_grf_m": _num(s.com_drop_grf_m),
        "com_drop_kinematic_m": _num(s.com_drop_kinematic_m),
        "hip_excursion_m": _num(s.hip_excursion_m),
        "hip_residual_rms_nm": _num(s.hip_residual_rms_nm),
        "joints": None,
    }
    if s.joints is not None:
        # _stance_result sets the works and stiffness with the joints
        assert s.brake_work_j is not None and s.push_work_j is not None and s.overall_stiffness_nm_per_rad is not None
        out["joints"] = {}
        for j, name in enumerate(JOINT_NAMES):
            arrays = {k: v.tolist() for k, v in s.joints.joint(name).items()}
            arrays["brake_work_j"] = float(s.brake_work_j[j])
            arrays["push_work_j"] = float(s.push_work_j[j])
            arrays["overall_stiffness_nm_per_rad"] = _num(s.overall_stiffness_nm_per_rad[j])
            out["joints"][name] = arrays
    return out


def analysis_to_json(analysis: RecordingAnalysis) -> dict[str, Any]:
    """The ``hop-impedance analyze`` JSON document (schema in docs/analyze_json.md)."""
    subj = analysis.subject
    model = analysis.model
    return {
        "schema": "hop_impedance.analyze/1",
        "subject": {
            "subject_id": subj.subject_id,
            "body_mass_kg": subj.body_mass_kg,
            "body_height_m": subj.body_height_m,
            "sex": subj.sex,
            "segments": None
            if model is None
            else {
                seg.name: {
                    "mass_kg": seg.mass_kg,
                    "length_m": seg.length_m,
                    "com_along_m": seg.com_along_m,
                    "com_perp_m": seg.com_perp_m,
                    "inertia_kgm2": seg.inertia_kgm2,
                }
                for seg in model.segments
            },
        },
        "recording": analysis.recording,
        "warnings": analysis.warnings,
        "stances": [stance_to_json(s, analysis.start_ns) for s in analysis.stances],
    }


def analyses_to_json(
    analyses: dict[str, RecordingAnalysis], add_fits: Callable[[dict[str, Any], RecordingAnalysis], object] | None = None
) -> dict[str, Any]:
    """The ``hop-impedance analyze --per-leg`` JSON: one document, each stance tagged with its ``side``.

    Each leg's part is :func:`analysis_to_json`
    (schema docs/analyze_json.md) of that leg's analysis; ``add_fits(doc,
    analysis)``, when given, adds the fits to it first (the CLI's
    ``add_fits_to_json``). ``legs[side]`` holds that leg's segments (one leg's
    foot, shank and thigh) and model structure; ``stances`` are the left leg's
    then the right leg's, each with ``"side"``.
    """
    legs, stances, doc, warnings = {}, [], {}, []
    for side, analysis in analyses.items():
        doc = analysis_to_json(analysis)
        if add_fits is not None:
            add_fits(doc, analysis)
        legs[side] = {"segments": doc["subject"]["segments"], "model_structure": doc.get("model_structure")}
        stances += [{**stance, "side": side} for stance in doc["stances"]]
        warnings += [w for w in doc["warnings"] if w not in warnings]  # both legs' notes (e.g. each rigid fit's)
    subject = {k: v for k, v in doc["subject"].items() if k != "segments"}
    return {"schema": "hop_impedance.analyze_per_leg/1", "subject": subject, "recording": doc["recording"],
            "warnings": warnings, "legs": legs, "stances": stances}
