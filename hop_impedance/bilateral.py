"""Contract v2 (docs/contract_v2.md): both legs' markers and one wrench per plate, in memory and in MCAP.

A v2 recording is a v1 recording plus what v1 sums or drops away:

- ``recording`` is the v1 view, unchanged: the summed plate on
  ``/force_plate/wrench`` and the right side's six markers under the v1 names
  (``toe`` ... ``head``). Every v1 consumer reads a v2 file as v1.
- ``plates``: per side (``"left"``, ``"right"``) the wrench of that foot's
  plate(s) on ``/force_plate/<side>/wrench``, in the contract frame and
  **about the contract origin** (the same point as the summed topic), so the
  summed wrench is exactly their sum.
- ``left_markers``: the left leg's markers, published on ``/mocap/markers``
  in the same message as the v1 six under the names ``toe_l``, ``heel_l``,
  ``ankle_l``, ``knee_l``, ``hip_l``; ``head`` is shared (one HAT). In memory
  they are a v1 :class:`MarkerSeries` (names ``toe`` ... ``head``) so the
  v1 analysis runs on either leg unchanged.

Reading a v1 file with :func:`load_bilateral` gives a recording with no plates
and no left markers: the lumped analysis is then the only one possible.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hop_impedance.recording import (
    FORCE_TOPIC,
    MARKER_NAMES,
    MARKER_TOPIC,
    WRENCH_TYPE,
    ForcePlateSeries,
    MarkerSeries,
    Recording,
)

SIDES: tuple[str, str] = ("left", "right")

#: v2 per-plate topics (geometry_msgs/msg/WrenchStamped, like the v1 summed topic).
PLATE_TOPICS: dict[str, str] = {side: f"/force_plate/{side}/wrench" for side in SIDES}

#: Left-leg marker names on ``/mocap/markers`` (the right leg keeps the v1 names; ``head`` is shared).
LEFT_MARKER_NAMES: tuple[str, ...] = tuple(f"{n}_l" for n in MARKER_NAMES if n != "head")

#: Every marker name of a v2 ``/mocap/markers`` message, in order.
V2_MARKER_NAMES: tuple[str, ...] = MARKER_NAMES + LEFT_MARKER_NAMES

#: Accepted right-leg aliases (``toe_r`` ... ``hip_r``) for recordings that name both sides explicitly.
RIGHT_ALIASES: dict[str, str] = {f"{n}_r": n for n in MARKER_NAMES if n != "head"}


@dataclass
class BilateralRecording:
    """A contract v2 recording (see the module docstring).

    Attributes
    ----------
    recording : Recording
        The v1 view: summed plate, right-side markers under the v1 names.
    plates : dict
        side -> :class:`ForcePlateSeries` about the contract origin, on the
        summed plate's stamps; empty for a v1 recording.
    left_markers : MarkerSeries or None
        The left leg's six markers under the v1 names (``head`` shared), on the
        right side's stamps; None for a v1 recording.
    """

    recording: Recording
    plates: dict[str, ForcePlateSeries] = field(default_factory=dict)
    left_markers: MarkerSeries | None = None

    @property
    def is_bilateral(self) -> bool:
        """Both plates and both legs' markers are present (per-leg analysis possible)."""
        return set(self.plates) == set(SIDES) and self.left_markers is not None

    def markers(self, side: str) -> MarkerSeries | None:
        """The six v1-named markers of one leg."""
        _check_side(side)
        return self.recording.markers if side == "right" else self.left_markers

    def leg(self, side: str) -> Recording:
        """A v1 :class:`Recording` of one leg: that foot's plate and that leg's markers.

        The v1 analysis (stance detection, kinematics, inverse dynamics) runs on
        it unchanged; with a per-leg body model it is the per-leg analysis
        (:mod:`hop_impedance.biomech.per_leg`).
        """
        _check_side(side)
        if side not in self.plates:
            raise ValueError(f"{self.recording.source or 'recording'}: no {PLATE_TOPICS[side]} data (a contract v1 recording?)")
        rec = self.recording
        warnings = [w for w in rec.warnings] + [f"{side} leg: {PLATE_TOPICS[side]} and the {side} leg's markers"]
        return Recording(self.plates[side], self.markers(side), rec.subject, f"{rec.source} [{side} leg]", warnings)

    def summed_plate_mismatch_n(self) -> float:
        """Largest |sum of the per-plate forces - summed plate force| (N): 0 for a consistent v2 recording."""
        if not self.plates:
            return 0.0
        total = sum(p.force_n for p in self.plates.values())
        return float(np.max(np.abs(total - self.recording.force.force_n)))


def _check_side(side: str) -> None:
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, got {side!r}")


def sum_plates(plates: dict[str, ForcePlateSeries]) -> ForcePlateSeries:
    """The v1 summed plate of per-side plates given about the same origin on the same stamps."""
    series = list(plates.values())
    stamps = series[0].stamp_ns
    for p in series[1:]:
        if p.stamp_ns.shape != stamps.shape or np.any(p.stamp_ns != stamps):
            raise ValueError("per-plate series must share their stamps to be summed")
    force = sum((p.force_n for p in series[1:]), series[0].force_n.copy())
    torque = sum((p.torque_nm for p in series[1:]), series[0].torque_nm.copy())
    return ForcePlateSeries(stamps.copy(), force, torque)


# -- MCAP ----------------------------------------------------------------------


