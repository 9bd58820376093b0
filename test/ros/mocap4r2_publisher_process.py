"""Child process for test_mocap4r2_adapter: a stand-in mocap4r2 driver publishing N Markers frames.

Every frame carries the six contract markers of the test's lab (labels RTOE ...,
indices 10..15) in a shuffled order among four markers of no interest, with the
identification mode cycling through what drivers send: names only (USE_NAME),
indices only (USE_INDEX, empty names), both (USE_BOTH, with indices that point
at the wrong markers, so only the names can be right), and an old driver's
index-only marker (USE_NAME with an empty name). Every seventh frame lacks the
knee (occluded). Positions follow :func:`position`. Exits 0 once all is acknowledged.
Usage: python mocap4r2_publisher_process.py N TOPIC
"""

import random
import sys
import time

import rclpy
from geometry_msgs.msg import Point
from rclpy.qos import QoSProfile, ReliabilityPolicy

from mocap4r2_msgs.msg import Marker, Markers

LABELS = ["RTOE", "RHEE", "RANK", "RKNE", "RTRO", "HEAD"]  # contract order: toe heel ankle knee hip head
INDICES = [10, 11, 12, 13, 14, 15]
OTHERS = [("LTOE", 20), ("LHEE", 21), ("C7", 22), ("RASI", 23)]


def position(frame: int, k: int) -> tuple[float, float, float]:
    """Lab position of marker k (0-5 contract order, 6+ others) in frame ``frame`` (m)."""
    return (0.001 * frame + 0.25 * k, -0.1 + 0.02 * k, 0.05 + 0.3 * k + 1e-4 * frame)


def frame_markers(i: int, rng: random.Random) -> list[Marker]:
    mode = i % 4
    entries = [(LABELS[k], INDICES[k], k) for k in range(6) if not (k == 3 and i % 7 == 0)]
    entries += [(name, idx, 6 + j) for j, (name, idx) in enumerate(OTHERS)]
    rng.shuffle(entries)
    out = []
    for label, index, k in entries:
        m = Marker(translation=Point(x=position(i, k)[0], y=position(i, k)[1], z=position(i, k)[2]))
        if mode == 0:
            m.id_type, m.marker_name, m.marker_index = Marker.USE_NAME, label.lower() if k == 1 else label, -1
        elif mode == 1:
            m.id_type, m.marker_name, m.marker_index = Marker.USE_INDEX, "", index
        elif mode == 2:
            m.id_type, m.marker_name, m.marker_index = Marker.USE_BOTH, label, INDICES[(k + 1) % 6] if k < 6 else index
        else:
            m.id_type, m.marker_name, m.marker_index = Marker.USE_NAME, "", index
        out.append(m)
    return out


def main() -> int:
    n, topic = int(sys.argv[1]), sys.argv[2]
    rclpy.init()
    node = rclpy.create_node("fake_mocap4r2_driver")
    pub = node.create_publisher(Markers, topic, QoSProfile(depth=n, reliability=ReliabilityPolicy.RELIABLE))
    deadline = time.monotonic() + 20.0
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.02)
    if pub.get_subscription_count() == 0:
        print("no subscriber matched", file=sys.stderr)
        return 3
    rng = random.Random(19)
    for i in range(n):
        msg = Markers(frame_number=1000 + i, markers=frame_markers(i, rng))
        msg.header.stamp.sec, msg.header.stamp.nanosec = 200, i * 4_000_000  # 250 Hz
        msg.header.frame_id = "map"
        pub.publish(msg)
        time.sleep(0.001)
    pub.wait_for_all_acked(rclpy.duration.Duration(seconds=10))
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
