"""Child process for test_two_process_dds: publishes N wrenches and N marker frames.

Waits until the subscriber has matched both topics, publishes, waits for the
subscriber to acknowledge (reliable QoS, deep history), then exits 0.
Usage: python publisher_process.py N
"""

import sys
import time

import rclpy
from geometry_msgs.msg import Point, WrenchStamped
from hop_impedance_msgs.msg import MarkerArray
from rclpy.qos import QoSProfile, ReliabilityPolicy


def main() -> int:
    n = int(sys.argv[1])
    rclpy.init()
    node = rclpy.create_node("test_publisher")
    qos = QoSProfile(depth=n, reliability=ReliabilityPolicy.RELIABLE)
    pub_w = node.create_publisher(WrenchStamped, "/force_plate/wrench", qos)
    pub_m = node.create_publisher(MarkerArray, "/mocap/markers", qos)
    deadline = time.monotonic() + 20.0
    while (pub_w.get_subscription_count() == 0 or pub_m.get_subscription_count() == 0) and time.monotonic() < deadline:
        time.sleep(0.02)
    if time.monotonic() >= deadline:
        print("no subscriber matched", file=sys.stderr)
        return 3
    for i in range(n):
        w = WrenchStamped()
        w.header.stamp.sec, w.header.stamp.nanosec = 100, i * 1000
        w.header.frame_id = "force_plate"
        w.wrench.force.z = 500.0 + i
        w.wrench.torque.y = -0.1 * i
        pub_w.publish(w)
        m = MarkerArray()
        m.header.stamp.sec, m.header.stamp.nanosec = 100, i * 1000
        m.names = ["toe", "heel", "ankle", "knee", "hip", "head"]
        m.positions = [Point(x=float(i), y=-0.1, z=0.01 * k) for k in range(6)]
        pub_m.publish(m)
    pub_w.wait_for_all_acked(rclpy.duration.Duration(seconds=10))
    pub_m.wait_for_all_acked(rclpy.duration.Duration(seconds=10))
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