def save_bilateral(path: str | Path, bilateral: BilateralRecording, compression: str = "zstd") -> None:
    """Write a v2 MCAP file: the v1 topics (markers with the left names added) plus one wrench topic per plate."""
    from hop_impedance.io.mcap_io import McapWriter
    from hop_impedance.io.recording_io import FORCE_FRAME_ID, write_recording_messages

    rec = bilateral.recording
    v1 = rec
    if bilateral.left_markers is not None and rec.markers is not None:
        right, left = rec.markers, bilateral.left_markers
        if right.stamp_ns.shape != left.stamp_ns.shape or np.any(right.stamp_ns != left.stamp_ns):
            raise ValueError("left and right markers must share their stamps (one /mocap/markers message per frame)")
        legs = [MARKER_NAMES.index(n[:-2]) for n in LEFT_MARKER_NAMES]
        positions = np.concatenate([right.positions_m, left.positions_m[:, legs]], axis=1)
        v1 = Recording(rec.force, MarkerSeries(right.stamp_ns, V2_MARKER_NAMES, positions), rec.subject, rec.source, rec.warnings)
    with McapWriter(path, compression=compression) as writer:
        write_recording_messages(writer, v1)
        for side, plate in bilateral.plates.items():
            for i, t in enumerate(plate.stamp_ns):
                message = _wrench_message(int(t), FORCE_FRAME_ID, plate.force_n[i], plate.torque_nm[i])
                writer.write(PLATE_TOPICS[side], WRENCH_TYPE, message, int(t))


def _wrench_message(stamp_ns: int, frame_id: str, force: np.ndarray, torque: np.ndarray) -> dict:
    """A WrenchStamped as the dict McapWriter encodes (same fields as the v1 summed topic)."""
    return {
        "header": {"stamp": {"sec": stamp_ns // 1_000_000_000, "nanosec": stamp_ns % 1_000_000_000}, "frame_id": frame_id},
        "wrench": {"force": dict(zip("xyz", map(float, force))), "torque": dict(zip("xyz", map(float, torque)))},
    }


def load_bilateral(path: str | Path, **options) -> BilateralRecording:
    """Read a v2 (or v1) MCAP file.

    The v1 part is read by :func:`hop_impedance.io.recording_io.load_recording`
    (``options`` are passed to it) with all its checks; then the per-plate
    topics and the left-leg marker names, if present. Per-plate samples are
    sorted by stamp and kept on the summed plate's stamps (a stamp missing on
    one plate is an error naming the topic).
    """
    from hop_impedance.input_checks import order_by_stamp
    from hop_impedance.io.mcap_io import MessageStream
    from hop_impedance.io.recording_io import load_recording

    rec = load_recording(path, **options)
    stream = MessageStream(path, topics=[*PLATE_TOPICS.values(), MARKER_TOPIC])
    plate_rows: dict[str, tuple[list[int], list[tuple[float, ...]]]] = {s: ([], []) for s in SIDES}
    left_stamps: list[int] = []
    left_pos: list[np.ndarray] = []
    names_cols: tuple[list[str], list[int] | None] = ([], None)
    for msg in stream:
        m = msg.message
        stamp = int(m.header.stamp.sec) * 1_000_000_000 + int(m.header.stamp.nanosec)
        if msg.topic == MARKER_TOPIC:
            names = list(m.names)
            if names != names_cols[0]:
                names_cols = (names, _left_columns(names))
            cols = names_cols[1]
            if cols is None or len(m.positions) != len(names):
                continue
            xyz = np.array([(p.x, p.y, p.z) for p in m.positions], dtype=float)
            left_stamps.append(stamp)
            left_pos.append(xyz[cols])
        else:
            side = next(s for s, topic in PLATE_TOPICS.items() if topic == msg.topic)
            f, t = m.wrench.force, m.wrench.torque
            plate_rows[side][0].append(stamp)
            plate_rows[side][1].append((f.x, f.y, f.z, t.x, t.y, t.z))
    plates = {}
    for side, (stamps, vals) in plate_rows.items():
        if not stamps:
            continue
        s, v = np.array(stamps, np.int64), np.array(vals, float)
        idx = order_by_stamp(s, PLATE_TOPICS[side], rec.warnings)
        s, v = s[idx], v[idx]
        if s.shape != rec.force.stamp_ns.shape or np.any(s != rec.force.stamp_ns):
            raise ValueError(f"{path}: {PLATE_TOPICS[side]} stamps differ from {FORCE_TOPIC}'s; "
                             "contract v2 publishes them together")
        plates[side] = ForcePlateSeries(s, v[:, :3].copy(), v[:, 3:].copy())
    left = None
    if left_stamps and rec.markers is not None:
        s = np.array(left_stamps, np.int64)
        idx = order_by_stamp(s, MARKER_TOPIC + " (left leg)", [])
        left = MarkerSeries(s[idx], MARKER_NAMES, np.stack(left_pos)[idx])
        if left.stamp_ns.shape != rec.markers.stamp_ns.shape or np.any(left.stamp_ns != rec.markers.stamp_ns):
            left = None
            rec.warnings.append(f"{MARKER_TOPIC}: left-leg markers not in every frame; the left leg's analysis is not possible")
    return BilateralRecording(rec, plates, left)


def leg_marker_names(side: str) -> tuple[str, ...]:
    """The names on a v2 ``/mocap/markers`` message of one leg's six markers, in :data:`MARKER_NAMES` order
    (the right leg keeps the v1 names, the left has ``_l``; ``head`` is shared)."""
    _check_side(side)
    return MARKER_NAMES if side == "right" else (*LEFT_MARKER_NAMES, "head")


def _left_columns(names: list[str]) -> list[int] | None:
    """Columns of toe_l, heel_l, ankle_l, knee_l, hip_l, head (v1 order) in a message's names; None if any is missing."""
    wanted = leg_marker_names("left")
    if not all(n in names for n in wanted):
        return None
    return [names.index(n) for n in wanted]
