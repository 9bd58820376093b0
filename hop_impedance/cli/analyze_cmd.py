"""``hop-impedance analyze REC.mcap --json OUT.json``: stances, inverse dynamics and impedance fits.

Every analysed stance's joint objects carry a ``fit`` object
(:func:`hop_impedance.impedance.stance_fit.fit_to_json`) unless ``--no-fit``.

The JSON schema is documented in docs/analyze_json.md.
"""

from __future__ import annotations

import argparse

from hop_impedance.cli.conventions import OptionDefault

OPTIONS = "hop_impedance.biomech.analysis:AnalysisOptions"

def register(subparsers) -> None:
    """Add the ``analyze`` parser."""
    p = subparsers.add_parser(
        "analyze",
        help="stances, joint kinematics and inverse dynamics of a recording",
        description="Detect stances, run 2D inverse dynamics and write per-stance results as JSON.",
    )
    p.add_argument("recordings", nargs="+", metavar="recording",
                   help="contract recording(s) (MCAP); with several, the JSON is a list of documents")
    p.add_argument("--json", required=True, metavar="OUT", help="output JSON file ('-' for stdout)")
    p.add_argument("--mass-kg", type=float, help="body mass (kg), overrides/replaces the /subject message")
    p.add_argument("--height-m", type=float, help="body height (m), overrides/replaces the /subject message")
    p.add_argument("--sex", choices=("female", "male"), help="de Leva table (default: the recording's, else female)")
    p.add_argument("--segments", metavar="YAML", help="per-segment overrides of the body model")
    p.add_argument("--cutoff-hz", type=float, default=OptionDefault(OPTIONS, "marker_cutoff_hz"),
                   help="low-pass cut-off for markers and forces (Hz, default %(default)s)")
    p.add_argument("--max-gap-s", type=float, default=OptionDefault(OPTIONS, "max_gap_s"),
                   help="longest marker gap filled (s, default %(default)s)")
    p.add_argument("--detector", action="append", metavar="NAME=VALUE",
                   help="stance detection setting (repeatable), e.g. takeoff_n=15; names and defaults: "
                        "DetectorOptions in biomech/stance_detection.py, the same as the nodes' parameters")
    p.add_argument("--model-terms", metavar="T1,T2,...",
                   help="fit this structure to every stance and joint (e.g. k0,k1,b0) instead of choosing one per joint "
                        "for the recording from the per-stance F-tests")
    p.add_argument("--no-fit", action="store_true", help="skip the per-stance impedance fits (no 'fit' objects)")
    p.add_argument("--per-leg", action="store_true",
                   help="contract v2 recordings: analyse each leg on its own plate and markers (docs/contract_v2.md)")
    p.add_argument("--report", metavar="DIR",
                   help="write Table 2/3 layouts (CSV, Markdown, Wilcoxon tests) and PNG figures of the fits; "
                        "one condition per recording, labelled by its median hop frequency")
    p.add_argument("--indent", type=int, default=None, help="pretty-print the JSON with this indent")
    p.set_defaults(func=run)


def _subject(rec, args, path):
    from dataclasses import replace

    from hop_impedance.recording import Subject

    subj = rec.subject
    if subj is None:
        if args.mass_kg is None or args.height_m is None:
            raise ValueError(f"{path}: no /subject message; give --mass-kg and --height-m")
        subj = Subject("unknown", args.mass_kg, args.height_m)
    changes = {}
    if args.mass_kg is not None:
        changes["body_mass_kg"] = args.mass_kg
    if args.height_m is not None:
        changes["body_height_m"] = args.height_m
    if args.sex is not None:
        changes["sex"] = args.sex
    return replace(subj, **changes) if changes else subj


