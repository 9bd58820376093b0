"""A node killed (SIGKILL) and restarted mid-recording resumes with the next complete stance.

Separate processes over real DDS: stance_detector, inverse_dynamics, impedance_estimator and a
replay (the bundled recording at real time, looped so enough stances follow the restart) as
children started like ``hop-impedance pipeline --processes``; this process collects
``/stance/events``, ``/impedance/profile`` and ``/impedance/stance_summary``.

What is asserted, with ``t_up`` the wall time at which the restarted node's reader (a new
endpoint GID; the killed one lingers until its DDS lease expires) is visible in the graph and,
for inverse_dynamics, its first progress report with input data received (the replay matches
new readers only after DDS discovery, measured up to several seconds under load) and a 3 s margin
for its readers to match the publishers (with 0.5 s, and again with 1.5 s in a later fresh-clone CI
run, the first stances after an estimator restart were missed: discovery between the new process
and inverse_dynamics was still under way):

- every stance whose touchdown event arrives after ``t_up + 3 s`` gets exactly one summary
  (accepted, or with a rejection reason) and three profiles, matched by touchdown stamp;
- the first summary published by the restarted node is that of the first such stance or an
  earlier one (it resumes with the next stance, no later);
- nothing is half-processed: every summary has its three profiles, and every rejected
  summary names its reason (a restarted estimator fits the recent stances of the
  transient-local ``/stance/kinetics`` history again: such a stance has two summaries,
  each with its three profiles). Stances in flight while the node was dead get no result; the
  killed node never published a summary without its profiles (summaries are published last).
"""

import collections
import os
import signal
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from hop_impedance_msgs.msg import ImpedanceProfile, Progress, StanceEvent, StanceSummary  # noqa: E402

from hop_impedance.nodes.common import (  # noqa: E402
    EVENTS_TOPIC,
    PROFILE_TOPIC,
    PROGRESS_TOPIC,  # noqa: E402
    STANCE_KINETICS_TOPIC,  # noqa: E402
    SUMMARY_TOPIC,
    stamp_ns,
)
from hop_impedance.nodes.qos import result_qos  # noqa: E402
from hop_impedance.nodes.runner import PipelineConfig, start_children, stop_children  # noqa: E402
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC  # noqa: E402

REC = "recordings/sim_2p20hz_hard.mcap"
MARGIN_S = 3.0
# the topic whose subscription shows that the restarted node is up (only that node subscribes it here)
WATCH = {"impedance_estimator": STANCE_KINETICS_TOPIC, "inverse_dynamics": MARKER_TOPIC}


class Collector:
    def __init__(self, node):
        self.node = node
        self.touchdowns: list[tuple[int, float]] = []  # (touchdown stamp ns, wall arrival)
        self.summaries: list[tuple[StanceSummary, float]] = []
        self.profiles: list[ImpedanceProfile] = []
        node.create_subscription(StanceEvent, EVENTS_TOPIC, self._on_event, result_qos(1000))
        node.create_subscription(StanceSummary, SUMMARY_TOPIC, lambda m: self.summaries.append((m, time.monotonic())),
                                 result_qos(1000))
        node.create_subscription(ImpedanceProfile, PROFILE_TOPIC, self.profiles.append, result_qos(1000))
        self.progress: list[tuple[str, int, float]] = []  # (node, inputs received, wall arrival)
        node.create_subscription(Progress, PROGRESS_TOPIC,
                                 lambda m: self.progress.append((m.node, sum(m.received), time.monotonic())), result_qos(1000))

    def _on_event(self, msg):
        if msg.event_type == StanceEvent.TOUCHDOWN:
            self.touchdowns.append((stamp_ns(msg.event_stamp), time.monotonic()))


def _spin_until(executor, predicate, timeout_s, alive):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        alive()
        executor.spin_once(timeout_sec=0.05)
    return predicate()


def _reader_gids(node, topic):
    return {bytes(info.endpoint_gid) for info in node.get_subscriptions_info_by_topic(topic)}


def _match(summaries, td_ns, tol_ns=5_000_000):
    return [s for s in summaries if abs(stamp_ns(s.touchdown_stamp) - td_ns) <= tol_ns]


