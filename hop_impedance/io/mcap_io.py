"""Read and write rosbag2-style MCAP (schema encoding ``ros2msg``, message encoding ``cdr``).

Reading decodes by the schema embedded in the file (``mcap_ros2``'s decoder),
so recordings made by any tool that follows the contract can be read. Writing
embeds the full ``.msg`` text of each type (:mod:`.message_definitions`).
Times are integer nanoseconds throughout.

Errors
------
All expected problems raise :class:`RecordingError` (a ``ValueError``) with a
one-line message: a missing file, a file that is not MCAP, an unknown topic.
A truncated file is *not* an error: the readable messages are returned and
:attr:`MessageStream.stopped_at` says where reading stopped.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcap.reader import NonSeekingReader, SeekingReader
from mcap.writer import CompressionType
from mcap.writer import Writer as _McapWriter
from mcap_ros2._dynamic import serialize_dynamic
from mcap_ros2.decoder import DecoderFactory

from hop_impedance.io.message_definitions import full_definition, schema_name

MCAP_MAGIC = b"\x89MCAP0\r\n"


class RecordingError(ValueError):
    """An expected problem with a recording file; the message is one line."""


@dataclass(frozen=True)
class DecodedMessage:
    """One message: topic, ``pkg/msg/Type`` schema name, log time (ns), decoded object."""

    topic: str
    schema_name: str
    log_time_ns: int
    publish_time_ns: int
    message: Any


@dataclass
class TopicInfo:
    """Per-topic summary: type, message count, first/last log time (ns)."""

    topic: str
    schema_name: str
    count: int
    first_ns: int
    last_ns: int

    @property
    def rate_hz(self) -> float:
        """Mean message rate over the topic's span (Hz); 0 for fewer than two messages."""
        span = (self.last_ns - self.first_ns) * 1e-9
        return (self.count - 1) / span if self.count > 1 and span > 0 else 0.0


def _check_file(path: str | Path) -> Path:
    p = Path(path)
    if not p.exists():
        raise RecordingError(f"{p}: no such file")
    if p.is_dir():
        metadata = sorted(p.glob("*.mcap"))
        if not metadata:
            raise RecordingError(f"{p}: is a folder without an .mcap file (expected a rosbag2 MCAP bag)")
        if len(metadata) > 1:
            raise RecordingError(f"{p}: holds {len(metadata)} .mcap files; name one")
        p = metadata[0]
    with open(p, "rb") as fh:
        head = fh.read(len(MCAP_MAGIC))
    if not head:
        raise RecordingError(f"{p}: is empty (0 bytes)")
    if head != MCAP_MAGIC:
        raise RecordingError(f"{p}: not an MCAP file (bad magic bytes; a ROS 1 bag or sqlite3 bag is not supported)")
    return p


class MessageStream:
    """Iterate the decoded messages of chosen topics in log-time order, reading to the break.

    Parameters
    ----------
    path : str or Path
        An ``.mcap`` file or a rosbag2 folder holding one.
    topics : iterable of str, optional
        Topics to read; None reads all. Asking for a topic the file does not
        have is not an error here (see :func:`summarize` to check first).
    decode : bool
        False yields the raw CDR bytes as ``message`` (replay, recorder copy).

    Attributes
    ----------
    stopped_at : str or None
        After iteration, a one-line note if the file ended early (truncated or
        corrupt), e.g. ``"truncated or corrupt: read 5120 messages, stopped after t=3.201 s of
        the recording (EndOfFile)"`` (t from the first message read).

    Notes
    -----
    A file with a valid summary is read chunk by chunk through its index (log-time
    order); one without (cut short, or still being written) front to back. Either
    way reading stops at the first damaged record, and every message before it is
    delivered: a file written by :class:`McapWriter` (chunks of at most 0.25 s)
    loses at most the chunk the damage is in.
    """

    def __init__(self, path: str | Path, topics: Iterable[str] | None = None, decode: bool = True):
        self.path = _check_file(path)
        self.topics = None if topics is None else list(topics)
        self.decode = decode
        self.stopped_at: str | None = None
        self.count = 0
        self.first_ns: int | None = None
        self.last_ns: int | None = None

    def __iter__(self) -> Iterator[DecodedMessage]:
        with open(self.path, "rb") as fh:
            reader: SeekingReader | NonSeekingReader
            try:
                reader = SeekingReader(fh, decoder_factories=[DecoderFactory()])
                summary = reader.get_summary()
            except Exception:  # noqa: BLE001 - any damage in the footer/summary: read front to back
                summary = None
            if summary is None or not summary.chunk_indexes and not summary.statistics:
                # No usable summary (truncated or streamed file): read front to back.
                fh.seek(0)
                reader = NonSeekingReader(fh, decoder_factories=[DecoderFactory()])
                ordered = False
            else:
                ordered = True
            yield from self._iterate(reader, ordered)

    def _iterate(self, reader, log_time_order: bool) -> Iterator[DecodedMessage]:
        try:
            if self.decode:
                it = reader.iter_decoded_messages(topics=self.topics, log_time_order=log_time_order)
            else:
                it = ((s, c, m, m.data) for s, c, m in reader.iter_messages(topics=self.topics, log_time_order=log_time_order))
            for schema, channel, message, decoded in it:
                self.count += 1
                self.first_ns = message.log_time if self.first_ns is None else self.first_ns
                self.last_ns = message.log_time
                yield DecodedMessage(channel.topic, schema.name if schema else "", message.log_time, message.publish_time,
                                     decoded)
        except GeneratorExit:
            raise
        except Exception as exc:  # noqa: BLE001 - damage can surface as any parser/decompressor error
            where = (f"after t={(self.last_ns - self.first_ns) * 1e-9:.3f} s of the recording"
                     if self.last_ns is not None and self.first_ns is not None else "before the first message")
            self.stopped_at = f"truncated or corrupt: read {self.count} messages, stopped {where} ({type(exc).__name__})"