def add_fits_to_json(doc: dict, analysis, model_terms: list[str] | None = None) -> list[dict]:
    """Fit every stance of ``analysis`` and put each joint's ``fit`` object into ``doc``.

    One model structure per joint for the recording (``recording_fits``, "One
    model per trial"): ``doc["model_structure"][joint]`` says which terms and
    why, each ``fit`` uses them, and ``stance_model`` next to it keeps that
    stance's own reduction (terms and p-values of its F-tests).
    ``model_terms`` fixes the structure for every joint instead.

    Parameters
    ----------
    doc : dict
        ``analysis_to_json(analysis)``; changed in place: ``stances[i].joints[joint].fit``
        for stances with joint data (rejected stances have ``joints: null``
        and no fit; their reason is the stance's ``rejection_reason``).
    analysis : RecordingAnalysis
    model_terms : list of str, optional

    Returns
    -------
    list of dict
        The fits, one ``{joint: JointImpedanceFit}`` per stance.
    """
    from hop_impedance.impedance.recording_fits import fit_recording_trial, given_structure
    from hop_impedance.impedance.stance_fit import fit_to_json

    given = None
    if model_terms:
        structure = given_structure(model_terms, "given on the command line (--model-terms)")
        given = {name: structure for name in ("ankle", "knee", "hip")}
    trial = fit_recording_trial(analysis, structures=given)
    doc["model_structure"] = {name: s.to_json() for name, s in trial.structures.items()}
    for stance, stance_fits, own in zip(doc["stances"], trial.fits, trial.stance_fits):
        if stance["joints"] is None:
            continue
        for name, fit in stance_fits.items():
            stance["joints"][name]["fit"] = fit_to_json(fit)
            stance["joints"][name]["stance_model"] = {"terms": list(own[name].terms),
                                                      "p_values": fit_to_json(own[name])["p_values"]}
    return trial.fits


def condition_label(analysis, path: str, taken: list[str]) -> str:
    """Report condition of one recording: its median hop frequency ("2.20 Hz"), else the file name; made unique."""
    import os

    import numpy as np

    freqs = [s.hop_frequency_hz for s in analysis.stances if s.hop_frequency_hz is not None]
    label = f"{np.median(freqs):.2f} Hz" if freqs else os.path.basename(path)
    base, k = label, 2
    while label in taken:
        label, k = f"{base} ({k})", k + 1
    return label


def checked_recording(path: str, flags, cutoff_hz: float, per_leg: bool = False):
    """A recording as ``analyze`` takes it: loaded (v2 per-leg view if ``per_leg``), with the subject in use
    (the file's /subject or ``flags.mass_kg/height_m/sex``) and the shared contract checks run again with that
    subject and the cut-off (rates rule). ``hop-impedance batch`` runs the same steps through this function.

    Returns
    -------
    (Recording, BilateralRecording or None)
    """
    from dataclasses import replace

    from hop_impedance.bilateral import load_bilateral
    from hop_impedance.input_checks import InputChecks
    from hop_impedance.io.recording_io import check_recording, load_recording

    bilateral = load_bilateral(path) if per_leg else None
    rec = bilateral.recording if bilateral is not None else load_recording(path)
    subject = _subject(rec, flags, path)
    rec = replace(rec, subject=subject)
    checks = InputChecks(cutoff_hz=cutoff_hz)
    checks.set_subject(subject)
    check_recording(checks, rec.force, rec.markers)
    return rec, bilateral


def analyze_and_fit(rec, options, model_terms: list[str] | None, fit: bool = True):
    """``analyze``'s analysis of one checked recording: (RecordingAnalysis, JSON dict, per-stance fits or None)."""
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.io.analyze_json import analysis_to_json

    analysis = analyze_recording(rec, options)
    doc = analysis_to_json(analysis)
    return analysis, doc, (add_fits_to_json(doc, analysis, model_terms) if fit else None)