@pytest.mark.slow
@pytest.mark.parametrize("victim", ["impedance_estimator", "inverse_dynamics"])
def test_killed_node_resumes_with_next_complete_stance(tmp_path, victim):
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    cfg = PipelineConfig(REC, str(tmp_path), rate=1.0, loop=True, processes=True)
    context = rclpy.Context()
    rclpy.init(context=context)
    children = {}
    try:
        node = rclpy.create_node("kill_restart_collector", context=context)
        col = Collector(node)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)

        def alive():
            for name, p in children.items():
                assert p.poll() is None or name == victim, f"{name} exited: {(tmp_path / (name + '.log')).read_text()[-2000:]}"

        children = start_children(("stance_detector", "inverse_dynamics", "impedance_estimator"), cfg, tmp_path)
        assert _spin_until(executor, lambda: node.count_subscribers(STANCE_KINETICS_TOPIC) >= 1
                           and node.count_subscribers(FORCE_TOPIC) >= 2, 60, alive)
        children |= start_children(("replay",), cfg, tmp_path)
        # let the pipeline publish a few summaries, then SIGKILL the victim and restart it at once
        assert _spin_until(executor, lambda: len(col.summaries) >= 3, 60, alive), "no summaries before the kill"
        children[victim].send_signal(signal.SIGKILL)
        children[victim].wait(timeout=10)
        t_kill = time.monotonic()
        n_before = len(col.summaries)
        # the dead node's reader stays in the graph until its DDS lease expires: wait for a new reader instead
        old_readers = _reader_gids(node, WATCH[victim])
        children |= start_children((victim,), cfg, tmp_path)
        assert _spin_until(executor, lambda: _reader_gids(node, WATCH[victim]) - old_readers, 60, alive)
        if victim == "inverse_dynamics":
            # its inputs flow again once the replay has matched the new readers (DDS discovery, can take
            # seconds under load): the first progress report of the new process with data received
            def receiving():
                return [w for n, r, w in col.progress if n == "/" + victim and r > 0 and w > t_kill]

            assert _spin_until(executor, receiving, 60, alive), "restarted inverse_dynamics never received data"

        t_up = time.monotonic()

        def after():
            return [td for td, wall in col.touchdowns if wall > t_up + MARGIN_S]

        assert _spin_until(executor, lambda: len(after()) >= 5, 60, alive), "too few stances after the restart"
        targets = after()[:4]  # the fifth touchdown ends the fourth stance's window (batch mode)
        assert _spin_until(executor, lambda: all(_match([s for s, _ in col.summaries], td) for td in targets), 30, alive), \
            (f"no result for stances after the restart: targets {targets}, summaries "
             f"{[(stamp_ns(s.touchdown_stamp), s.rejection_reason) for s, _ in col.summaries]} "
             f"({victim} log: {(tmp_path / (victim + '.log')).read_text()[-1500:]})")
        # the profiles published with the last summaries: another topic, so they may arrive after the summary
        # (reliable, so they do arrive; under load a fixed 0.5 s was once too short for the last stance's two)
        def profiles_complete() -> bool:
            got = collections.Counter(stamp_ns(p.touchdown_stamp) for p in col.profiles)
            want = collections.Counter(stamp_ns(s.touchdown_stamp) for s, _ in col.summaries)
            return all(got[td] >= 3 * n for td, n in want.items())

        _spin_until(executor, profiles_complete, 10, alive)
    finally:
        stop_children(children)
        rclpy.shutdown(context=context)

    summaries = [s for s, _ in col.summaries]
    # every stance whose touchdown came after the restart: exactly one result, accepted or with a reason
    for td in targets:
        (s,) = _match(summaries, td)
        assert all(s.accepted) or s.rejection_reason
    # the restarted node resumes with the next stance: its first summary is no later than the first target
    restarted = [s for s, wall in col.summaries[n_before:] if wall > t_kill]
    assert stamp_ns(restarted[0].touchdown_stamp) <= targets[0] + 5_000_000
    # nothing half-processed: each summary has its three profiles (by touchdown stamp and joint). A restarted
    # estimator fits the recent stances again from the transient-local /stance/kinetics history (issue 15, late
    # joiners), so a stance may have two summaries, each with its three profiles.
    by_stance = {}
    for p in col.profiles:
        by_stance.setdefault(stamp_ns(p.touchdown_stamp), []).append(p)
    n_summaries = {}
    for s in summaries:
        n_summaries[stamp_ns(s.touchdown_stamp)] = n_summaries.get(stamp_ns(s.touchdown_stamp), 0) + 1
    for s in summaries:
        profiles = by_stance.get(stamp_ns(s.touchdown_stamp), [])
        assert sorted(p.joint for p in profiles) == sorted(["ankle", "hip", "knee"] * n_summaries[stamp_ns(s.touchdown_stamp)]), \
            s.stance_index
        for p in profiles:
            assert p.accepted or p.rejection_reason
    # and the stances before the kill had results too
    assert n_before >= 3
