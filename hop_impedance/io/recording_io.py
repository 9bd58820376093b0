"""Contract recordings <-> in-memory :class:`~hop_impedance.recording.Recording`.

:func:`load_recording` reads ``/force_plate/wrench``, ``/mocap/markers`` and
``/subject`` from a rosbag2-style MCAP file into arrays, checking what the
contract promises and saying clearly what is wrong:

- samples are ordered by ``header.stamp`` (the measurement instant); messages
  that arrived out of order are re-sorted and counted, exact duplicates dropped
  and counted, gaps longer than 1.5 sample periods counted as dropped samples;
- a truncated file yields what was readable plus a warning saying where it stopped;
- missing contract markers (after an optional name mapping) raise an error naming them;
- markers that look like millimetres, and forces that look like the force on
  the plate instead of on the subject, raise errors that say so.

All warnings are collected in ``Recording.warnings`` (one line each).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hop_impedance.io.mcap_io import McapWriter, MessageStream, RecordingError
from hop_impedance.recording import (
    FORCE_TOPIC,
    MARKER_NAMES,
    MARKER_TOPIC,
    SUBJECT_TOPIC,
    ForcePlateSeries,
    MarkerSeries,
    Recording,
    Subject,
)

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
MARKER_TYPE = "hop_impedance_msgs/msg/MarkerArray"
SUBJECT_TYPE = "hop_impedance_msgs/msg/SubjectInfo"

FORCE_FRAME_ID = "force_plate"
LAB_FRAME_ID = "lab"


def _stamp_ns(header) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _order_by_stamp(stamps: np.ndarray, label: str, warnings: list[str]) -> np.ndarray:
    """Indices that sort samples by stamp and drop exact duplicates; notes what was done."""
    order = np.argsort(stamps, kind="stable")
    n_out_of_order = int(np.count_nonzero(np.diff(stamps) < 0))
    if n_out_of_order:
        warnings.append(f"{label}: {n_out_of_order} message(s) arrived out of order; re-sorted by header.stamp")
    sorted_stamps = stamps[order]
    keep = np.concatenate([[True], np.diff(sorted_stamps) > 0]) if len(order) else np.zeros(0, bool)
    n_dup = int(np.count_nonzero(~keep))
    if n_dup:
        warnings.append(f"{label}: {n_dup} message(s) with a repeated header.stamp dropped")
    return order[keep]


def _count_gaps(stamps: np.ndarray, label: str, warnings: list[str]) -> None:
    if len(stamps) < 3:
        return
    dt = np.diff(stamps)
    period = float(np.median(dt))
    big = dt > 1.5 * period
    if big.any():
        missing = int(np.sum(np.round(dt[big] / period) - 1))
        warnings.append(f"{label}: {missing} sample(s) missing in {int(big.sum())} gap(s) (nominal period {period * 1e-6:.2f} ms)")


def _marker_columns(names: list[str], wanted: dict[str, str]) -> list[int]:
    missing = [f"{contract} (as {name!r})" if contract != name else contract for contract, name in wanted.items() if name not in names]
    if missing:
        raise RecordingError(
            f"{MARKER_TOPIC}: missing marker(s) {', '.join(missing)}; the recording has {names}. "
            "Give a mapping (--marker-map) if the names differ."
        )
    return [names.index(wanted[c]) for c in MARKER_NAMES]


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
    f_stamp: list[int] = []
    f_vals: list[tuple[float, ...]] = []
    m_stamp: list[int] = []
    m_pos: list[np.ndarray] = []
    subject: Subject | None = None
    marker_cols: list[int] | None = None
    marker_names: list[str] | None = None
    wanted = {name: (marker_map or {}).get(name, name) for name in MARKER_NAMES}
    warnings: list[str] = []
    n_bad_marker_frames = 0
    for msg in stream:
        m = msg.message
        if msg.topic == FORCE_TOPIC:
            f, t = m.wrench.force, m.wrench.torque
            f_stamp.append(_stamp_ns(m.header))
            f_vals.append((f.x, f.y, f.z, t.x, t.y, t.z))
        elif msg.topic == MARKER_TOPIC:
            names = list(m.names)
            if names != marker_names:
                marker_cols = _marker_columns(names, wanted)
                marker_names = names
            if len(m.positions) != len(names):
                n_bad_marker_frames += 1
                continue
            xyz = np.array([(p.x, p.y, p.z) for p in m.positions], dtype=float)
            m_stamp.append(_stamp_ns(m.header))
            m_pos.append(xyz[marker_cols])
        elif msg.topic == SUBJECT_TOPIC and subject is None:
            subject = Subject(str(m.subject_id), float(m.body_mass), float(m.body_height))
    if stream.stopped_at:
        warnings.append(f"{stream.path.name}: {stream.stopped_at}")
    if n_bad_marker_frames:
        warnings.append(f"{MARKER_TOPIC}: {n_bad_marker_frames} frame(s) with names/positions of different lengths skipped")
    if not f_stamp:
        raise RecordingError(f"{stream.path}: no {FORCE_TOPIC} messages (is this a hopping recording of contract v1?)")
    force = _force_series(np.array(f_stamp, dtype=np.int64), np.array(f_vals, dtype=float), warnings)
    markers = None
    if m_stamp:
        markers = _marker_series(np.array(m_stamp, dtype=np.int64), np.stack(m_pos), warnings)
    elif require_markers:
        raise RecordingError(f"{stream.path}: no {MARKER_TOPIC} messages; joint angles and moments need markers")
    if subject is None:
        warnings.append(f"{SUBJECT_TOPIC}: missing; body mass and height must be given (e.g. --mass, --height)")
    else:
        _check_subject(subject)
    _check_force_units(force, subject)
    return Recording(force=force, markers=markers, subject=subject, source=str(stream.path), warnings=warnings)


def _force_series(stamps: np.ndarray, vals: np.ndarray, warnings: list[str]) -> ForcePlateSeries:
    idx = _order_by_stamp(stamps, FORCE_TOPIC, warnings)
    _count_gaps(stamps[idx], FORCE_TOPIC, warnings)
    return ForcePlateSeries(stamps[idx], vals[idx, :3].copy(), vals[idx, 3:].copy())


def _marker_series(stamps: np.ndarray, pos: np.ndarray, warnings: list[str]) -> MarkerSeries:
    idx = _order_by_stamp(stamps, MARKER_TOPIC, warnings)
    _count_gaps(stamps[idx], MARKER_TOPIC, warnings)
    pos = pos[idx]
    finite = pos[np.isfinite(pos)]
    if finite.size and np.nanmedian(np.abs(finite)) > 20.0:
        raise RecordingError(
            f"{MARKER_TOPIC}: marker coordinates have a median magnitude of {np.nanmedian(np.abs(finite)):.0f}; "
            "they look like millimetres, but the contract says metres"
        )
    return MarkerSeries(stamps[idx], MARKER_NAMES, pos)


def _check_subject(subject: Subject) -> None:
    if not 10.0 <= subject.body_mass_kg <= 300.0:
        raise RecordingError(f"{SUBJECT_TOPIC}: body_mass {subject.body_mass_kg} kg is implausible (contract: kg)")
    if not 0.5 <= subject.body_height_m <= 2.6:
        raise RecordingError(f"{SUBJECT_TOPIC}: body_height {subject.body_height_m} m is implausible (contract: m)")


def _check_force_units(force: ForcePlateSeries, subject: Subject | None) -> None:
    fz = force.force_n[:, 2]
    if not len(fz):
        return
    lo, hi = np.percentile(fz, [1, 99])
    if -lo > 5 * max(hi, 1.0) and -lo > 100:
        raise RecordingError(
            f"{FORCE_TOPIC}: force.z is mostly negative (down to {lo:.0f} N); the contract wants the force on "
            "the subject (z up), this looks like the force on the plate"
        )
    if subject is not None and hi > 40 * subject.body_weight_n:
        raise RecordingError(
            f"{FORCE_TOPIC}: force.z reaches {hi:.0f} N, {hi / subject.body_weight_n:.0f} body weights; "
            "not newtons?"
        )


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
            {"header": _header(start, LAB_FRAME_ID), "subject_id": s.subject_id, "body_mass": s.body_mass_kg, "body_height": s.body_height_m},
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
            pts = [{"x": float(p[0]), "y": float(p[1]), "z": float(p[2])} for p in mk.positions_m[i]]
            writer.write(MARKER_TOPIC, MARKER_TYPE, {"header": _header(t, LAB_FRAME_ID), "names": list(mk.names), "positions": pts}, t)


def _header(stamp_ns: int, frame_id: str) -> dict:
    return {"stamp": {"sec": int(stamp_ns // 1_000_000_000), "nanosec": int(stamp_ns % 1_000_000_000)}, "frame_id": frame_id}
