"""mocap4r2 adapter over real DDS: a separate driver process publishes mocap4r2_msgs/Markers,
the adapter node republishes the contract MarkerArray, checked marker by marker."""

import math
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
from hop_impedance_msgs.msg import MarkerArray  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402

from hop_impedance.child_env import child_env  # noqa: E402
from hop_impedance.nodes.mocap4r2_adapter import MarkerIdentities, Mocap4r2AdapterNode  # noqa: E402
from hop_impedance.recording import MARKER_NAMES  # noqa: E402
from mocap4r2_msgs.msg import Marker  # noqa: E402
from test.ros.mocap4r2_publisher_process import INDICES, LABELS, position  # noqa: E402

N = 200
#: Topics of this test process only, so a pytest sharing the ROS domain cannot feed or read them.
IN_TOPIC = f"/test_mocap4r2_{os.getpid()}/markers"
OUT_TOPIC = f"/test_mocap4r2_{os.getpid()}/mocap/markers"
ORIGIN = (0.5, -0.2, 0.01)


def test_driver_process_frames_arrive_as_contract_markers():
    frames = []
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        params = [
            Parameter("input_topic", value=IN_TOPIC),
            Parameter("output_topic", value=OUT_TOPIC),
            Parameter("marker_names", value=list(MARKER_NAMES)),
            Parameter("marker_labels", value=LABELS),
            Parameter("marker_indices", value=INDICES),
            Parameter("origin_m", value=list(ORIGIN)),
            Parameter("reliable_inputs", value=True),
        ]
        adapter = Mocap4r2AdapterNode(context=context, parameter_overrides=params)
        listener = rclpy.create_node("test_listener", context=context)
        listener.create_subscription(MarkerArray, OUT_TOPIC, frames.append,
                                     QoSProfile(depth=N, reliability=ReliabilityPolicy.RELIABLE))
        child = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("mocap4r2_publisher_process.py")), str(N), IN_TOPIC],
            env=child_env(), stderr=subprocess.PIPE, text=True,
        )
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(adapter)
        executor.add_node(listener)
        deadline = time.monotonic() + 30.0
        while len(frames) < N and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        rc = child.wait(timeout=30)
        assert rc == 0, child.stderr.read()
        missing, frames_out = list(adapter.missing), adapter.frames_out
        level = adapter._diag_level()
    finally:
        rclpy.shutdown(context=context)
    assert len(frames) == frames_out == N
    knee = MARKER_NAMES.index("knee")
    for i, f in enumerate(frames):
        assert (f.header.stamp.sec, f.header.stamp.nanosec) == (200, i * 4_000_000)
        assert f.header.frame_id == "lab"
        assert list(f.names) == list(MARKER_NAMES)
        for k, p in enumerate(f.positions):
            if k == knee and i % 7 == 0:
                assert math.isnan(p.x) and math.isnan(p.y) and math.isnan(p.z), f"frame {i}: occluded knee must be NaN"
                continue
            want = [a - o for a, o in zip(position(i, k), ORIGIN)]
            assert [p.x, p.y, p.z] == want, f"frame {i} (id mode {i % 4}), {MARKER_NAMES[k]}"
    assert missing[knee] == len(range(0, N, 7)) and sum(missing) == missing[knee]
    assert level[0] == 0


def _marker(id_type, name="", index=-1):
    return Marker(id_type=id_type, marker_name=name, marker_index=index)


def test_identities_follow_id_type():
    ids = MarkerIdentities(["toe", "hip"], ["RTOE", ""], [7, 3])
    assert ids.slot(_marker(Marker.USE_NAME, "RTOE")) == MARKER_NAMES.index("toe")
    assert ids.slot(_marker(Marker.USE_NAME, "rtoe")) == MARKER_NAMES.index("toe")
    assert ids.slot(_marker(Marker.USE_BOTH, "RTOE", 3)) == MARKER_NAMES.index("toe")  # the name wins
    assert ids.slot(_marker(Marker.USE_INDEX, "RTOE", 3)) == MARKER_NAMES.index("hip")  # the index wins
    assert ids.slot(_marker(Marker.USE_NAME, "", 7)) == MARKER_NAMES.index("toe")  # old driver: index only
    assert ids.slot(_marker(Marker.USE_NAME, "LTOE", 7)) is None
    with pytest.raises(ValueError, match="not contract markers"):
        MarkerIdentities(["foot"], ["X"], [1])
    with pytest.raises(ValueError, match="neither a label nor an index"):
        MarkerIdentities(["toe"], [""], [-1])
