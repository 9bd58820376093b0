"""Two OS processes exchange our MarkerArray and geometry_msgs/WrenchStamped over real DDS."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from hop_impedance_msgs.msg import MarkerArray  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402

from hop_impedance.child_env import child_env  # noqa: E402

N = 500


def test_markers_and_wrenches_cross_process_boundary_intact():
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    wrenches, frames = [], []
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node("test_subscriber", context=context)
        qos = QoSProfile(depth=N, reliability=ReliabilityPolicy.RELIABLE)
        node.create_subscription(WrenchStamped, "/force_plate/wrench", wrenches.append, qos)
        node.create_subscription(MarkerArray, "/mocap/markers", frames.append, qos)
        child = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("publisher_process.py")), str(N)],
            env=child_env(), stderr=subprocess.PIPE, text=True,
        )
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        deadline = time.monotonic() + 30.0
        while (len(wrenches) < N or len(frames) < N) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        rc = child.wait(timeout=30)
        assert rc == 0, child.stderr.read()
    finally:
        rclpy.shutdown(context=context)
    assert len(wrenches) == N and len(frames) == N
    assert [w.wrench.force.z for w in wrenches] == [500.0 + i for i in range(N)]
    assert wrenches[7].wrench.torque.y == pytest.approx(-0.7)
    assert wrenches[7].header.frame_id == "force_plate"
    assert list(frames[3].names) == ["toe", "heel", "ankle", "knee", "hip", "head"]
    assert frames[3].positions[5].z == pytest.approx(0.05)
    assert frames[499].positions[0].x == 499.0
