"""``hop-impedance replay REC.mcap``: publish a recording onto its ROS 2 topics."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay",
        help="play a recording onto the contract topics (ROS 2)",
        description="Publish an MCAP recording's /force_plate/wrench, /mocap/markers and /subject with the "
        "recorded timing. DDS discovery stays on this machine unless ROS_AUTOMATIC_DISCOVERY_RANGE says otherwise.",
    )
    p.add_argument("recording", help="MCAP file or rosbag2 folder")
    p.add_argument("--rate", type=float, default=1.0,
                   help="speed factor (1 = real time; 0 = as fast as subscribers take it without loss) [1]")
    p.add_argument("--loop", action="store_true", help="restart at the end (stamps keep increasing)")
    p.add_argument("--wait", type=float, default=5.0, help="seconds to wait for subscribers before playing [5]")
    p.add_argument("--best-effort", action="store_true", help="publish sensor topics best-effort (as live drivers do)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import rclpy
    from rclpy.parameter import Parameter

    from hop_impedance.io.mcap_io import MessageStream

    MessageStream(args.recording)  # an empty / non-MCAP / missing file: one line before ROS starts

    from hop_impedance.nodes.replay import ReplayNode

    params = [
        Parameter("recording", value=str(args.recording)),
        Parameter("rate", value=float(args.rate)),
        Parameter("loop", value=bool(args.loop)),
        Parameter("wait_for_subscribers_s", value=float(args.wait)),
        Parameter("reliable", value=not args.best_effort),
    ]
    import sys

    from rclpy.executors import ExternalShutdownException

    interrupted = False
    with rclpy.init():
        node = ReplayNode(parameter_overrides=params)
        try:
            while rclpy.ok() and not node.finished.is_set():
                rclpy.spin_once(node, timeout_sec=0.1)
        except (KeyboardInterrupt, ExternalShutdownException):
            interrupted = True
        # SIGINT shuts the context down: the playback thread then ends and sets ``finished`` too, possibly
        # before this line, so a finished node alone does not mean the replay ran to its end
        interrupted = interrupted or not rclpy.ok() or not node.finished.is_set()
        node.stop()
        node.finished.wait(5.0)  # the playback thread ends before the context goes
        for topic, n in node.published.items():
            print(f"{topic}: {n} messages published")
        for stop in node.stops:
            print(f"hop-impedance replay: warning: {stop}", file=sys.stderr)
    if interrupted:
        print("hop-impedance replay: interrupted", file=sys.stderr)
        return 130
    if node.error:
        raise ValueError(node.error)
    return 0
