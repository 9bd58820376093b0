"""Test-session settings shared by every test.

Network rule: any rclpy started by a test (in-process or in a child process)
keeps DDS discovery on loopback. Each pytest process gets its own ROS domain so
that concurrent runs on one machine do not see each other's topics.
"""

import os

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
os.environ.setdefault("MPLBACKEND", "Agg")
