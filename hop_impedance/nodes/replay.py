"""``replay``: play an MCAP recording onto its topics with the recorded timing.

Parameters
----------
recording : str
    Path of the ``.mcap`` file (or rosbag2 folder).
rate : float
    Playback speed factor: 1.0 real time, 10.0 ten times faster, 0.0 as fast
    as the subscribers take it without loss (reliable QoS; the node waits for
    every message to be acknowledged in blocks of ``block_size``).
loop : bool
    Start again at the end; header stamps of later passes are shifted by the
    recording's length so time keeps increasing downstream.
topics : list of str
    Topics to play (default: the contract's three inputs).
wait_for_subscribers_s : float
    Before starting, wait up to this long until every played topic has a
    subscriber (so nothing published before discovery is lost).
reliable : bool
    Publish sensor topics reliably (default true: a replay should not lose data).
consumers : list of str
    Fully qualified names of the nodes that consume the played topics (e.g.
    ``/stance_detector``, ``/inverse_dynamics``). With ``rate`` 0 and
    consumers given, flow control is by *consumer progress* instead of
    acknowledgements: each consumer reports on ``/pipeline/progress`` the
    newest input stamp it has processed, and the replay never runs more than
    ``max_ahead_s`` of recording time ahead of the slowest one. Subscriber
    queues (KEEP_LAST, depth ``qos.INPUT_DEPTH`` = 2000) then hold at most
    ``max_ahead_s`` x rate messages (500 at 1 kHz), so nothing overflows
    however slow a consumer is. A consumer silent for ``consumer_timeout_s``
    (crashed) is left out until it reports again, so a dead node cannot
    stall the replay.
max_ahead_s : float
    Recording time the replay may run ahead of the slowest consumer (s).
drop_fraction, drop_seed : float, int
    Tests of loss: leave out this fraction of the sensor messages, chosen by a
    seeded generator (reproducible, unlike loss from CPU starvation).

At the end the replay waits until every message is acknowledged and then
publishes a ``std_msgs/Header`` on ``/replay/end_of_stream`` (reliable,
transient-local) whose stamp is the newest played stamp: the consumers flush
their stages (the last stance) when they have received data up to it.

Messages are published as the CDR bytes stored in the file (no decode /
re-encode) except on loop passes after the first. ``/subject`` is published
with transient-local durability, as the contract asks.
"""

from __future__ import annotations

import bisect
import threading
import time
from typing import Any

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.serialization import deserialize_message, serialize_message

from hop_impedance.io.mcap_io import MessageStream, RecordingError
from hop_impedance.nodes.common import END_TOPIC, PROGRESS_TOPIC, header_stamp_ns, stamp_ns
from hop_impedance.nodes.message_types import message_class
from hop_impedance.nodes.qos import input_qos, latched_qos, result_qos
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC

DEFAULT_TOPICS = [FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC]
#: Published stamps kept per topic for rate-0 pacing (10 s at 1 kHz; more than ``max_ahead_s`` needs).
PACING_HISTORY = 10_000


def _raw_messages(path: str, topics: list[str], stops: list[str] | None = None):
    """(topic, schema name, log time ns, CDR bytes) in log-time order, without decoding, to the break.

    A truncated or damaged file yields what precedes the damage; where it stopped
    is appended to ``stops`` (one line).
    """
    stream = MessageStream(path, topics=topics, decode=False)
    for m in stream:
        yield m.topic, m.schema_name, m.log_time_ns, m.message
    if stream.stopped_at and stops is not None:
        stops.append(f"{stream.path.name}: {stream.stopped_at}")