def summarize(path: str | Path) -> list[TopicInfo]:
    """Topics of a recording with counts and time spans (read to the break of a damaged file)."""
    return read_summary(path)[0]


def read_summary(path: str | Path) -> tuple[list[TopicInfo], str | None]:
    """:func:`summarize` plus where reading stopped (None for an intact file)."""
    p = _check_file(path)
    counts: Counter[str] = Counter()
    first: dict[str, int] = {}
    last: dict[str, int] = {}
    names: dict[str, str] = {}
    stream = MessageStream(p, decode=False)
    for msg in stream:
        t = msg.topic
        counts[t] += 1
        first[t] = min(first.get(t, msg.log_time_ns), msg.log_time_ns)
        last[t] = max(last.get(t, msg.log_time_ns), msg.log_time_ns)
        names[t] = msg.schema_name
    infos = [TopicInfo(t, names[t], counts[t], first[t], last[t]) for t in sorted(counts)]
    return infos, stream.stopped_at


class McapWriter:
    """Write ROS 2 messages to a rosbag2-style MCAP file.

    Schemas and channels are registered on first use. Messages can be given as
    dicts / objects with the message's fields (encoded with ``mcap_ros2``) or as
    CDR bytes already serialised by rclpy (:meth:`write_serialized`).

    Chunks hold at most ``max_chunk_span_s`` of log time (default 0.25 s) and
    ``chunk_size`` bytes, so a file cut short (crash, full disk, copy
    interrupted) keeps every complete chunk: all but the last 0.25 s.
    :meth:`flush` ends the chunk in progress and pushes it to the disk (the
    recorder calls it every 0.5 s). The summary and index are written at
    :meth:`close`.

    Use as a context manager; :meth:`close` is safe to call twice.
    """

    def __init__(self, path: str | Path, compression: str = "zstd", chunk_size: int = 1 << 20,
                 max_chunk_span_s: float = 0.25):
        self.path = Path(path)
        if self.path.parent and not self.path.parent.exists():
            raise RecordingError(f"{self.path.parent}: output folder does not exist")
        self._fh = open(self.path, "wb")
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
        self._writer = _McapWriter(self._fh, chunk_size=chunk_size, compression=comp)
        self._writer.start(profile="ros2", library="hop_impedance")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._channel_types: dict[str, str] = {}
        self._encoders: dict[str, Any] = {}
        self._sequence: Counter[str] = Counter()
        self._closed = False
        self._span_ns = int(max_chunk_span_s * 1e9)
        self._chunk_lo: int | None = None  # log-time range of the chunk in progress
        self._chunk_hi: int | None = None

    def _channel(self, topic: str, type_name: str) -> int:
        name = schema_name(type_name)
        cid = self._channels.get(topic)
        if cid is not None:
            if self._channel_types[topic] != name:
                raise RecordingError(f"topic {topic} already written with type {self._channel_types[topic]}, not {name}")
            return cid
        if name not in self._schemas:
            self._schemas[name] = self._writer.register_schema(name, "ros2msg", full_definition(name).encode())
        cid = self._writer.register_channel(topic=topic, message_encoding="cdr", schema_id=self._schemas[name])
        self._channels[topic] = cid
        self._channel_types[topic] = name
        return cid

    def _encoder(self, type_name: str):
        name = schema_name(type_name)
        enc = self._encoders.get(name)
        if enc is None:
            enc = serialize_dynamic(name, full_definition(name))[name]
            self._encoders[name] = enc
        return enc

    def write(self, topic: str, type_name: str, message: Any, log_time_ns: int, publish_time_ns: int | None = None) -> None:
        """Encode and write one message (fields as a dict or attributes)."""
        self.write_serialized(topic, type_name, self._encoder(type_name)(message), log_time_ns, publish_time_ns)

    def write_serialized(self, topic: str, type_name: str, data: bytes, log_time_ns: int,
                         publish_time_ns: int | None = None) -> None:
        """Write one message already serialised as CDR (e.g. by ``rclpy.serialization``)."""
        cid = self._channel(topic, type_name)
        t = int(log_time_ns)
        if self._chunk_lo is not None and self._chunk_hi is not None and \
                max(self._chunk_hi, t) - min(self._chunk_lo, t) > self._span_ns:
            self.flush()
        self._chunk_lo = t if self._chunk_lo is None else min(self._chunk_lo, t)
        self._chunk_hi = t if self._chunk_hi is None else max(self._chunk_hi, t)
        seq = self._sequence[topic]
        self._sequence[topic] += 1
        self._writer.add_message(
            channel_id=cid,
            log_time=int(log_time_ns),
            publish_time=int(log_time_ns if publish_time_ns is None else publish_time_ns),
            sequence=seq,
            data=data,
        )

    def flush(self) -> None:
        """End the chunk in progress and write it to the file (readable even if the process dies next)."""
        if not self._closed:
            self._writer.flush()
            self._chunk_lo = self._chunk_hi = None

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """Attach a metadata record (string key/values)."""
        self._writer.add_metadata(name, {str(k): str(v) for k, v in data.items()})

    def close(self) -> None:
        """Finish the file (writes the summary and index)."""
        if not self._closed:
            self._writer.finish()
            self._fh.close()
            self._closed = True

    def __enter__(self) -> McapWriter:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def now_ns() -> int:
    """Wall-clock time (ns since the Unix epoch)."""
    return time.time_ns()
