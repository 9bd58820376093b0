"""The pipeline runner: replay -> stance_detector, inverse_dynamics -> impedance_estimator -> recorder.

``run_pipeline`` starts the node graph either in this process (one
EventsExecutor spinning every node) or as separate processes
(``python -m hop_impedance.nodes.<name> --ros-args -p ...`` with
:func:`hop_impedance.child_env.child_env`: the environment without the ROS
wheels' bootstrap marker, so each child re-derives ``LD_LIBRARY_PATH``, and
with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``),
plus a :class:`ResultCollector` in this process that gathers what the
pipeline publishes. It returns when the stream has been played and every
stance result has reached the collector and the recorder, or at the time
limit; child processes are always stopped (SIGINT, then SIGKILL) on return,
error or Ctrl-C.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from rclpy.node import Node

from hop_impedance.child_env import child_env
from hop_impedance.nodes.common import (
    CONTROLLER_TOPIC,
    DIAGNOSTICS_TOPIC,
    PROFILE_TOPIC,
    PROGRESS_TOPIC,
    STANCE_KINETICS_TOPIC,
    SUMMARY_TOPIC,
    freeze_startup_objects,
    stamp_ns,
    warm_up_logging,
)
from hop_impedance.nodes.qos import latched_qos, result_qos
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC

if TYPE_CHECKING:
    from hop_impedance.nodes.replay import ReplayNode

CONSUMERS = ["/stance_detector", "/inverse_dynamics"]
NODE_MODULES = ("stance_detector", "inverse_dynamics", "impedance_estimator", "recorder", "replay")


@dataclass
class PipelineConfig:
    """What :func:`run_pipeline` runs.

    Attributes
    ----------
    recording : str
        MCAP to replay.
    out_dir : str
        Folder of the output MCAP (``pipeline.mcap``: inputs + outputs).
    rate : float
        Replay speed factor; 0 = as fast as the consumers take it (progress flow control).
    processes : bool
        Separate OS processes instead of one process.
    low_latency : bool
        inverse_dynamics analyses at take-off + post_pad_s (stages.py) instead of batch-identical windows.
    publish_frames : bool
        Per-frame JointKinetics.
    rerun : bool
        Add the Rerun bridge node (``nodes/rerun_bridge.py``).
    rerun_save : str or None
        The bridge writes this .rrd file (implies ``rerun``); headless-safe.
    rerun_url : str or None
        The bridge streams to a running viewer at this address (implies ``rerun``).
        With ``rerun`` and neither given, the bridge spawns a viewer on loopback.
    timeout_s : float
        Give up (and report) after this long.
    params_file : str or None
        ROS 2 YAML parameter file for the nodes (``config/pipeline.yaml``).
    overrides : dict
        ``{node: {parameter: value}}`` on top of everything else (benchmarks, tests).
    ready_to_play : callable or None
        The replay starts only once this returns True (polled while the nodes spin, bounded by
        ``timeout_s``), e.g. a benchmark's own controller listener has matched the feed's
        publisher (``subscription.get_publisher_count() > 0``): the feed keeps only its latest
        message (depth 1), so a listener matched after the first stances never sees them
        (measured: the one-process latency bench heard 8 of 10 stances, missing stances 0 and 1).
    """

    recording: str
    out_dir: str = "pipeline_out"
    rate: float = 0.0
    processes: bool = False
    low_latency: bool = False
    publish_frames: bool = True
    rerun: bool = False
    rerun_save: str | None = None
    rerun_url: str | None = None
    timeout_s: float = 120.0
    params_file: str | None = None
    loop: bool = False
    overrides: dict = field(default_factory=dict)
    ready_to_play: Callable[[], bool] | None = None

    @property
    def with_rerun(self) -> bool:
        """Whether the Rerun bridge runs."""
        return bool(self.rerun or self.rerun_save or self.rerun_url)

    @property
    def output_mcap(self) -> str:
        return str(Path(self.out_dir) / "pipeline.mcap")


@dataclass
class PipelineReport:
    """What came out: per-stance summaries and profiles, progress of each node, diagnostics, timing."""

    summaries: list = field(default_factory=list)
    profiles: list = field(default_factory=list)
    controller: object = None
    progress: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict)
    wall_s: float = 0.0
    finished: bool = False
    output_mcap: str = ""
    rrd: str = ""
    #: In-process runs: wall time from the replay's first message to its end-of-stream (s).
    replay_play_s: float = float("nan")
    #: ``--processes``: which node died and how (one line), empty when none did.
    died: str = ""
    #: Ctrl-C / SIGTERM ended the run before the stream was through.
    interrupted: bool = False
    #: Where reading the recording stopped (a truncated or damaged file), one line each.
    input_warnings: list = field(default_factory=list)
    #: ``--processes``: node processes that did not exit within :data:`STOP_GRACE_S` of SIGINT and were killed.
    killed: list = field(default_factory=list)
    #: Messages the recorder received but its file lacks (:func:`recorder_shortfall`), one line per topic.
    recorder_shortfall: list = field(default_factory=list)

    def received(self, node: str, topic: str) -> int:
        """Messages of ``topic`` the node ``node`` reported received (0 if unknown)."""
        p = self.progress.get(node)
        if p is None or topic not in p.topics:
            return 0
        return int(p.received[list(p.topics).index(topic)])

    def diag(self, node: str, key: str, default: str = "") -> str:
        return self.diagnostics.get(node, {}).get(key, default)


class NodeDied(Exception):
    """A node process exited with an error before the run was over (message: which, how, its log)."""


class ResultCollector(Node):
    """Collects summaries, profiles, the controller feed, progress and diagnostics of the pipeline."""

    def __init__(self, **kwargs) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from hop_impedance_msgs.msg import ControllerImpedance, ImpedanceProfile, Progress, StanceSummary

        super().__init__("result_collector", **kwargs)
        self.report = PipelineReport()
        r = self.report
        self.create_subscription(StanceSummary, SUMMARY_TOPIC, r.summaries.append, result_qos(1000))
        self.create_subscription(ImpedanceProfile, PROFILE_TOPIC, r.profiles.append, result_qos(1000))
        self.create_subscription(ControllerImpedance, CONTROLLER_TOPIC, lambda m: setattr(r, "controller", m), latched_qos())
        self.create_subscription(Progress, PROGRESS_TOPIC, lambda m: r.progress.__setitem__(m.node, m), result_qos(100))
        self.create_subscription(DiagnosticArray, DIAGNOSTICS_TOPIC, self._on_diag, 50)

    def _on_diag(self, msg) -> None:
        for status in msg.status:
            self.report.diagnostics[status.name] = {kv.key: kv.value for kv in status.values}

    def done(self) -> bool:
        """Stream ended, the detector and inverse dynamics flushed, every stance summarised and recorded."""
        p = self.report.progress
        idn, det, rec = p.get("/inverse_dynamics"), p.get("/stance_detector"), p.get("/recorder")
        if not (idn and det and rec and idn.finished and det.finished):
            return False
        n = idn.stances_out
        return len(self.report.summaries) >= n and self.report.received("/recorder", SUMMARY_TOPIC) >= n


def node_parameters(cfg: PipelineConfig) -> dict[str, dict]:
    """Parameters of each node for ``cfg`` (on top of ``cfg.params_file``; ``cfg.overrides`` last)."""
    params: dict[str, dict] = {
        "replay": {"recording": str(cfg.recording), "rate": float(cfg.rate), "loop": bool(cfg.loop),
                   "consumers": CONSUMERS, "wait_for_subscribers_s": 10.0},
        "stance_detector": {},
        "inverse_dynamics": {"low_latency": bool(cfg.low_latency), "publish_frames": bool(cfg.publish_frames)},
        # rate 0 (as fast as the nodes take it) is not real time: a stance may reach the estimator seconds of wall
        # clock after its take-off because of the backlog, so the feed's age rule (docs/pipeline.md) is off there
        "impedance_estimator": {} if cfg.rate > 0 else {"max_age_s": 0.0},
        "recorder": {"output": cfg.output_mcap, "copy_inputs_from": str(cfg.recording)},
        "rerun_bridge": {"save_path": str(cfg.rerun_save or ""), "viewer_url": str(cfg.rerun_url or ""),
                         "spawn": not (cfg.rerun_save or cfg.rerun_url)},
    }
    for node, values in cfg.overrides.items():
        params[node] = {**params[node], **values}
    return params


def run_pipeline(cfg: PipelineConfig) -> PipelineReport:
    """Run the node graph on ``cfg.recording``; see the module docstring."""
    from hop_impedance.io.mcap_io import read_summary

    if not Path(cfg.recording).exists():
        raise FileNotFoundError(f"{cfg.recording}: no such recording")
    infos, stopped = read_summary(cfg.recording)  # one-line RecordingError for an empty / non-MCAP file
    if not {i.topic for i in infos} & {FORCE_TOPIC, MARKER_TOPIC}:
        raise ValueError(f"{cfg.recording}: no {FORCE_TOPIC} or {MARKER_TOPIC} messages to replay"
                         + (f" ({stopped})" if stopped else ""))
    Path(cfg.out_dir).mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    report = _run_processes(cfg) if cfg.processes else _run_in_process(cfg)
    report.recorder_shortfall = recorder_shortfall(report)
    if stopped:
        report.input_warnings.append(f"{Path(cfg.recording).name}: {stopped}; replayed up to there")
    return report


def _spin_until_done(executor, collector: ResultCollector, cfg: PipelineConfig, t0: float, alive=lambda: None) -> None:
    """Spin until done or the time limit; a dead node (:class:`NodeDied`) or Ctrl-C end it early, in the report."""
    from rclpy.executors import ExternalShutdownException

    deadline = t0 + cfg.timeout_s
    try:
        while time.monotonic() < deadline and not collector.done():
            executor.spin_once(timeout_sec=0.05)
            alive()
        end = time.monotonic() + 0.3  # let the last diagnostics / controller message in
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    except NodeDied as exc:
        collector.report.died = str(exc)
    except (KeyboardInterrupt, ExternalShutdownException):
        collector.report.interrupted = True
    except Exception as exc:  # noqa: BLE001 - a node's callback failed in this process: report it, do not hang or trace
        where = _raising_node(exc)
        collector.report.died = f"node {where} failed: {type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
    collector.report.finished = collector.done() and not collector.report.died


def _raising_node(exc: BaseException) -> str:
    """The pipeline node whose code raised ``exc`` (from the traceback's frames), or 'of the pipeline'."""
    tb = exc.__traceback__
    name = "of the pipeline"
    while tb is not None:
        module = tb.tb_frame.f_globals.get("__name__", "")
        if module.startswith("hop_impedance.nodes.") and module.rsplit(".", 1)[1] in NODE_MODULES:
            name = module.rsplit(".", 1)[1]
        tb = tb.tb_next
    return name


def _in_process_nodes(cfg: PipelineConfig, context) -> list[Node]:
    """Every node but the replay (:func:`_replay_node`)."""
    from rclpy.parameter import Parameter

    from hop_impedance.nodes.impedance_estimator import ImpedanceEstimatorNode
    from hop_impedance.nodes.inverse_dynamics import InverseDynamicsNode
    from hop_impedance.nodes.recorder import RecorderNode
    from hop_impedance.nodes.stance_detector import StanceDetectorNode

    params = node_parameters(cfg)
    classes = {"stance_detector": StanceDetectorNode, "inverse_dynamics": InverseDynamicsNode,
               "impedance_estimator": ImpedanceEstimatorNode, "recorder": RecorderNode}
    nodes = []
    for name, cls in classes.items():
        nodes.append(cls(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params[name].items()]))
    if cfg.with_rerun:
        nodes.extend(_rerun_nodes(context, params["rerun_bridge"]))
    return nodes


