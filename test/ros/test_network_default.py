"""Every way of starting a node keeps DDS discovery on loopback unless told otherwise."""

import os
import subprocess
import sys


def _range_seen_by(module: str) -> str:
    env = {k: v for k, v in os.environ.items() if k != "ROS_AUTOMATIC_DISCOVERY_RANGE"}
    code = f"import {module}, os; print(os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE'))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip().splitlines()[-1]


def test_importing_a_node_module_defaults_to_localhost():
    assert _range_seen_by("hop_impedance.nodes.replay") == "LOCALHOST"


def test_the_cli_defaults_to_localhost():
    env = {k: v for k, v in os.environ.items() if k != "ROS_AUTOMATIC_DISCOVERY_RANGE"}
    code = "import os, hop_impedance.cli.main as m; m.main([]); print(os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE'))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "LOCALHOST"


def test_an_explicit_setting_is_respected():
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET")
    code = "import hop_impedance.nodes, os; print(os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'])"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "SUBNET"
