"""Is the ``mcap`` writer exception-safe? An exception raised by a signal handler at a random point of a write loop.

Each trial writes 200-byte ``/joint_kinetics`` messages (1 ms apart, a flush every 100, as the recorder's timer
would) through :class:`hop_impedance.io.mcap_io.McapWriter` until a ``SIGALRM`` 1-50 ms in raises an exception
(what ``KeyboardInterrupt`` from rclpy's chained SIGINT handler did inside the recorder's callbacks), then closes
the file and counts its messages against the writes that returned. A trial is lost when the file holds fewer
than those writes (the write in flight may or may not be there). Why ``nodes.common.StopRequest`` exists.

    .venv/bin/python bench/mcap_interrupt_probe.py [--trials 300] [--seed 0]
"""

from __future__ import annotations

import argparse
import random
import signal
import tempfile
from pathlib import Path

from hop_impedance.io.mcap_io import McapWriter, summarize
from hop_impedance.nodes.common import TOPIC_TYPES

TOPIC = "/joint_kinetics"


class Interrupted(Exception):
    """Raised by the alarm's handler."""


def _raise(*_args) -> None:
    raise Interrupted


def one_trial(path: Path, after_s: float) -> tuple[int, int]:
    """(writes that returned, messages in the closed file)."""
    writer = McapWriter(path)
    done = 0
    signal.setitimer(signal.ITIMER_REAL, after_s)
    try:
        while True:
            writer.write_serialized(TOPIC, TOPIC_TYPES[TOPIC], bytes(200), done * 1_000_000, 0)
            done += 1
            if done % 100 == 0:
                writer.flush()
    except Interrupted:
        pass
    writer.close()
    return done, {i.topic: i.count for i in summarize(str(path))}.get(TOPIC, 0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    signal.signal(signal.SIGALRM, _raise)
    rng = random.Random(args.seed)
    lost_trials, lost_messages = 0, 0
    with tempfile.TemporaryDirectory() as tmp:
        for trial in range(args.trials):
            done, in_file = one_trial(Path(tmp) / f"{trial}.mcap", rng.uniform(0.001, 0.05))
            if in_file < done:
                lost_trials += 1
                lost_messages += done - in_file
    print(f"{lost_trials} of {args.trials} interrupted trials lost messages ({lost_messages} messages in all)")


if __name__ == "__main__":
    main()
