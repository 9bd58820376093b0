"""Hit rate per hidden effect and false-discovery rate on null recordings (issue 8).

Generates recordings with :func:`hop_impedance.simulation.stance_set.simulate_stance_set_recording`
(8 hops by default, seed 001 / Table 2 laws at the seed's frequencies, default sensor noise:
force 2 N, markers 1 mm) with one hidden effect each at the explicit sizes of
:class:`~hop_impedance.simulation.stance_set.EffectSizes` and :data:`SENSOR_SIZES`,
plus null (baseline truth) and two-effect cases, and runs
:func:`hop_impedance.discovery.workflow.discover` (selection only, no forward gaps).

Counting
--------
- ``exact``: the set of named effects equals the hidden set;
- ``named``: every hidden effect is named (possibly with an extra name);
- ``named or ambiguous``: every hidden effect is named or listed in a step's
  ``ambiguous_with`` (the workflow said it cannot tell them apart);
- ``extra``: a name outside the hidden set (on nulls: a false discovery);
- generation failures (a stance that does not take off even after re-draws)
  are counted apart: they are not runs of the workflow;
- on ``null``, the two-sided 95 % Clopper-Pearson interval of the false-discovery
  rate (``scipy.stats.binomtest(extra, runs).proportion_ci()``) and the one-sided 95 % upper bound
  (``alternative="less"``) are printed under the table.

Three sources (issue 16): our simulator (``--cases``), the second generator
(``--strict-cases``, :mod:`hop_impedance.validation.strict_generator`) and truth-labelled outside
recordings (``--foreign DIR``). The table gives counts with two-sided 95 % Clopper-Pearson intervals and
the number of named steps whose held-out forward gap did not shrink.

Usage: .venv/bin/python bench/discovery_hit_rates.py [--seeds N] [--null-seeds N] [--hops N] [--cases a,b,...]
       [--sizes rate_fraction=0.25,...] [--freqs 2.2]
       [--strict-cases null,angle_dependent_stiffness,... --strict-seeds N --strict-null-seeds N]
       [--strict-null-seed-list 1,3,7] [--foreign DIR]
Prints one line per run and the table (markdown) at the end.
``--scheduler local`` (the embedded cluster of ``hop-impedance batch``) or ``--scheduler tcp://HOST:8786``
runs one Dask task per case and seed through :func:`hop_impedance.batch.runner.cluster_map`, discovery
with one process per task; the lines of each run print in the serial order once all are back.
``--gate-folds K [--gate-search levenberg-marquardt] [--gate-converge]``: the stiffness gate's session-11 option
(held out over K folds) and its search; ``--screen-uncorrected``: session 13's option (the held-out test before the
gate at alpha, ``stiffness_gate.SCREEN_CORRECTED = False``); ``--surface-folds K``: ``forward_selection.SURFACE_FOLDS``
(each model's surface law shot on K held-out folds once the surface is in the model; 2 is the default since session
15, 0 the leave-one-out of sessions 1-14); ``--log-ratio-cap X``: ``forward_selection.LOG_RATIO_CAP`` (the t-tests see
every per-stance log gap ratio clipped to +-X, natural log units; log 10 = 2.3026 is the default since session 16,
``inf`` the uncapped test of sessions 1-15); ``--eq7-fit``: ``identify.EQ7_FIT`` (every joint law identified subject to
seed 000's Eq. 7, K >= 0 and B >= 0 on the training samples; session 16's option, off by default);
``--touchdown-velocity-fit W``: ``forward_selection.TOUCHDOWN_VELOCITY_FIT_S`` (each model's touchdown velocities
corrected on the stance's first W s of joint angles; session 17's option, off by default); ``--gate-per-signal`` /
``--no-gate-per-signal``: ``stiffness_gate.GATE_PER_SIGNAL`` (session 17; on by default since its end); ``--energy-pairs``:
``forward_selection.ENERGY_PAIRS`` (session 19's option: a loss and the push-off replacing it tried together when no
single candidate passes); ``--accept-step``: ``forward_selection.VELOCITY_FIT_ACCEPT`` (session 20's sub-option of
the velocity fit: the step checked; its ``--velocity-fit-shared``, not adopted, was removed in session 23 and runs at
commit a93ac09); ``--simulate-from D``: ``forward_selection.SIMULATE_FROM_S`` (session 22's option: every held-out
stance simulated from the measured state D s after its touchdown, compared from there); ``--two-segment``:
``forward_selection.TWO_SEGMENT`` with it (session 23's sub-option: the run from the touchdown compared before the
start sample, the late run from it), ``--two-segment-flight``: ``forward_selection.TWO_SEGMENT_FLIGHT`` with that
(a run from the touchdown that takes off before the start sample compared as in flight up to it); ``--work-scale X``:
``forward_selection.WORK_SCALE`` (the net-joint-work term's scale, session 26; its ``--gate-order`` and
``--push-off-signed``, measured and removed, run at commit 9b1492a); ``--two-sided-duration``:
``forward_selection.TWO_SIDED_DURATION`` (session 14's option, re-measured in session 28: the duration term also
charges a stance simulated past the measured take-off); ``--angle-hold``: ``forward_selection.ANGLE_HOLD`` (session
29's option: the angle terms' stiffness held past the stance's measured angles); set in this
process, so only without ``--scheduler``. Run with
``PYTHONPATH=<this checkout>`` from a worktree: a script's ``sys.path[0]`` is ``bench/``, so otherwise the installed
package is imported and options set on it are not the checkout's (session 16 measured the default that way).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

from scipy.stats import binomtest
from two_segment_flags import add_two_segment_arguments, check_two_segment

from hop_impedance.discovery.model import members
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import load_recording
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import EffectSizes, simulate_stance_set_recording
from hop_impedance.validation.strict_generator import StrictConfig, strict_recording

BASE = dict(angle_dependent_stiffness=False, damping=False, push_off=False)
#: ``--json-dir``: where each run's discover document is written (empty: nowhere).
JSON_DIR: list[str] = []
FREQS = (1.53, 1.87, 2.2)
#: Frequencies where the stance-set generator cannot make the case (passive stances do not take off):
#: damping at 1.53 Hz (the soft Table-2 stiffness with b0 = 2 never unloads), activation at 1.53 Hz
#: (a_min 0.3 of the 1.53 Hz stiffness collapses at landing).
CASE_FREQS = {"joint_damping": (1.87, 2.2), "time_dependent_activation": (1.87, 2.2)}
#: Sensor effect sizes of the study.
SENSOR_SIZES = {"marker_time_offset_s": 0.015, "force_offset_n": 20.0}
#: case -> (law switches, surfaces, sensors, expected effects)
CASES = {
    "null": ({}, ("rigid",), {}, set()),
    "angle_dependent_stiffness": ({"angle_dependent_stiffness": True}, ("rigid",), {}, {"angle_dependent_stiffness"}),
    "rate_dependent_stiffness": ({"rate_dependent_stiffness": True}, ("rigid",), {}, {"rate_dependent_stiffness"}),
    "joint_damping": ({"damping": True}, ("rigid",), {}, {"joint_damping"}),
    "surface_compliance": ({}, ("hard",), {}, {"surface_compliance"}),
    "time_dependent_activation": ({"time_activation": True}, ("hard", "soft"), {},
                                  {"time_dependent_activation", "surface_compliance"}),
    "stream_latency": ({}, ("rigid",), {"marker_time_offset_s": SENSOR_SIZES["marker_time_offset_s"]},
                       {"stream_latency"}),
    "force_plate_offset": ({}, ("rigid",), {"force_offset_n": SENSOR_SIZES["force_offset_n"]}, {"force_plate_offset"}),
    "active_push_off": ({"push_off": True}, ("rigid",), {}, {"active_push_off"}),
    "two:angle+offset": ({"angle_dependent_stiffness": True}, ("rigid",), {"force_offset_n": SENSOR_SIZES["force_offset_n"]},
                         {"angle_dependent_stiffness", "force_plate_offset"}),
    "two:push+soft": ({"push_off": True}, ("soft",), {}, {"active_push_off", "surface_compliance"}),
}

#: Second generator (hop_impedance.validation.strict_generator): strict family, lossless, time-symmetric.
STRICT_CASES = {
    "null": StrictConfig(),
    # k1 = 2.5 k_td per rad referenced to touchdown (seed 000's Eq. 10; the generator's default since session 18): K at
    # touchdown is 0.33 / 0.49 / 0.77 of mid-stance's at the ankle / knee / hip (medians, seeds 0-3; seed 000's Table 2
    # at 2.2 Hz: 0.35 / 0.49 / 0.64). Sessions 15-17: k1 = 0.8 k0 per rad about mid-stance (0.35 / 0.66 / 0.91), whose
    # touchdown stiffness varied from stance to stance with the stance's flexion, unlike seed 000's law: 0/3 named
    "angle_dependent_stiffness": StrictConfig(angle_k1=2.5),
    "force_plate_offset": StrictConfig(force_offset_n=30.0),
    "stream_latency": StrictConfig(marker_latency_s=0.015),
}


def generate(name: str, seed: int, hops: int, sizes: EffectSizes = EffectSizes(), freqs: tuple | None = None):
    """(recording, frequency) of one case and seed; raises ValueError when generation fails."""
    law, surfaces, sensors, _ = CASES[name]
    freqs = freqs or CASE_FREQS.get(name, FREQS)
    freq = freqs[seed % len(freqs)]
    rec, _ = simulate_stance_set_recording(freq, surfaces, hops, seed=seed, effects=Effects(**{**BASE, **law}),
                                           sensors=SensorConfig(**sensors), rtol=1e-6, sizes=sizes,
                                           redraws=10)
    return rec, freq


def classify(expected: set, doc: dict) -> dict:
    """Counting flags of one run (see module docstring)."""
    found = set(doc["effects_found"])
    ambiguous = {one for st in doc["steps"] for a in st["ambiguous_with"] for one in members(a["effect"])}
    return {"exact": found == expected, "named": expected <= found,
            "named_or_ambiguous": expected <= (found | ambiguous), "extra": bool(found - expected),
            "found": sorted(found), "ambiguous": sorted(ambiguous)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--null-seeds", type=int, default=20)
    ap.add_argument("--hops", type=int, default=8)
    ap.add_argument("--cases", default=",".join(CASES), help="simulator cases ('' for none)")
    ap.add_argument("--sizes", default="", help="EffectSizes overrides, e.g. rate_fraction=0.25,push_fraction=0.2")
    ap.add_argument("--strict-cases", default="", help="second-generator cases, e.g. " + ",".join(STRICT_CASES))
    ap.add_argument("--strict-seeds", type=int, default=5)
    ap.add_argument("--strict-null-seeds", type=int, default=10)
    ap.add_argument("--strict-null-seed-list", default="",
                    help="second-generator null seeds to run, e.g. 1,3,7 (instead of 0..--strict-null-seeds-1)")
    ap.add_argument("--foreign", default="", help="also score the truth-labelled recordings in this folder "
                                                  "(e.g. ../shared/foreign)")
    ap.add_argument("--freqs", default="", help="hop frequencies to cycle over (Hz), e.g. 2.2 (default: per case)")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="one Dask task per case and seed (simulator and second-generator cases): 'local' for the "
                         "embedded cluster of hop-impedance batch, or tcp://HOST:8786; discovery uses one process "
                         "per task")
    ap.add_argument("--gate-folds", type=int, default=None, help="stiffness_gate.FOLDS (held-out gate; no --scheduler)")
    ap.add_argument("--gate-search", choices=("nelder-mead", "levenberg-marquardt"), default=None)
    ap.add_argument("--gate-converge", action="store_true", help="stiffness_gate.TO_CONVERGENCE")
    ap.add_argument("--json-dir", default="", help="also write each run's discover document to DIR/<case>_<seed>.json")
    ap.add_argument("--surface-folds", type=int, default=None,
                    help="forward_selection.SURFACE_FOLDS (each model's surface shot on K folds; default 2, 0: sessions 1-14)")
    ap.add_argument("--screen-uncorrected", action="store_true",
                    help="stiffness_gate.SCREEN_CORRECTED = False (session 13's option: the held-out test at alpha)")
    ap.add_argument("--log-ratio-cap", type=float, default=None, metavar="X",
                    help="forward_selection.LOG_RATIO_CAP: the t-tests see each per-stance log gap ratio clipped to +-X "
                         "(natural log; default log 10 = 2.3026 since session 16; inf: no cap)")
    ap.add_argument("--eq7-fit", action="store_true",
                    help="identify.EQ7_FIT = True: the joint law identified subject to Eq. 7 (K >= 0, B >= 0)")
    ap.add_argument("--touchdown-velocity-fit", type=float, default=None, metavar="W",
                    help="forward_selection.TOUCHDOWN_VELOCITY_FIT_S = W: each model's touchdown velocities corrected "
                         "on the stance's first W s (session 17's option)")
    ap.add_argument("--simulate-from", type=float, default=None, metavar="D",
                    help="forward_selection.SIMULATE_FROM_S = D: held-out stances simulated from the measured state "
                         "D s after touchdown (session 22's option)")
    add_two_segment_arguments(ap, "--simulate-from")
    ap.add_argument("--angle-terms", default=None, metavar="TERMS",
                    help="model.ANGLE_TERMS, e.g. k1 (seed 000's Eq. 10, the default since session 30) or k1,k2 (Eq. 3)")
    ap.add_argument("--energy-pairs", action="store_true",
                    help="forward_selection.ENERGY_PAIRS = True (session 19's option): when no single candidate passes, "
                         "a loss and the push-off that replaces it tried together")
    ap.add_argument("--accept-step", action="store_true",
                    help="forward_selection.VELOCITY_FIT_ACCEPT = True (session 20): the velocity step checked")
    ap.add_argument("--work-scale", type=float, default=None, metavar="X",
                    help="forward_selection.WORK_SCALE = X: the net-joint-work term's scale, a share of the work the "
                         "joints absorb per measured stance (default 1; session 26)")
    ap.add_argument("--two-sided-duration", action="store_true",
                    help="forward_selection.TWO_SIDED_DURATION = True (session 14's option): the duration term is the "
                         "simulated take-off minus the measured one, also for a stance simulated too long")
    ap.add_argument("--angle-hold", action="store_true",
                    help="forward_selection.ANGLE_HOLD = True (session 29's option): a held-out stance's angle terms "
                         "hold their stiffness past the joint angles measured in it")
    ap.add_argument("--gate-per-signal", action="store_true",
                    help="stiffness_gate.GATE_PER_SIGNAL = True (session 17's option): the gate also passes a candidate "
                         "significantly better on one sampled signal (Bonferroni over the 7) and worse on none; "
                         "the default since the end of session 17")
    ap.add_argument("--no-gate-per-signal", action="store_true",
                    help="stiffness_gate.GATE_PER_SIGNAL = False: the gate of sessions 8-16 (the total gap only)")
    ap.add_argument("--per-term", action="store_true",
                    help="forward_selection.PER_TERM = True (session 37's option): the screen also passes a candidate "
                         "significantly better on one of the gap's ten terms (Bonferroni over them) and worse on none")
    ap.add_argument("--gate-eq7-damping", action="store_true",
                    help="stiffness_gate.GATE_EQ7_DAMPING = True (session 38's option): a damping model's fold laws in "
                         "the gate identified subject to Eq. 7 (K >= 0, B >= 0 on the training samples)")
    args = ap.parse_args()
    check_two_segment(ap, args, "--simulate-from", args.simulate_from is not None)
    _configure_gate(ap, args)
    JSON_DIR[:] = [args.json_dir] if args.json_dir else []
    sizes = EffectSizes(**{k: float(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)})
    freqs = tuple(float(f) for f in args.freqs.split(",") if f) or None
    calls = [("simulator", name, seed, args.hops, sizes, freqs)
             for name in filter(None, args.cases.split(","))
             for seed in range(args.null_seeds if name == "null" else args.seeds)]
    null_seeds = [int(s) for s in args.strict_null_seed_list.split(",") if s] or range(args.strict_null_seeds)
    calls += [("second generator", name, seed, args.hops, sizes, freqs)
              for name in filter(None, args.strict_cases.split(","))
              for seed in (null_seeds if name == "null" else range(args.strict_seeds))]
    tallies = {("simulator", n): new_tally() for n in filter(None, args.cases.split(","))}
    tallies.update({("second generator", n): new_tally() for n in filter(None, args.strict_cases.split(","))})
    if args.scheduler:
        from hop_impedance.batch.runner import cluster_map

        for call, (tally, text) in zip(calls, cluster_map(_case_run_captured, calls, mode=args.scheduler)):
            print(text, end="", flush=True)
            _add(tallies[call[:2]], tally)
    else:
        for call in calls:
            _add(tallies[call[:2]], case_run(*call))
    rows = list(tallies.items())
    if args.foreign:
        rows += foreign_rows(args.foreign)
    print_table(rows)


def _configure_gate(ap: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """The stiffness gate's options, set in this process (a Dask worker would not see them)."""
    from hop_impedance.discovery import forward_selection, identify, model, stiffness_gate

    # (flag, module, constant, value or None when not given): each set in this process, so not with --scheduler
    for flag, module, name, value in (
            ("--surface-folds", forward_selection, "SURFACE_FOLDS", args.surface_folds),
            ("--log-ratio-cap", forward_selection, "LOG_RATIO_CAP", args.log_ratio_cap),
            ("--eq7-fit", identify, "EQ7_FIT", True if args.eq7_fit else None),
            ("--touchdown-velocity-fit", forward_selection, "TOUCHDOWN_VELOCITY_FIT_S", args.touchdown_velocity_fit),
            ("--simulate-from", forward_selection, "SIMULATE_FROM_S", args.simulate_from),
            ("--two-segment", forward_selection, "TWO_SEGMENT", True if args.two_segment else None),
            ("--two-segment-flight", forward_selection, "TWO_SEGMENT_FLIGHT", True if args.two_segment_flight else None),
            ("--angle-terms", model, "ANGLE_TERMS", tuple(args.angle_terms.split(",")) if args.angle_terms else None),
            ("--energy-pairs", forward_selection, "ENERGY_PAIRS", True if args.energy_pairs else None),
            ("--accept-step", forward_selection, "VELOCITY_FIT_ACCEPT", True if args.accept_step else None),
            ("--work-scale", forward_selection, "WORK_SCALE", args.work_scale),
            ("--two-sided-duration", forward_selection, "TWO_SIDED_DURATION", True if args.two_sided_duration else None),
            ("--angle-hold", forward_selection, "ANGLE_HOLD", True if args.angle_hold else None),
            ("--gate-per-signal", stiffness_gate, "GATE_PER_SIGNAL", True if args.gate_per_signal else None),
            ("--no-gate-per-signal", stiffness_gate, "GATE_PER_SIGNAL", False if args.no_gate_per_signal else None),
            ("--per-term", forward_selection, "PER_TERM", True if args.per_term else None),
            ("--gate-eq7-damping", stiffness_gate, "GATE_EQ7_DAMPING", True if args.gate_eq7_damping else None)):
        if value is None:
            continue
        if args.scheduler:
            ap.error(f"{flag} is set in this process: run without --scheduler")
        setattr(module, name, value)
    if args.gate_folds is None and args.gate_search is None and not args.gate_converge and not args.screen_uncorrected:
        return
    if args.scheduler:
        ap.error("--gate-* options set the gate in this process: run without --scheduler")
    if args.gate_folds is not None:
        stiffness_gate.FOLDS = args.gate_folds
    if args.gate_search:
        stiffness_gate.SEARCH = args.gate_search
    if args.gate_converge:
        for name, value in stiffness_gate.TO_CONVERGENCE.items():
            setattr(stiffness_gate, name, value)
    if args.screen_uncorrected:
        stiffness_gate.SCREEN_CORRECTED = False