class ReplayNode(Node):
    """Publishes a recording's messages; see the module docstring for parameters."""

    def __init__(self, **kwargs) -> None:
        super().__init__("replay", **kwargs)
        self.declare_parameter("recording", "", _desc("MCAP file or rosbag2 folder to play"))
        self.declare_parameter("rate", 1.0, _desc("speed factor; 0 = as fast as subscribers take it without loss"))
        self.declare_parameter("loop", False, _desc("restart at the end, shifting stamps forward"))
        self.declare_parameter("topics", DEFAULT_TOPICS, _desc("topics to play"))
        self.declare_parameter("wait_for_subscribers_s", 5.0, _desc("wait this long for subscribers before playing"))
        self.declare_parameter("reliable", True, _desc("publish sensor topics with reliable QoS"))
        self.declare_parameter("block_size", 200, _desc("with rate 0: wait for acknowledgement every N messages"))
        self.declare_parameter("consumers", [""], _desc("nodes whose /pipeline/progress paces a rate-0 replay"))
        self.declare_parameter("max_ahead_s", 0.5, _desc("rate 0 with consumers: run at most this far (recording s) ahead"))
        self.declare_parameter("consumer_timeout_s", 2.0, _desc("leave out a consumer silent for this long (s)"))
        self.declare_parameter("drop_fraction", 0.0, _desc("tests: leave out this fraction of sensor messages (seeded loss)"))
        self.declare_parameter("drop_seed", 0, _desc("tests: seed of the messages left out"))
        self.drop_fraction = float(self.get_parameter("drop_fraction").value)
        self._drop_rng = None
        if self.drop_fraction > 0:
            import numpy as np

            self._drop_rng = np.random.default_rng(int(self.get_parameter("drop_seed").value))
        self.consumers = [c for c in self.get_parameter("consumers").value if c]
        self.max_ahead_ns = int(float(self.get_parameter("max_ahead_s").value) * 1e9)
        self.consumer_timeout_s = float(self.get_parameter("consumer_timeout_s").value)
        self.progress: dict[str, tuple[dict[str, int], float]] = {}  # node -> ({topic: consumed stamp ns}, wall time of report)
        self.wait_s = 0.0
        self.play_s = 0.0  # wall time from the first message played to end-of-stream (throughput without start-up)
        self.last_stamp_ns = 0
        self._progress_event = threading.Event()
        from hop_impedance_msgs.msg import Progress
        from std_msgs.msg import Header

        self.create_subscription(Progress, PROGRESS_TOPIC, self._on_progress, result_qos(50))
        self._end_pub = self.create_publisher(Header, END_TOPIC, latched_qos())
        self.path = self.get_parameter("recording").value
        if not self.path:
            raise ValueError("replay: parameter 'recording' is required")
        self.rate = float(self.get_parameter("rate").value)
        if self.rate < 0:
            raise ValueError(f"replay: rate must be >= 0, got {self.rate}")
        self.topics = list(self.get_parameter("topics").value)
        self.reliable = bool(self.get_parameter("reliable").value)
        self.published = {t: 0 for t in self.topics}
        self.dropped = {t: 0 for t in self.topics}
        #: Where reading a damaged file stopped (one line per pass), shown by the CLI.
        self.stops: list[str] = []
        self._published_stamps: dict[str, list[int]] = {}  # topic -> increasing stamps published (ns), recent
        self.finished = threading.Event()
        self.error: str | None = None
        self._pubs: dict[str, rclpy.publisher.Publisher] = {}
        self._types: dict[str, type] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="replay", daemon=True)
        self._thread.start()

    def _publisher(self, topic: str, schema: str):
        pub = self._pubs.get(topic)
        if pub is None:
            cls = message_class(schema)
            qos = latched_qos() if topic == SUBJECT_TOPIC else input_qos(self.reliable)
            pub = self.create_publisher(cls, topic, qos)
            self._pubs[topic] = pub
            self._types[topic] = cls
        return pub

    def _wait_for_subscribers(self) -> None:
        timeout = float(self.get_parameter("wait_for_subscribers_s").value)
        # Create every publisher up front so discovery can happen while we wait.
        for topic, schema, _, _ in _first_per_topic(self.path, self.topics):
            self._publisher(topic, schema)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not self._stop.is_set():
            # With consumers: also wait for their first /pipeline/progress report, i.e. they are
            # spinning; under load a reader matched late loses the first samples of a volatile topic.
            reported = all(c in self.progress for c in self.consumers)
            if reported and all(p.get_subscription_count() > 0 for t, p in self._pubs.items() if t != SUBJECT_TOPIC):
                time.sleep(0.2)  # let the matched readers finish their handshake
                return
            time.sleep(0.02)

    def _run(self) -> None:
        try:
            self._wait_for_subscribers()
            loop = bool(self.get_parameter("loop").value)
            shift = 0
            t_play = time.monotonic()
            while not self._stop.is_set():
                span = self._play_once(shift)
                if not loop or span <= 0:
                    break
                shift += span
            t_drain = time.monotonic()
            self._drain()
            self._publish_end()
            self.play_s = time.monotonic() - t_play
            self.get_logger().info(f"end of stream published after {time.monotonic() - t_drain:.3f} s waiting for the "
                                   "readers' acknowledgement of the last messages")
        except (RecordingError, ValueError) as exc:
            self.error = str(exc)
            self.get_logger().error(self.error)
        except Exception as exc:  # an unexpected failure must still end the replay visibly  # noqa: BLE001
            if self._stop.is_set() or not self.context.ok():
                return  # Ctrl-C / shutdown while publishing: a stop, not a failure (finally still runs)
            self.error = f"replay failed: {type(exc).__name__}: {exc}"
            self.get_logger().error(self.error)
        finally:
            self.finished.set()

    def _play_once(self, shift_ns: int) -> int:
        """Publish the file once; returns its span in ns (for loop shifts)."""
        block = int(self.get_parameter("block_size").value)
        wall0 = time.monotonic()
        first = last = None
        n = 0
        for topic, schema, log_ns, data in _raw_messages(self.path, self.topics, self.stops):
            if self._stop.is_set():
                break
            if first is None:
                first = log_ns
            last = log_ns
            if topic == SUBJECT_TOPIC and shift_ns:
                continue  # latched once is enough
            pub = self._publisher(topic, schema)
            if self.rate > 0:
                due = wall0 + (log_ns - first) * 1e-9 / self.rate
                delay = due - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            payload = data if not shift_ns else self._shifted(topic, data, shift_ns)
            if topic != SUBJECT_TOPIC:
                stamp = header_stamp_ns(payload)
                self.last_stamp_ns = max(self.last_stamp_ns, stamp)
                if self.rate == 0 and self.consumers:
                    self._wait_for_consumers()
            if topic != SUBJECT_TOPIC and self._drop_rng is not None and self._drop_rng.random() < self.drop_fraction:
                self.dropped[topic] += 1  # injected loss (tests): the message is in the file but never sent
                continue
            pub.publish(payload)
            if topic != SUBJECT_TOPIC:
                self._note_published(topic, stamp)
            self.published[topic] += 1
            n += 1
            if self.rate == 0 and not self.consumers and n % block == 0:
                self._drain()
        return 0 if first is None else (last - first) + 1_000_000

    def _shifted(self, topic: str, data: bytes, shift_ns: int) -> bytes:
        msg: Any = deserialize_message(data, self._types[topic])  # a generated message class (no type information)
        total = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec + shift_ns
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(total, 1_000_000_000)
        return serialize_message(msg)

    def _drain(self) -> None:
        for topic, pub in self._pubs.items():
            if topic != SUBJECT_TOPIC:
                pub.wait_for_all_acked(Duration(seconds=5.0))

    def _on_progress(self, msg) -> None:
        if msg.node not in self.consumers:
            return
        consumed = {t: stamp_ns(s) for t, s in zip(msg.topics, msg.last_stamps) if t in self.topics and t != SUBJECT_TOPIC}
        if consumed:
            self.progress[msg.node] = (consumed, time.monotonic())
            self._progress_event.set()

    def _behind(self, node: str, now: float, t_wait: float) -> bool:
        """Whether ``node`` has not processed a message published more than ``max_ahead_s`` (stamp time) before the newest.

        Measured against the stamps actually published on each topic the node
        consumes (not the stamp about to go out, nor a stamp difference), so a gap
        in the stamps, a block of late messages or a topic the file does not have
        (force-only, marker-only) never makes the replay wait for data it has not
        sent: a consumer holding back only its reorder window is never behind.
        """
        consumed, seen = self.progress.get(node, ({}, t_wait))
        if now - seen > self.consumer_timeout_s:
            return False  # silent (crashed or never started): do not stall on it
        for topic, done in consumed.items():
            stamps = self._published_stamps.get(topic)
            if not stamps:
                continue
            i = bisect.bisect_right(stamps, done)
            if i < len(stamps) and stamps[i] <= stamps[-1] - self.max_ahead_ns:
                return True
        return False

    def _note_published(self, topic: str, stamp: int) -> None:
        """Keep the increasing published stamps of ``topic`` (late, older stamps are no pacing target)."""
        stamps = self._published_stamps.setdefault(topic, [])
        if not stamps or stamp > stamps[-1]:
            stamps.append(stamp)
            if len(stamps) > 2 * PACING_HISTORY:
                del stamps[:PACING_HISTORY]

    def _wait_for_consumers(self) -> None:
        """Block until no live consumer is more than ``max_ahead_s`` behind the published data."""
        t_wait = time.monotonic()
        while not self._stop.is_set():
            now = time.monotonic()
            if not any(self._behind(node, now, t_wait) for node in self.consumers):
                break
            self._progress_event.clear()
            self._progress_event.wait(0.01)
        self.wait_s += time.monotonic() - t_wait

    def _publish_end(self) -> None:
        from std_msgs.msg import Header

        msg = Header(frame_id=str(self.path))
        msg.stamp.sec, msg.stamp.nanosec = divmod(self.last_stamp_ns, 1_000_000_000)
        self._end_pub.publish(msg)

    def stop(self) -> None:
        """Ask the playback thread to stop (returns at once)."""
        self._stop.set()