def _replay_node(cfg: PipelineConfig, context) -> ReplayNode:
    """The replay (last: it starts playing once its subscribers are matched)."""
    from rclpy.parameter import Parameter

    from hop_impedance.nodes.replay import ReplayNode

    params = node_parameters(cfg)["replay"]
    return ReplayNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def _rerun_nodes(context, params: dict) -> list[Node]:
    """The Rerun bridge (imported lazily: rerun-sdk is only needed with ``--rerun``)."""
    from rclpy.parameter import Parameter

    from hop_impedance.nodes.rerun_bridge import RerunBridge

    return [RerunBridge(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])]


def _run_in_process(cfg: PipelineConfig) -> PipelineReport:
    import rclpy

    context = rclpy.Context()
    t0 = time.monotonic()
    rclpy.init(context=context, args=["--ros-args", "--params-file", cfg.params_file] if cfg.params_file else None)
    nodes: list[Node] = []
    try:
        collector = ResultCollector(context=context)
        nodes = [collector, *_in_process_nodes(cfg, context)]
        executor = _executor_for(context)
        for n in nodes:
            executor.add_node(n)
        _wait_until_ready(executor, cfg, t0 + cfg.timeout_s)
        replay = _replay_node(cfg, context)
        nodes.append(replay)
        executor.add_node(replay)
        warm_up_logging()  # else the first log call in a callback costs tens of ms (the first stance's latency)
        freeze_startup_objects()  # no full collection of the start-up objects on a stance's path
        _spin_until_done(executor, collector, cfg, t0)
        _wait_for_bridge(executor, nodes, len(collector.report.summaries))
        replay.stop()
        replay.finished.wait(5.0)  # the playback thread ends before its node is destroyed
        collector.report.replay_play_s = replay.play_s or float("nan")
        if replay.error:
            raise ValueError(replay.error)
        report = collector.report
    finally:
        for n in reversed(nodes):
            n.destroy_node()
        context.try_shutdown()  # already shut down after Ctrl-C
    report.wall_s = time.monotonic() - t0
    report.output_mcap = cfg.output_mcap
    report.rrd = str(cfg.rerun_save or "")
    return report