def case_run(source: str, name: str, seed: int, hops: int, sizes: EffectSizes, freqs,
             workers: int | None = None) -> dict:
    """Generate one recording of a case (simulator or second generator), discover, return its tally."""
    tally = new_tally()
    try:
        if source == "simulator":
            expected = CASES[name][3]
            rec, freq = generate(name, seed, hops, sizes, freqs)
            label = f"{name:28s} seed {seed} f={freq}"
        else:
            expected = set(STRICT_CASES[name].effects)
            rec, _ = strict_recording(replace(STRICT_CASES[name], seed=seed, hops=hops))
            label = f"strict {name:21s} seed {seed}"
    except ValueError as exc:
        tally["gen_fail"] += 1
        print(f"{'' if source == 'simulator' else 'strict '}{name} seed {seed}: generation failed: {exc}", flush=True)
        return tally
    run_one(rec, label, expected, tally, workers)
    return tally


def _case_run_captured(*call) -> tuple[dict, str]:
    """:func:`case_run` in a Dask task: one process (the cluster runs one task per core), printout returned."""
    import contextlib
    import io

    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        tally = case_run(*call, workers=1)
    return tally, text.getvalue()


def _add(total: dict, tally: dict) -> None:
    for k, v in tally.items():
        total[k] += v


def new_tally() -> dict:
    return {"exact": 0, "named": 0, "named_or_ambiguous": 0, "extra": 0, "runs": 0, "gen_fail": 0,
            "steps": 0, "steps_not_shrinking": 0}


