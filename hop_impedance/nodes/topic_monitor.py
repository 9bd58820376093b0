"""``topic_monitor``: count what arrives on topics (message count, stamp span, rate).

Used by the demo and the end-to-end tests to report what crossed DDS. Subscribes
with the same QoS the pipeline uses and records each message's ``header.stamp``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rclpy.node import Node

from hop_impedance.nodes.message_types import message_class
from hop_impedance.nodes.qos import input_qos, latched_qos
from hop_impedance.recording import SUBJECT_TOPIC


@dataclass
class TopicCount:
    """What one topic delivered: count and first/last header stamp (ns)."""

    topic: str
    count: int = 0
    first_ns: int | None = None
    last_ns: int | None = None
    stamps: list[int] = field(default_factory=list, repr=False)

    @property
    def span_s(self) -> float:
        return 0.0 if self.first_ns is None or self.last_ns is None else (self.last_ns - self.first_ns) * 1e-9

    @property
    def rate_hz(self) -> float:
        return (self.count - 1) / self.span_s if self.count > 1 and self.span_s > 0 else 0.0


class TopicMonitor(Node):
    """Counts messages on ``topics`` (a dict topic -> ``pkg/msg/Type``)."""

    def __init__(self, topics: dict[str, str], reliable: bool = True, **kwargs):
        super().__init__("topic_monitor", **kwargs)
        self.counts = {t: TopicCount(t) for t in topics}
        for topic, type_name in topics.items():
            qos = latched_qos() if topic == SUBJECT_TOPIC else input_qos(reliable)
            self.create_subscription(message_class(type_name), topic, self._callback(topic), qos)

    def _callback(self, topic: str):
        entry = self.counts[topic]

        def on_message(msg) -> None:
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            entry.count += 1
            entry.first_ns = stamp if entry.first_ns is None else min(entry.first_ns, stamp)
            entry.last_ns = stamp if entry.last_ns is None else max(entry.last_ns, stamp)
            entry.stamps.append(stamp)

        return on_message
