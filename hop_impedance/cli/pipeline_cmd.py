"""``hop-impedance pipeline REC.mcap``: the ROS 2 node graph on a replayed recording.

Starts replay, stance_detector, inverse_dynamics, impedance_estimator and
recorder in one process (EventsExecutor) or, with ``--processes``, as
separate processes; prints the per-stance table and losses; writes
``OUT/pipeline.mcap`` (inputs and outputs). See docs/pipeline.md.
"""

from __future__ import annotations

import argparse

from hop_impedance.cli.conventions import DeprecatedAlias, OptionDefault, add_rrd_argument, positional_or_alias

CONFIG = "hop_impedance.nodes.runner:PipelineConfig"


def add_pipeline_arguments(p: argparse.ArgumentParser, recording_help: str = "MCAP recording to replay") -> None:
    """Arguments shared by ``pipeline`` and ``demo``: the recording (positional) and the run's options.

    ``--recording`` is the former flag for the recording, kept as a deprecated alias
    (read it with :func:`recording_from_args`).
    """
    p.add_argument("recording", nargs="?", help=recording_help)
    p.add_argument("--recording", dest="recording_flag", action=DeprecatedAlias, new="a positional REC.mcap")
    p.add_argument("--out", default=OptionDefault(CONFIG, "out_dir"), help="folder for pipeline.mcap and logs [%(default)s]")
    p.add_argument("--rate", type=float, default=OptionDefault(CONFIG, "rate"),
                   help="replay speed factor; 0 = as fast as the nodes take it without loss [%(default)s]")
    p.add_argument("--processes", action="store_true", help="one OS process per node instead of one process")
    p.add_argument("--low-latency", action="store_true", help="analyse each stance at take-off + 50 ms (docs/pipeline.md)")
    p.add_argument("--no-frames", action="store_true", help="do not publish per-frame /joint_kinetics")
    p.add_argument("--params-file", help="ROS 2 YAML parameter file (e.g. config/pipeline.yaml)")
    p.add_argument("--timeout", type=float, default=OptionDefault(CONFIG, "timeout_s"),
                   help="give up after this many seconds [%(default)s]")
    p.add_argument("--json", metavar="OUT", help="also write every stance's row, the losses and the exit status as JSON "
                                                "('-' for stdout; docs/pipeline.md)")
    p.add_argument("--tolerate-loss", action="store_true",
                   help="exit 0 even when input messages were lost on the way (they are still reported)")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "pipeline",
        help="run the ROS 2 node graph on a replayed recording",
        description="Replay a recording through replay -> stance_detector, inverse_dynamics -> impedance_estimator "
        "-> recorder and print one line per stance. DDS stays on this machine (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST).",
    )
    add_pipeline_arguments(p)
    p.add_argument("--loop", action="store_true", help="replay in a loop (until --timeout)")
    p.add_argument("--rerun", action="store_true", help="add the Rerun bridge node (spawns a viewer unless --rrd/--connect)")
    add_rrd_argument(p, "the Rerun bridge writes this .rrd (implies --rerun; works headless)", old=("--rerun-save",))
    p.add_argument("--connect", metavar="URL",
                   help="the Rerun bridge streams to this viewer, e.g. rerun+http://127.0.0.1:9876/proxy (as view --connect)")
    p.add_argument("--rerun-url", dest="connect", action=DeprecatedAlias, new="--connect", metavar="URL")
    p.set_defaults(func=run)


def recording_from_args(args: argparse.Namespace) -> str:
    """The recording to replay: the positional, or the deprecated ``--recording``; one of them is needed."""
    recording = positional_or_alias(args, "recording", "recording_flag", "--recording")
    if recording is None:
        raise ValueError("no recording given: hop-impedance pipeline REC.mcap")
    return recording