def run_one(rec, label: str, expected: set, tally: dict, workers: int | None = None) -> None:
    """Discover on one recording and add its flags to ``tally`` (a refusal counts as a miss)."""
    t0 = time.perf_counter()
    try:
        doc = discover(rec, workers=workers)
    except ValueError as exc:
        tally["runs"] += 1
        tally["extra"] += not expected  # a null that cannot be judged is not a correct "none"
        print(f"{label}: discovery refused: {exc} (counted as a miss)", flush=True)
        return
    if JSON_DIR:
        from hop_impedance.discovery.report import to_json_ready

        out = Path(JSON_DIR[0]) / ("_".join(label.split()).replace("=", "") + ".json")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(to_json_ready(doc)))
    flags = classify(expected, doc)
    tally["runs"] += 1
    for k in ("exact", "named", "named_or_ambiguous", "extra"):
        tally[k] += flags[k]
    for st in doc["steps"]:
        tally["steps"] += 1
        tally["steps_not_shrinking"] += not st["gap_after"]["total"] < st["gap_before"]["total"]
    print(f"{label} found={flags['found']} ambiguous={flags['ambiguous']} "
          f"{'EXACT' if flags['exact'] else 'MISS' if not flags['named'] else 'NAMED+EXTRA'} "
          f"{time.perf_counter() - t0:.1f}s", flush=True)


