"""Late joiners (issue 15): an estimator started after the third stance still fits every stance, once.

One process, real DDS: replay (flow-controlled, as fast as the nodes take it),
stance_detector and inverse_dynamics run; the impedance_estimator node is
created only once three ``/stance/kinetics`` messages have been published.
``/stance/kinetics`` is transient-local with the last 20 stances
(``nodes/qos.history_qos``), so the estimator gets the three it missed at
once and the rest live: one summary per stance inverse dynamics published,
matched by touchdown stamp, none twice. A stance delivered twice (the
history and the live sample overlap) is fitted once.
"""

import os
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from hop_impedance_msgs.msg import StanceKinetics, StanceSummary  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from hop_impedance.nodes.common import STANCE_KINETICS_TOPIC, SUMMARY_TOPIC, stamp_ns  # noqa: E402
from hop_impedance.nodes.qos import history_qos, result_qos  # noqa: E402
from hop_impedance.nodes.runner import PipelineConfig, node_parameters  # noqa: E402

REC = "recordings/sim_2p20hz_hard.mcap"


def _node(cls, context, params):
    return cls(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def test_estimator_started_after_the_third_stance_fits_every_stance_once(tmp_path):
    from hop_impedance.nodes.impedance_estimator import ImpedanceEstimatorNode
    from hop_impedance.nodes.inverse_dynamics import InverseDynamicsNode
    from hop_impedance.nodes.replay import ReplayNode
    from hop_impedance.nodes.stance_detector import StanceDetectorNode

    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    params = node_parameters(PipelineConfig(REC, str(tmp_path), rate=0.0))
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        watcher = rclpy.create_node("late_joiner_watcher", context=context)
        kinetics, summaries = [], []
        watcher.create_subscription(StanceKinetics, STANCE_KINETICS_TOPIC, kinetics.append, history_qos())
        watcher.create_subscription(StanceSummary, SUMMARY_TOPIC, summaries.append, result_qos(1000))
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        nodes = [watcher, _node(StanceDetectorNode, context, params["stance_detector"]),
                 _node(InverseDynamicsNode, context, {**params["inverse_dynamics"], "publish_frames": False})]
        for n in nodes:
            executor.add_node(n)
        replay = _node(ReplayNode, context, params["replay"])
        executor.add_node(replay)

        def spin_until(predicate, timeout_s):
            deadline = time.monotonic() + timeout_s
            while time.monotonic() < deadline and not predicate():
                executor.spin_once(timeout_sec=0.05)
            return predicate()

        assert spin_until(lambda: len(kinetics) >= 3, 60)
        assert not summaries  # nobody fitted yet
        early = [stamp_ns(m.touchdown_stamp) for m in kinetics]
        estimator = _node(ImpedanceEstimatorNode, context, params["impedance_estimator"])
        executor.add_node(estimator)
        assert spin_until(lambda: replay.finished.is_set() and len(summaries) >= len(kinetics) >= 10, 90), \
            (len(summaries), len(kinetics))
        spin_until(lambda: False, 1.0)  # anything late or duplicated would arrive now
        # a stance delivered again (history and live overlap) is not fitted twice
        n = len(summaries)
        estimator._on_stance(kinetics[0])
        spin_until(lambda: False, 0.3)
        assert len(summaries) == n
    finally:
        rclpy.shutdown(context=context)

    published = sorted(stamp_ns(m.touchdown_stamp) for m in kinetics)
    fitted = sorted(stamp_ns(s.touchdown_stamp) for s in summaries)
    assert fitted == published  # every stance once, including the three published before the estimator existed
    assert set(early) <= set(fitted) and len(early) >= 3
