"""Test-session settings shared by every test.

Network rule: any rclpy started by a test (in-process or in a child process)
keeps DDS discovery on loopback. Each pytest process gets its own ROS domain so
that concurrent runs on one machine do not see each other's topics, and each
test moves on to the next domain (:func:`own_ros_domain`), so DDS data of an
earlier test (a transient-local publisher still alive in this process or in a
child) cannot reach a later test's subscribers.
"""

import itertools
import os

import pytest

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
os.environ.setdefault("MPLBACKEND", "Agg")

_DOMAINS = itertools.count(int(os.environ["ROS_DOMAIN_ID"]))


@pytest.fixture(autouse=True)
def own_ros_domain(monkeypatch):
    """A fresh ROS_DOMAIN_ID (1..100, cycling) for every test and the processes it starts.

    The full suite once saw a test receive 20 stances where its own pipeline published 10, and a pipeline
    report with 11 summaries for 1 stance: the extra ones came from an earlier test's nodes in the same
    domain. Domains 1-100 stay within the port range DDS maps for a default participant setup.
    """
    monkeypatch.setenv("ROS_DOMAIN_ID", str(1 + (next(_DOMAINS) - 1) % 100))