def foreign_rows(folder: str) -> list:
    """Tallies per hidden-effect set of the truth-labelled recordings (``*.mcap`` + ``*.truth.json``) in ``folder``."""
    tallies: dict = {}
    for path in sorted(Path(folder).glob("*.mcap")):
        truth = json.loads(path.with_suffix(".truth.json").read_text())
        expected = {e for e in truth["effects"] if e != "none"}
        key = "null" if not expected else "+".join(sorted(expected))
        tally = tallies.setdefault(key, new_tally())
        try:
            rec = load_recording(path)
        except ValueError as exc:
            tally["runs"] += 1
            print(f"{path.name}: cannot load: {exc} (counted as a miss)", flush=True)
            continue
        run_one(rec, f"foreign {path.stem}", expected, tally)
    return [(("foreign", k), t) for k, t in sorted(tallies.items())]


def _ci(k: int, n: int) -> str:
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
    return f"[{100 * ci.low:.0f}, {100 * ci.high:.0f}] %"


def print_table(rows: list) -> None:
    """Markdown table (counts, share, two-sided 95 % Clopper-Pearson interval) and the null bounds."""
    print("\n| source | case | runs | exact (95 % CI) | all hidden named | named or reported ambiguous "
          "| wrong extra name (95 % CI) | steps whose gap did not shrink | generation failures |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (source, name), t in rows:
        n = max(t["runs"], 1)
        pct = {k: f"{t[k]}/{t['runs']} ({100 * t[k] / n:.0f} %)" for k in ("exact", "named", "named_or_ambiguous", "extra")}
        print(f"| {source} | {name} | {t['runs']} | {pct['exact']} {_ci(t['exact'], n)} | {pct['named']} "
              f"| {pct['named_or_ambiguous']} | {pct['extra']} {_ci(t['extra'], n)} "
              f"| {t['steps_not_shrinking']}/{t['steps']} | {t['gen_fail']} |")
    for (source, name), t in rows:
        if name == "null" and t["runs"]:
            ci = binomtest(t["extra"], t["runs"]).proportion_ci(confidence_level=0.95, method="exact")
            upper = binomtest(t["extra"], t["runs"], alternative="less").proportion_ci(0.95, "exact").high
            print(f"\n{source} null: {t['extra']}/{t['runs']} false discoveries, 95 % Clopper-Pearson interval "
                  f"[{100 * ci.low:.1f} %, {100 * ci.high:.1f} %] (two-sided), one-sided 95 % upper bound "
                  f"{100 * upper:.1f} %")


if __name__ == "__main__":
    main()
