"""Contract recordings <-> in-memory :class:`~hop_impedance.recording.Recording`.

:func:`load_recording` reads ``/force_plate/wrench``, ``/mocap/markers`` and
``/subject`` from a rosbag2-style MCAP file into arrays, checking what the
contract promises and saying clearly what is wrong:

- samples are ordered by ``header.stamp`` (the measurement instant); messages
  that arrived out of order are re-sorted and counted, exact duplicates dropped
  and counted, gaps longer than 1.5 sample periods counted as dropped samples;
- a truncated file yields what was readable plus a warning saying where it stopped;
- the contract checks of :mod:`hop_impedance.input_checks` (the same ones the
  live nodes run): missing contract markers, millimetres, the force on the
  plate instead of on the subject, implausible subject values raise
  :class:`~hop_impedance.input_checks.InputCheckError` naming the rule.

All warnings are collected in ``Recording.warnings`` (one line each).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hop_impedance.input_checks import InputChecks, order_by_stamp
from hop_impedance.io.mcap_io import McapWriter, MessageStream, RecordingError
from hop_impedance.recording import (
    FORCE_TOPIC,
    MARKER_NAMES,
    MARKER_TOPIC,
    MARKER_TYPE,
    SUBJECT_TOPIC,
    SUBJECT_TYPE,
    WRENCH_TYPE,
    ForcePlateSeries,
    MarkerSeries,
    Recording,
    Subject,
)

FORCE_FRAME_ID = "force_plate"
LAB_FRAME_ID = "lab"


def _stamp_ns(header) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _count_gaps(stamps: np.ndarray, label: str, warnings: list[str]) -> None:
    if len(stamps) < 3:
        return
    dt = np.diff(stamps)
    period = float(np.median(dt))
    big = dt > 1.5 * period
    if big.any():
        missing = int(np.sum(np.round(dt[big] / period) - 1))
        warnings.append(f"{label}: {missing} sample(s) missing in {int(big.sum())} gap(s) "
                        f"(nominal period {period * 1e-6:.2f} ms)")


def load_recording(path: str | Path, marker_map: dict[str, str] | None = None, require_markers: bool = False) -> Recording:
    """Read a contract recording.

    Parameters
    ----------
    path : str or Path
        ``.mcap`` file (or rosbag2 folder holding one).
    marker_map : dict, optional
        Contract marker name -> name used in the recording, for recordings
        that use other marker names.
    require_markers : bool
        Raise if the recording has no ``/mocap/markers`` (default: allow
        force-only recordings, which support stance detection only).

    Returns
    -------
    Recording
        Arrays sorted by measurement time; ``warnings`` lists what was repaired.

    Raises
    ------
    RecordingError
        Missing or non-MCAP file, no force-plate topic, missing markers,
        implausible units.
    """
    stream = MessageStream(path, topics=[FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC])
    checks = InputChecks(marker_map=marker_map)
    read = _read_contract_messages(stream, checks)
    warnings = _reading_warnings(stream, read)
    if not read.force_stamp_ns:
        raise RecordingError(f"{stream.path}: no {FORCE_TOPIC} messages (is this a hopping recording of contract v1?)")
    force = _force_series(np.array(read.force_stamp_ns, dtype=np.int64), np.array(read.force_values, dtype=float), warnings)
    markers = None
    if read.marker_stamp_ns:
        markers = _marker_series(np.array(read.marker_stamp_ns, dtype=np.int64), np.stack(read.marker_positions_m), warnings)
    elif require_markers:
        raise RecordingError(f"{stream.path}: no {MARKER_TOPIC} messages; joint angles and moments need markers")
    if read.subject is None:
        warnings.append(f"{SUBJECT_TOPIC}: missing; body mass and height must be given (e.g. --mass-kg, --height-m)")
    else:
        checks.set_subject(read.subject)
    check_recording(checks, force, markers)
    return Recording(force=force, markers=markers, subject=read.subject, source=str(stream.path), warnings=warnings)


@dataclass
class _ContractMessages:
    """The contract topics of one file as read, in arrival order (sorted later by stamp)."""

    force_stamp_ns: list[int] = field(default_factory=list)
    #: (fx, fy, fz, tx, ty, tz) per wrench message (N, N m)
    force_values: list[tuple[float, ...]] = field(default_factory=list)
    marker_stamp_ns: list[int] = field(default_factory=list)
    #: (6, 3) contract markers per frame (m), columns picked by the marker names
    marker_positions_m: list[np.ndarray] = field(default_factory=list)
    #: the first ``/subject`` message; later ones are ignored
    subject: Subject | None = None
    #: marker frames whose names and positions differ in length (skipped)
    n_bad_marker_frames: int = 0


def _read_contract_messages(stream: MessageStream, checks: InputChecks) -> _ContractMessages:
    """Decode every wrench, marker and subject message of ``stream``.

    The marker names of each frame go through ``checks`` (missing contract
    markers raise :class:`~hop_impedance.input_checks.InputCheckError` at once).
    """
    read = _ContractMessages()
    marker_cols: list[int] | None = None
    for msg in stream:
        m = msg.message
        if msg.topic == FORCE_TOPIC:
            f, t = m.wrench.force, m.wrench.torque
            read.force_stamp_ns.append(_stamp_ns(m.header))
            read.force_values.append((f.x, f.y, f.z, t.x, t.y, t.z))
        elif msg.topic == MARKER_TOPIC:
            names = list(m.names)
            marker_cols = checks.marker_names(names)
            checks.raise_if_failed()
            if len(m.positions) != len(names):
                read.n_bad_marker_frames += 1
                continue
            xyz = np.array([(p.x, p.y, p.z) for p in m.positions], dtype=float)
            read.marker_stamp_ns.append(_stamp_ns(m.header))
            read.marker_positions_m.append(xyz[marker_cols])
        elif msg.topic == SUBJECT_TOPIC and read.subject is None:
            read.subject = Subject(str(m.subject_id), float(m.body_mass), float(m.body_height))
    return read


def _reading_warnings(stream: MessageStream, read: _ContractMessages) -> list[str]:
    """What went wrong while reading: where a truncated file stopped, skipped malformed marker frames."""
    warnings: list[str] = []
    if stream.stopped_at:
        warnings.append(f"{stream.path.name}: {stream.stopped_at}")
    if read.n_bad_marker_frames:
        warnings.append(f"{MARKER_TOPIC}: {read.n_bad_marker_frames} frame(s) with names/positions of different lengths skipped")
    return warnings


def _force_series(stamps: np.ndarray, vals: np.ndarray, warnings: list[str]) -> ForcePlateSeries:
    idx = order_by_stamp(stamps, FORCE_TOPIC, warnings)
    _count_gaps(stamps[idx], FORCE_TOPIC, warnings)
    return ForcePlateSeries(stamps[idx], vals[idx, :3].copy(), vals[idx, 3:].copy())


def _marker_series(stamps: np.ndarray, pos: np.ndarray, warnings: list[str]) -> MarkerSeries:
    idx = order_by_stamp(stamps, MARKER_TOPIC, warnings)
    _count_gaps(stamps[idx], MARKER_TOPIC, warnings)
    return MarkerSeries(stamps[idx], MARKER_NAMES, pos[idx])


def check_recording(checks: InputChecks, force: ForcePlateSeries, markers: MarkerSeries | None) -> None:
    """Run the shared contract checks (:mod:`hop_impedance.input_checks`) on loaded arrays; raise on a failure.

    ``checks`` already holds the subject and marker names; the streams are fed
    in stamp order, as the live nodes see them after their reorder buffers.
    """
    checks.force(force.stamp_ns, force.force_n[:, 2])
    if markers is not None:
        checks.markers(markers.stamp_ns, markers.positions_m)
    checks.raise_if_failed()


def save_recording(path: str | Path, recording: Recording, compression: str = "zstd", chunk_size: int = 1 << 20) -> None:
    """Write a Recording as a contract MCAP file.

    ``/subject`` is written first (log time = first sample), then wrench and
    marker messages with log time = publish time = ``header.stamp``.
    ``chunk_size`` (bytes, before compression) bounds what a crash mid-write
    can lose: a truncated file keeps every complete chunk.
    """
    with McapWriter(path, compression=compression, chunk_size=chunk_size) as writer:
        write_recording_messages(writer, recording)


def write_recording_messages(writer: McapWriter, recording: Recording) -> None:
    """Write a Recording's contract topics into an open writer (see :func:`save_recording`)."""
    start = recording.start_ns
    if recording.subject is not None:
        s = recording.subject
        writer.write(
            SUBJECT_TOPIC,
            SUBJECT_TYPE,
            {"header": _header(start, LAB_FRAME_ID), "subject_id": s.subject_id, "body_mass": s.body_mass_kg,
             "body_height": s.body_height_m},
            start,
        )
    events = [(int(t), 0, i) for i, t in enumerate(recording.force.stamp_ns)]
    if recording.markers is not None:
        events += [(int(t), 1, i) for i, t in enumerate(recording.markers.stamp_ns)]
    events.sort()
    f = recording.force
    for t, kind, i in events:
        if kind == 0:
            fx, fy, fz = (float(v) for v in f.force_n[i])
            tx, ty, tz = (float(v) for v in f.torque_nm[i])
            msg = {
                "header": _header(t, FORCE_FRAME_ID),
                "wrench": {"force": {"x": fx, "y": fy, "z": fz}, "torque": {"x": tx, "y": ty, "z": tz}},
            }
            writer.write(FORCE_TOPIC, WRENCH_TYPE, msg, t)
        else:
            mk = recording.markers
            assert mk is not None  # marker events are only made when there are markers (above)
            pts = [{"x": float(p[0]), "y": float(p[1]), "z": float(p[2])} for p in mk.positions_m[i]]
            writer.write(MARKER_TOPIC, MARKER_TYPE,
                         {"header": _header(t, LAB_FRAME_ID), "names": list(mk.names), "positions": pts}, t)


def _header(stamp_ns: int, frame_id: str) -> dict:
    return {"stamp": {"sec": int(stamp_ns // 1_000_000_000), "nanosec": int(stamp_ns % 1_000_000_000)}, "frame_id": frame_id}