def _wait_for_bridge(executor, nodes: list[Node], n_stances: int, timeout_s: float = 5.0) -> None:
    """If a Rerun bridge runs in this process, spin until it has logged ``n_stances`` stances (bounded)."""
    bridges = [n for n in nodes if n.get_name() == "rerun_bridge"]
    if not bridges:
        return
    from hop_impedance.nodes.rerun_bridge import RerunBridge  # imported already: the bridge runs

    bridge = bridges[0]
    assert isinstance(bridge, RerunBridge)
    deadline = time.monotonic() + timeout_s
    while bridge.stances_logged < n_stances and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)


def _executor_for(context):
    from rclpy.experimental import EventsExecutor

    return EventsExecutor(context=context)


def child_command(name: str, params: dict, params_file: str | None = None) -> list[str]:
    """``python -m hop_impedance.nodes.<name> --ros-args [--params-file F] -p k:=v ...``."""
    cmd = [sys.executable, "-m", f"hop_impedance.nodes.{name}", "--ros-args"]
    if params_file:
        cmd += ["--params-file", params_file]
    for k, v in params.items():
        cmd += ["-p", f"{k}:={_yaml(v)}"]
    return cmd


def _yaml(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, list):
        return "[" + ",".join(f"'{x}'" for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str) and not v:
        return "''"  # rcl cannot parse an empty override (``-p name:=``)
    return str(v)