def config_from_args(args: argparse.Namespace):
    from hop_impedance.nodes.runner import PipelineConfig

    return PipelineConfig(
        recording=recording_from_args(args), out_dir=args.out, rate=args.rate, processes=args.processes,
        low_latency=args.low_latency, publish_frames=not args.no_frames, rerun=getattr(args, "rerun", False),
        rerun_save=getattr(args, "rrd", None), rerun_url=getattr(args, "connect", None),
        timeout_s=args.timeout, params_file=args.params_file, loop=getattr(args, "loop", False),
    )


def print_report(report, recording: str, tolerate_loss: bool = False) -> int:
    """Print the table, losses and problems; return the exit code.

    0 only when the run finished, no input check failed and no message was lost
    (or ``tolerate_loss``); 1 otherwise; 130 after Ctrl-C. Problems are one line
    each on stderr, never a traceback.
    """
    from hop_impedance.io.mcap_io import summarize
    from hop_impedance.nodes.runner import loss_lines, stance_table

    for warning in report.input_warnings:
        _problem(f"warning: {warning}")
    counts = {i.topic: i.count for i in summarize(recording)}
    _warn_missing_topics(counts)
    for line in stance_table(report):
        print(line)
    for line in loss_lines(report, counts):
        print(line)
    _print_estimator_figures(report)
    _print_dropped_inputs(report)
    return _exit_code(report, counts, tolerate_loss)


def _problem(text: str) -> None:
    """One problem line on stderr."""
    import sys

    print(f"hop-impedance pipeline: {text}", file=sys.stderr)


def _warn_missing_topics(counts: dict[str, int]) -> None:
    """A warning, with its consequence, per contract topic the file lacks (``counts``: messages per topic)."""
    from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC

    missing = {FORCE_TOPIC: "no stances can be detected", MARKER_TOPIC: "stances have no joint data",
               SUBJECT_TOPIC: "mass and height come from parameters or the run stops"}
    for topic, consequence in missing.items():
        if not counts.get(topic):
            _problem(f"warning: the recording has no {topic} messages: {consequence}")


#: The node whose /diagnostics carry the model structures and the fit and latency figures.
_ESTIMATOR = "/impedance_estimator"


def _ms(report, key: str) -> str:
    """A millisecond diagnostic of the estimator (a string on /diagnostics) to one decimal, '?' when missing."""
    value = report.diag(_ESTIMATOR, key, "?")
    try:
        return f"{float(value):.1f}"
    except ValueError:
        return value


def _print_estimator_figures(report) -> None:
    """Model structure per joint, fit and take-off-to-profile times, the output files."""
    for joint in ("ankle", "knee", "hip"):  # one model structure per joint (impedance_estimator, recording_fits)
        print(f"model {joint}: {report.diag(_ESTIMATOR, f'model_{joint}', '?')}")
    print(f"fit p50/p99: {_ms(report, 'fit_p50_ms')}/{_ms(report, 'fit_p99_ms')} ms; "
          f"take-off to profile p50/p99: {_ms(report, 'takeoff_to_profile_p50_ms')}/"
          f"{_ms(report, 'takeoff_to_profile_p99_ms')} ms")
    print(f"output: {report.output_mcap}  ({report.wall_s:.1f} s wall)")
    if getattr(report, "rrd", None):
        print(f"Rerun recording: {report.rrd}  (open it with: .venv/bin/rerun {report.rrd})")


def _print_dropped_inputs(report) -> None:
    """Warnings for input messages the nodes dropped: later than the reorder window, or a repeated stamp."""
    for node in ("/stance_detector", "/inverse_dynamics"):
        late = sum(int(report.diag(node, k, "0") or 0) for k in ("force_late_dropped", "markers_late_dropped"))
        if late:
            _problem(f"warning: {node}: {late} input messages arrived later than the reorder window and were not used")
    dups = sum(int(report.diag("/inverse_dynamics", k, "0") or 0)
               for k in ("force_duplicates_dropped", "markers_duplicates_dropped"))
    if dups:
        _problem(f"warning: /inverse_dynamics: {dups} input messages with a repeated header.stamp dropped")


