"""A node process stopped with SIGINT finishes the callback in progress and closes its files (``spin_node``).

Session 26's CI under load: the recorder exited cleanly on the runner's SIGINT, yet its MCAP file lacked the
last stance's outputs it had acknowledged receiving. rclpy's own signal handlers chain to Python's, which raises
``KeyboardInterrupt`` inside whatever callback runs, and an exception in the middle of an ``mcap`` write or flush
loses the chunk in progress (``bench/mcap_interrupt_probe.py``). Here a real rclpy node process writes MCAP
messages in one long timer callback; SIGINT arrives in the middle of it. The callback must run to its end and the
file must hold every message written.
"""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy")

ROOT = Path(__file__).resolve().parents[2]

NODE = r'''
import sys, time
from rclpy.node import Node
from hop_impedance.io.mcap_io import McapWriter
from hop_impedance.nodes.common import TOPIC_TYPES, spin_node

TOPIC = "/joint_kinetics"

class Busy(Node):
    def __init__(self):
        super().__init__("busy_writer")
        self.writer = McapWriter(sys.argv[1])
        self.written = 0
        self.timer = self.create_timer(0.05, self.work)

    def work(self):
        self.timer.cancel()
        print("busy", flush=True)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.5:  # SIGINT arrives in here
            self.writer.write_serialized(TOPIC, TOPIC_TYPES[TOPIC], bytes(200), self.written * 1000, 0)
            self.written += 1
            if self.written % 100 == 0:
                self.writer.flush()
        print("finished", self.written, flush=True)

    def destroy_node(self):
        self.writer.close()
        print("closed", self.written, flush=True)
        super().destroy_node()

spin_node(Busy, [])
'''


def test_sigint_inside_a_callback_lets_it_finish_and_the_file_hold_every_message(tmp_path):
    from hop_impedance.io.mcap_io import summarize

    out = tmp_path / "busy.mcap"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    proc = subprocess.Popen([sys.executable, "-c", NODE, str(out)], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        first = proc.stdout.readline()
        assert first.strip() == "busy", first + proc.stdout.read()
        proc.send_signal(signal.SIGINT)
        rest, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, rest
    lines = rest.split()
    # the callback was not cut short by the signal, and then the node closed its file
    assert "finished" in lines and "closed" in lines, rest
    written = int(lines[lines.index("closed") + 1])
    assert written > 1000
    assert {i.topic: i.count for i in summarize(str(out))}["/joint_kinetics"] == written