#: Nodes off the path from a take-off to /impedance/controller (inverse_dynamics detects its own stances; the
#: replay is the clock both ends are measured by): ``--processes`` starts them this much nicer, so on a machine
#: with few cores the analysis and the fit of a stance get a core first. They still get every idle cycle.
OFF_CONTROLLER_PATH = ("stance_detector", "recorder", "rerun_bridge")
OFF_PATH_NICE = 10


def start_children(names, cfg: PipelineConfig, log_dir: Path) -> dict[str, subprocess.Popen]:
    """Start node processes (``child_env()``: inherited environment minus the bootstrap marker).

    stdout/stderr go to ``log_dir/<name>.log``; the nodes of :data:`OFF_CONTROLLER_PATH` run
    :data:`OFF_PATH_NICE` nicer.
    """
    params = node_parameters(cfg)
    children = {}
    for name in names:
        log = open(log_dir / f"{name}.log", "w")  # noqa: SIM115 - closed with the process
        nicer = (lambda: os.nice(OFF_PATH_NICE)) if name in OFF_CONTROLLER_PATH else None
        children[name] = subprocess.Popen(child_command(name, params[name], cfg.params_file), env=child_env(),
                                          stdout=log, stderr=subprocess.STDOUT, preexec_fn=nicer)
        log.close()
    return children


#: Seconds a node process gets to exit after SIGINT before it is killed. On a quiet machine every node exits in
#: well under one; the recorder finishes its file on the way out, and a kill loses the chunk in progress (up to its
#: last 0.5 s flush). Sessions 1-17 gave 5 s; a CI run under load (session 17, load 5-8) found the file one stance
#: summary short of the ten the recorder had acknowledged, read then as a kill inside that grace. Session 26's CI
#: found the same with no node killed: the cause was rclpy's SIGINT raising ``KeyboardInterrupt`` inside the
#: recorder's MCAP write (mended by ``common.StopRequest``, session 27). A longer grace costs nothing when the nodes
#: exit, and :func:`recorder_shortfall` catches a short file whatever the cause.
STOP_GRACE_S = 20.0


