"""``recorder``: write the pipeline's topics to an MCAP file so a session can be replayed and audited.

Subscribes ``topics`` (default: every output topic and ``/diagnostics``) as
raw CDR (no decode) and writes them with the contract's MCAP layout
(rosbag2 style, schema text embedded). With ``copy_inputs_from`` (the
replayed recording) the input topics are copied from that file first, byte
for byte, so the output file holds inputs and outputs without pushing the
1 kHz inputs through DDS a second time; live, list the input topics in
``topics`` instead.

Times: ``log_time`` = the message's ``header.stamp`` (the sample clock,
so outputs sit next to the input samples they come from: a profile at its
take-off), ``publish_time`` = the wall-clock receive time. Every pipeline
message starts with a ``std_msgs/Header``, read straight from the CDR bytes.
The file is finished (index and summary written) when the node is destroyed;
until then the chunk in progress is flushed to the disk every ``flush_period_s``
(0.5 s), so a recorder killed with SIGKILL leaves a file readable (``info``,
``analyze``, ``replay`` read to the break) up to its last flush.
"""

from __future__ import annotations

import time
from pathlib import Path

from rclpy.node import Node

from hop_impedance.io.mcap_io import McapWriter, MessageStream
from hop_impedance.nodes.common import OUTPUT_TOPICS, TOPIC_TYPES, InputTracker, ProgressReporter, declare, header_stamp_ns
from hop_impedance.nodes.message_types import message_class
from hop_impedance.nodes.qos import input_qos, latched_qos, result_qos
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC


class RecorderNode(Node):
    """Writes topics to ``output``; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("recorder", **kwargs)
        self.output = declare(self, "output", "", "MCAP file to write (its folder is created)")
        topics = declare(self, "topics", list(OUTPUT_TOPICS), "topics to record (type from the pipeline's topic table)")
        source = declare(self, "copy_inputs_from", "", "copy the input topics of this MCAP into the output first")
        reliable = declare(self, "reliable_inputs", True, "QoS reliability used for recorded input topics")
        flush_s = declare(self, "flush_period_s", 0.5, "write the chunk in progress to the disk this often (s)")
        if not self.output:
            raise ValueError("recorder: parameter 'output' is required")
        unknown = [t for t in topics if t not in TOPIC_TYPES]
        if unknown:
            raise ValueError(f"recorder: no known type for topic(s) {unknown}; known: {sorted(TOPIC_TYPES)}")
        Path(self.output).parent.mkdir(parents=True, exist_ok=True)
        self.writer = McapWriter(self.output)
        self.copied = copy_messages(source, self.writer) if source else 0
        self.trackers = {t: InputTracker(t) for t in topics}
        for topic in topics:
            qos = latched_qos() if topic == SUBJECT_TOPIC else (
                input_qos(reliable) if topic in (FORCE_TOPIC, MARKER_TOPIC) else result_qos(5000))
            self.create_subscription(message_class(TOPIC_TYPES[topic]), topic, self._writer_for(topic), qos, raw=True)
        self.progress = ProgressReporter(self, self.trackers, period_s=0.05)
        self.writer.flush()  # the copied inputs are on the disk before the first output arrives
        self.create_timer(flush_s, self.writer.flush)

    def _writer_for(self, topic: str):
        type_name = TOPIC_TYPES[topic]
        tracker = self.trackers[topic]

        def on_message(data: bytes) -> None:
            stamp = header_stamp_ns(data)
            tracker.received += 1
            self.writer.write_serialized(topic, type_name, data, stamp, time.time_ns())
            self.progress.processed_ns[topic] = max(stamp, self.progress.processed_ns.get(topic, 0))

        return on_message

    def close(self) -> None:
        """Finish the file (safe to call twice)."""
        self.writer.close()

    def destroy_node(self) -> None:
        self.close()
        super().destroy_node()


def copy_messages(path: str, writer: McapWriter, topics: tuple[str, ...] = (FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC)) -> int:
    """Copy ``topics`` of an MCAP file into ``writer`` unchanged (CDR bytes, log and publish times), to the break."""
    n = 0
    stream = MessageStream(path, topics=list(topics), decode=False)
    for m in stream:
        writer.write_serialized(m.topic, m.schema_name, m.message, m.log_time_ns, m.publish_time_ns)
        n += 1
    return n


def main(args=None) -> None:
    """Run the node (``python -m hop_impedance.nodes.recorder --ros-args -p output:=OUT.mcap``).

    The file is finished in :meth:`RecorderNode.destroy_node`, which ``spin_node`` calls on exit.
    """
    from hop_impedance.nodes.common import spin_node

    spin_node(RecorderNode, args)


if __name__ == "__main__":
    main()