def run(args: argparse.Namespace) -> int:
    """Load, analyse, write the JSON; print a one-line summary on stderr."""
    import json
    import sys

    from hop_impedance.cli.json_output import json_output
    from hop_impedance.impedance.report import write_report

    options = _options_from_args(args)
    with json_output(args.json) as write_json:
        docs: list[dict] = []
        records: list = []
        conditions: list[str] = []
        terms = args.model_terms.split(",") if args.model_terms else None
        for path in args.recordings:
            docs.append(_analyze_path(path, args, options, terms, records, conditions))
        if args.report:
            written = write_report(records, conditions, args.report)
            print(f"hop-impedance analyze: report ({len(written)} files) -> {args.report}", file=sys.stderr)
        doc = docs[0] if len(docs) == 1 else docs
        write_json(json.dumps(doc, indent=args.indent, allow_nan=False))
    print(_summary_line(docs, args), file=sys.stderr)
    return 0


def _options_from_args(args: argparse.Namespace):
    """``AnalysisOptions`` from the flags, after the checks that need no recording (one-line ValueErrors)."""
    from hop_impedance.biomech.analysis import AnalysisOptions
    from hop_impedance.biomech.body_model import load_overrides
    from hop_impedance.biomech.stance_detection import DetectorOptions

    if not args.cutoff_hz > 0:
        raise ValueError(f"--cutoff-hz must be > 0, got {args.cutoff_hz}")
    if not args.max_gap_s >= 0:
        raise ValueError(f"--max-gap-s must be >= 0, got {args.max_gap_s}")
    if args.report and args.no_fit:
        raise ValueError("--report needs the fits; drop --no-fit")
    if args.report and args.per_leg:
        raise ValueError("--report is for the lumped analysis; drop --per-leg or --report")
    return AnalysisOptions(
        marker_cutoff_hz=args.cutoff_hz,
        force_cutoff_hz=args.cutoff_hz,
        max_gap_s=args.max_gap_s,
        overrides=load_overrides(args.segments) if args.segments else None,
        detector=DetectorOptions.from_settings(args.detector),
    )


def _analyze_path(path: str, args: argparse.Namespace, options, terms: list[str] | None, records: list,
                  conditions: list[str]) -> dict:
    """The JSON document of one recording (per leg with ``--per-leg``), its warnings printed on stderr.

    A lumped analysis with fits also appends its fit records and its
    condition label to ``records`` and ``conditions`` (for ``--report``).
    """
    import os
    import sys
    from dataclasses import replace

    from hop_impedance.biomech.per_leg import analyze_legs
    from hop_impedance.impedance.report import fit_records
    from hop_impedance.io.analyze_json import analyses_to_json

    rec, bilateral = checked_recording(path, args, min(options.marker_cutoff_hz, options.force_cutoff_hz), args.per_leg)
    for warning in rec.warnings:
        named = warning if warning.startswith(f"{os.path.basename(path)}:") else f"{path}: {warning}"
        print(f"hop-impedance analyze: warning: {named}", file=sys.stderr)
    if bilateral is not None:
        fits = None if args.no_fit else (lambda d, a: add_fits_to_json(d, a, terms))
        return analyses_to_json(analyze_legs(replace(bilateral, recording=rec), options), fits)
    analysis, doc, fits = analyze_and_fit(rec, options, terms, fit=not args.no_fit)
    if fits is not None:
        label = condition_label(analysis, path, conditions)
        conditions.append(label)
        records += fit_records(fits, label, analysis.subject.subject_id)
    return doc


def _summary_line(docs: list[dict], args: argparse.Namespace) -> str:
    """The one-line summary: stances, stances with inverse dynamics, solved joint fits, output."""
    stances = [s for d in docs for s in d["stances"]]
    n = len(stances)
    ok = sum(1 for s in stances if s["joints"] is not None)
    fitted = sum(1 for s in stances for j in (s["joints"] or {}).values() if (j.get("fit") or {}).get("status") == "solved")
    fit_note = "" if args.no_fit else f", {fitted} joint fits"
    return f"hop-impedance analyze: {n} stances, {ok} with inverse dynamics{fit_note} -> {args.json}"