def stop_children(children: dict[str, subprocess.Popen], grace_s: float = STOP_GRACE_S) -> list[str]:
    """SIGINT every child (nodes exit cleanly, the recorder finishes its file), then SIGKILL stragglers.

    Returns the names of the children that had to be killed.
    """
    for p in children.values():
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
    deadline = time.monotonic() + grace_s
    killed = []
    for name, p in children.items():
        try:
            p.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
            killed.append(name)
    return killed


def recorder_shortfall(report: PipelineReport, path: str | None = None) -> list[str]:
    """Topics of which the recorder's file holds fewer messages than the recorder acknowledged receiving.

    The acknowledgement is the recorder's last ``/pipeline/progress`` (a lower bound: it may lag the last
    messages), so any shortfall is a loss between the recorder's callback and the disk (a killed recorder, a file
    not finished). One line per topic: ``"<topic>: <n> in <file> of <m> the recorder received"``; empty when the
    file holds everything or the run had no recorder.
    """
    from hop_impedance.io.mcap_io import summarize

    path = path or report.output_mcap
    progress = report.progress.get("/recorder")
    if progress is None or not path or not Path(path).exists():
        return []
    in_file = {i.topic: i.count for i in summarize(path)}
    out = []
    for topic, received in zip(progress.topics, progress.received):
        if in_file.get(topic, 0) < int(received):
            out.append(f"{topic}: {in_file.get(topic, 0)} in {Path(path).name} of {int(received)} the recorder received")
    return out


def ready_subscriptions(cfg: PipelineConfig) -> dict[str, int]:
    """Subscriptions every downstream node must have before the replay starts (topic -> count).

    Results are reliable but volatile: a node still importing scipy when a
    stance is published would never get it (measured under load: 9 of 10
    stances missed by a late impedance_estimator). Counts include this
    process's :class:`ResultCollector`.
    """
    out = {FORCE_TOPIC: 2, MARKER_TOPIC: 1, STANCE_KINETICS_TOPIC: 1,
           SUMMARY_TOPIC: 2 + cfg.with_rerun, PROFILE_TOPIC: 2 + cfg.with_rerun}
    if cfg.with_rerun:
        out[FORCE_TOPIC] += 1
    return out


#: Publishers the collector must have discovered before the replay starts: its own readers are then
#: matched (measured under load: a collector that saw every subscription but not yet the estimator's
#: publishers received none of the 10 summaries of a 3 s rate-0 run).
READY_PUBLISHERS = {STANCE_KINETICS_TOPIC: 1, SUMMARY_TOPIC: 1, PROFILE_TOPIC: 1, CONTROLLER_TOPIC: 1}


def _wait_for_graph(executor, node: Node, expected: dict[str, int], deadline: float, alive=lambda: None) -> None:
    """Spin until ``node`` sees ``expected[topic]`` subscriptions and the :data:`READY_PUBLISHERS` (or raise at ``deadline``)."""
    while True:
        missing = {t: n for t, n in expected.items() if node.count_subscribers(t) < n}
        missing |= {t: n for t, n in READY_PUBLISHERS.items() if node.count_publishers(t) < n}
        if not missing:
            return
        if time.monotonic() > deadline:
            raise ValueError(f"nodes not up in time; subscriptions missing on {sorted(missing)} (see the node logs)")
        alive()
        executor.spin_once(timeout_sec=0.05)


def _wait_until_ready(executor, cfg: PipelineConfig, deadline: float, alive=lambda: None) -> None:
    """Spin until ``cfg.ready_to_play()`` holds (or raise at ``deadline``); nothing to wait for without it."""
    while cfg.ready_to_play is not None and not cfg.ready_to_play():
        if time.monotonic() > deadline:
            raise ValueError("not ready to play in time (PipelineConfig.ready_to_play never held)")
        alive()
        executor.spin_once(timeout_sec=0.05)


def _watch(children: dict[str, subprocess.Popen], log_dir: Path):
    """A check that raises :class:`NodeDied` when a child exited with an error (the replay exits 0 when done)."""

    def alive() -> None:
        for name, p in children.items():
            code = p.poll()
            if code not in (None, 0):
                how = f"was killed by signal {-code} ({signal.Signals(-code).name})" if code < 0 else f"exited with code {code}"
                raise NodeDied(f"node {name} {how}; see {log_dir / (name + '.log')}")

    return alive


