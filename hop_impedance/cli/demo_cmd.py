"""``hop-impedance demo``: the main job of ``make demo``.

Replays a bundled recording through the ROS 2 node graph in this process
(multi-threaded executor) and prints what crossed DDS per topic.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="replay a bundled recording through the ROS 2 nodes and summarise",
        description="The main job of `make demo`: replay a recording through the node graph and print a summary.",
    )
    p.add_argument("--recording", default="recordings/hop_2p20hz_hard.mcap", help="recording to replay")
    p.add_argument("--out", default="demo_out", help="folder for outputs")
    p.add_argument("--rate", type=float, default=0.0, help="replay speed factor (0 = as fast as the nodes take it) [0]")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import rclpy
    from rclpy.executors import MultiThreadedExecutor
    from rclpy.parameter import Parameter

    from hop_impedance.io.mcap_io import summarize
    from hop_impedance.nodes.replay import ReplayNode
    from hop_impedance.nodes.topic_monitor import TopicMonitor

    recording = Path(args.recording)
    if not recording.exists():
        raise FileNotFoundError(f"{recording}: no such recording (see recordings/README.md)")
    Path(args.out).mkdir(parents=True, exist_ok=True)
    infos = {i.topic: i for i in summarize(recording)}
    t0 = time.monotonic()
    with rclpy.init():
        monitor = TopicMonitor({t: i.schema_name for t, i in infos.items()})
        replay = ReplayNode(parameter_overrides=[
            Parameter("recording", value=str(recording)), Parameter("rate", value=float(args.rate))])
        executor = MultiThreadedExecutor(num_threads=2)
        executor.add_node(monitor)
        executor.add_node(replay)
        while not replay.finished.is_set():
            executor.spin_once(timeout_sec=0.1)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and any(
            monitor.counts[t].count < n for t, n in replay.published.items() if t in monitor.counts):
            executor.spin_once(timeout_sec=0.05)
        executor.shutdown()
        if replay.error:
            raise ValueError(replay.error)
    elapsed = time.monotonic() - t0
    print(f"replayed {recording} through ROS 2 in {elapsed:.1f} s")
    print(f"{'topic':<22} {'in file':>8} {'received':>9} {'rate Hz':>9} {'span s':>8}")
    for topic, info in infos.items():
        c = monitor.counts[topic]
        print(f"{topic:<22} {info.count:>8} {c.count:>9} {c.rate_hz:>9.1f} {c.span_s:>8.3f}")
    return 0