def _first_per_topic(path: str, topics: list[str]):
    """The first message of each topic (for creating publishers before playing)."""
    seen = set()
    for topic, schema, log_ns, data in _raw_messages(path, topics):
        if topic not in seen:
            seen.add(topic)
            yield topic, schema, log_ns, data
            if len(seen) == len(topics):
                return


def _desc(text: str):
    from rcl_interfaces.msg import ParameterDescriptor

    return ParameterDescriptor(description=text)


def main(args=None) -> None:
    """Run the replay node until the recording has been played (or Ctrl-C / SIGTERM)."""
    from rclpy.executors import ExternalShutdownException

    from hop_impedance.nodes.common import wants_help

    if wants_help(args):  # print the parameters without starting ROS (checked by test/test_colcon_workspace.py)
        print(__doc__)
        return
    failed = None
    with rclpy.init(args=args):
        node = None
        try:
            node = ReplayNode()
            while rclpy.ok() and not node.finished.is_set():
                rclpy.spin_once(node, timeout_sec=0.1)
            node._end_pub.wait_for_all_acked(Duration(seconds=5.0))  # the latched end-of-stream must reach the consumers
            for topic, n in node.published.items():
                node.get_logger().info(f"{topic}: {n} messages")
            for stop in node.stops:
                node.get_logger().warning(stop)
            failed = node.error
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            if node is not None:
                node.stop()
                node.finished.wait(5.0)
    if failed:
        raise SystemExit(2)  # the runner reports "node replay exited with code 2" and the log's error line


if __name__ == "__main__":
    main()