def _run_processes(cfg: PipelineConfig) -> PipelineReport:
    import rclpy

    t0 = time.monotonic()
    log_dir = Path(cfg.out_dir) / "logs"
    log_dir.mkdir(parents=True, exist_ok=True)
    context = rclpy.Context()
    rclpy.init(context=context)
    children: dict[str, subprocess.Popen] = {}
    try:
        collector = ResultCollector(context=context)
        executor = _executor_for(context)
        executor.add_node(collector)
        names = NODE_MODULES[:-1] + ("rerun_bridge",) if cfg.with_rerun else NODE_MODULES[:-1]
        children = start_children(names, cfg, log_dir)
        alive = _watch(children, log_dir)
        try:
            _wait_for_graph(executor, collector, ready_subscriptions(cfg), t0 + cfg.timeout_s, alive)
            _wait_until_ready(executor, cfg, t0 + cfg.timeout_s, alive)
        except NodeDied as exc:
            collector.report.died = str(exc)
        else:
            children |= start_children(("replay",), cfg, log_dir)
            _spin_until_done(executor, collector, cfg, t0, alive)
        report = collector.report
    finally:
        killed = stop_children(children)
        collector.destroy_node() if "collector" in locals() else None
        context.try_shutdown()  # already shut down after Ctrl-C
    report.wall_s = time.monotonic() - t0
    report.output_mcap = cfg.output_mcap
    report.rrd = str(cfg.rerun_save or "")
    report.killed = killed
    return report


def stance_table(report: PipelineReport) -> list[str]:
    """The per-stance table: index, touchdown (s from the first stance), contact time, k0/k1 and R^2 per joint, status."""
    rows = sorted(report.summaries, key=lambda s: stamp_ns(s.touchdown_stamp))
    if not rows:
        return ["no stances"]
    t_first = stamp_ns(rows[0].touchdown_stamp)
    head = (f"{'#':>3} {'td s':>7} {'tc s':>6} | {'ankle k0':>8} {'k1':>7} {'R2':>5} | {'knee k0':>8} {'k1':>7} {'R2':>5} | "
            f"{'hip k0':>8} {'k1':>7} {'R2':>5} | status")
    lines = [head, "-" * len(head)]
    for s in rows:
        cells = []
        for j in range(3):
            cells.append(f"{_n(s.k0[j], 8, 1)} {_n(s.k1[j], 7, 0)} {_n(s.r_squared[j], 5, 3)}")
        status = "accepted" if not s.rejection_reason else s.rejection_reason
        if s.force_samples_lost_before:
            status += f" [{s.force_samples_lost_before} force samples lost since the previous stance]"
        td = (stamp_ns(s.touchdown_stamp) - t_first) * 1e-9
        lines.append(f"{s.stance_index:>3} {td:>7.3f} {s.contact_time_s:>6.3f} | " + " | ".join(cells) + f" | {status}")
    lines.append("k0 in N m/rad, k1 in N m/rad^2 (both legs lumped; 0 = term removed by the model reduction)")
    return lines


def _n(x: float, width: int, digits: int) -> str:
    return f"{x:>{width}.{digits}f}" if x == x else f"{'-':>{width}}"


def loss_lines(report: PipelineReport, file_counts: dict[str, int]) -> list[str]:
    """Messages in the file vs received per consumer, and the losses the nodes counted."""
    out = [f"{node} {topic}: {got} of {sent} received, {max(sent - got, 0)} lost"
           for node, topic, got, sent in _consumer_counts(report, file_counts)]
    between = report.diag("/inverse_dynamics", "force_lost_between_stances", "0")
    if between not in ("0", ""):
        out.append(f"/inverse_dynamics: {between} force samples lost outside reported stances "
                   "(flights, or whole stances never detected; stances with losses inside are rejected)")
    return out


def _consumer_counts(report: PipelineReport, file_counts: dict[str, int]):
    """(consumer, input topic, received, in the file) for every consumer and the inputs it subscribes."""
    for node in CONSUMERS:
        for topic in (FORCE_TOPIC, MARKER_TOPIC):
            if node == "/stance_detector" and topic == MARKER_TOPIC:
                continue
            yield node, topic, report.received(node, topic), file_counts.get(topic, 0)


def messages_lost(report: PipelineReport, file_counts: dict[str, int]) -> int:
    """Input messages of the file some consumer did not receive (sum over consumers and topics)."""
    return sum(max(sent - got, 0) for _, _, got, sent in _consumer_counts(report, file_counts))
