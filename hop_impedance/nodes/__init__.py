"""ROS 2 nodes: thin adapters around the core (the only modules that use rclpy).

Network rule: importing this package makes DDS discovery stay on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) unless the environment already
says otherwise, so ``python -m hop_impedance.nodes.<node>`` and the console
scripts are safe by default. The variable is read when rclpy initialises its
context, which every node does after this import.
"""

import os

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