def _exit_code(report, counts: dict[str, int], tolerate_loss: bool) -> int:
    """Print the input-check lines and the run's end state; the exit code :func:`print_report` documents."""
    from hop_impedance.nodes.runner import STOP_GRACE_S, messages_lost

    code = 0
    for note in input_notes(report):
        _problem(note)
        code = 1 if note.startswith("error") else code
    if report.interrupted:
        _problem(f"interrupted; {len(report.summaries)} stances finished (table above)")
        return 130
    if report.died:
        _problem(f"error: {report.died}; {len(report.summaries)} stances finished (table above)")
        return 1
    if not report.finished:
        _problem("error: did not finish in time (see the losses above and the logs)")
        return 1
    for name in report.killed:
        _problem(f"warning: node {name} did not exit within {STOP_GRACE_S:.0f} s of SIGINT and was killed")
    if report.recorder_shortfall:
        _problem("error: the output file lacks messages the recorder received: " + "; ".join(report.recorder_shortfall))
        return 1
    lost = messages_lost(report, counts)
    if lost and not tolerate_loss:
        _problem(f"error: {lost} input messages lost on the way (lines above); pass --tolerate-loss to accept")
        return 1
    return code


def input_notes(report) -> list[str]:
    """The input check state the nodes published on /diagnostics, as ``error: ...`` / ``note: ...`` lines."""
    out = []
    for node, values in sorted(report.diagnostics.items()):
        failure = values.get("input_check", "")
        if failure and failure != "ok":
            out.append(f"error: {node}: {failure}")
        note = values.get("input_note", "")
        if note:
            out.append(f"note: {node}: {note}")
    return out


def pipeline_document(report, recording: str, exit_status: int) -> dict:
    """The run as a JSON-ready dict: one row per stance the nodes reported (accepted or rejected, with the
    reason), the messages each consumer received against the file, the input-check lines and the exit status."""
    from hop_impedance.io.mcap_io import summarize
    from hop_impedance.nodes.common import stamp_ns
    from hop_impedance.nodes.runner import _consumer_counts

    def num(x: float) -> float | None:
        return float(x) if x == x else None

    rows = []
    for s in sorted(report.summaries, key=lambda s: stamp_ns(s.touchdown_stamp)):
        rows.append({
            "stance_index": int(s.stance_index), "touchdown_stamp_ns": stamp_ns(s.touchdown_stamp),
            "takeoff_stamp_ns": stamp_ns(s.takeoff_stamp), "contact_time_s": num(s.contact_time_s),
            "complete": bool(s.complete), "rejection_reason": s.rejection_reason or None,
            "accepted": [bool(a) for a in s.accepted], "k0": [num(x) for x in s.k0], "k1": [num(x) for x in s.k1],
            "r_squared": [num(x) for x in s.r_squared],
            "force_samples_lost_before": int(s.force_samples_lost_before),
            "force_samples_lost_in_stance": int(s.force_samples_lost_in_stance),
        })
    counts = {i.topic: i.count for i in summarize(recording)}
    received = [{"node": node, "topic": topic, "received": got, "in_file": sent}
                for node, topic, got, sent in _consumer_counts(report, counts)]
    return {"recording": recording, "exit_status": exit_status, "finished": bool(report.finished),
            "died": report.died or None, "stances": rows, "received": received, "input_checks": input_notes(report),
            "output_mcap": str(report.output_mcap)}


def run(args: argparse.Namespace) -> int:
    import json

    from hop_impedance.cli.json_output import json_output
    from hop_impedance.nodes.runner import run_pipeline

    config = config_from_args(args)
    report = run_pipeline(config)
    if not args.json:
        return print_report(report, config.recording, args.tolerate_loss)
    with json_output(args.json) as write_json:
        code = print_report(report, config.recording, args.tolerate_loss)
        write_json(json.dumps(pipeline_document(report, config.recording, code), indent=1, allow_nan=False))
    return code
