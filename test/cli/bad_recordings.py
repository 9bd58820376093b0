"""Bad recordings built from a bundled one, the ways real lab data go wrong (issue 14's table).

Each helper takes the loaded bundled :class:`Recording` and writes a changed
copy with the project's writer, so the tests exercise the same readers a user's
file would.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from hop_impedance.io.mcap_io import McapWriter
from hop_impedance.io.recording_io import (
    MARKER_TYPE,
    SUBJECT_TYPE,
    WRENCH_TYPE,
    _header,
    load_recording,
    save_recording,
    write_recording_messages,
)
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC, ForcePlateSeries, MarkerSeries

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = ROOT / "recordings" / "sim_2p20hz_hard.mcap"


def bundled(seconds: float | None = None):
    """The bundled 2.20 Hz recording, optionally only its first ``seconds``."""
    rec = load_recording(BUNDLED)
    if seconds is None:
        return rec
    end = rec.start_ns + int(seconds * 1e9)
    return keep(rec, lambda t: t < end)


def keep(rec, predicate):
    """Only the samples whose stamp satisfies ``predicate(stamp_ns_array)``."""
    f, m = rec.force, rec.markers
    kf = predicate(f.stamp_ns)
    force = ForcePlateSeries(f.stamp_ns[kf], f.force_n[kf], f.torque_nm[kf])
    markers = None
    if m is not None:
        km = predicate(m.stamp_ns)
        markers = MarkerSeries(m.stamp_ns[km], m.names, m.positions_m[km])
    return replace(rec, force=force, markers=markers)


def plate_sign(rec):
    """Force and moment as the plate feels them (z down): the negated wrench."""
    f = rec.force
    return replace(rec, force=ForcePlateSeries(f.stamp_ns, -f.force_n, -f.torque_nm))


def millimetres(rec):
    m = rec.markers
    return replace(rec, markers=MarkerSeries(m.stamp_ns, m.names, m.positions_m * 1000.0))


def upper_case_names(rec):
    m = rec.markers
    return replace(rec, markers=MarkerSeries(m.stamp_ns, tuple(n.upper() for n in m.names), m.positions_m))


def no_subject(rec):
    return replace(rec, subject=None)


def force_only(rec):
    return replace(rec, markers=None)


def duplicates(rec, fraction: float = 0.1, seed: int = 0):
    """Every stream with ``fraction`` of its messages written twice (seeded)."""
    rng = np.random.default_rng(seed)

    def dup(n):
        extra = rng.choice(n, int(fraction * n), replace=False)
        return np.sort(np.concatenate([np.arange(n), extra]))

    f, m = rec.force, rec.markers
    i, j = dup(len(f)), dup(len(m))
    return replace(rec, force=ForcePlateSeries(f.stamp_ns[i], f.force_n[i], f.torque_nm[i]),
                   markers=MarkerSeries(m.stamp_ns[j], m.names, m.positions_m[j]))


def gap(rec, start_s: float, length_s: float, force: bool = True, markers: bool = True):
    """Remove ``length_s`` of samples starting ``start_s`` after the first sample."""
    a = rec.start_ns + int(start_s * 1e9)
    b = a + int(length_s * 1e9)
    f, m = rec.force, rec.markers
    kf = ~((f.stamp_ns >= a) & (f.stamp_ns < b)) if force else np.ones(len(f), bool)
    out = replace(rec, force=ForcePlateSeries(f.stamp_ns[kf], f.force_n[kf], f.torque_nm[kf]))
    if m is not None and markers:
        km = ~((m.stamp_ns >= a) & (m.stamp_ns < b))
        out = replace(out, markers=MarkerSeries(m.stamp_ns[km], m.names, m.positions_m[km]))
    return out


def write(path, rec) -> Path:
    save_recording(path, rec)
    return Path(path)


def write_late_block(path, rec, start_s: float, length_s: float) -> Path:
    """The messages stamped in ``[start, start + length)`` written after all others (log time = end of file)."""
    a = rec.start_ns + int(start_s * 1e9)
    b = a + int(length_s * 1e9)
    inside = keep(rec, lambda t: (t >= a) & (t < b))
    outside = keep(rec, lambda t: (t < a) | (t >= b))
    late_ns = int(max(rec.force.stamp_ns[-1], rec.markers.stamp_ns[-1])) + 1_000_000
    with McapWriter(path) as w:
        write_recording_messages(w, outside)
        for k, t in enumerate(inside.force.stamp_ns):
            fx, fy, fz = (float(v) for v in inside.force.force_n[k])
            tx, ty, tz = (float(v) for v in inside.force.torque_nm[k])
            w.write(FORCE_TOPIC, WRENCH_TYPE, {"header": _header(int(t), "force_plate"), "wrench": {
                "force": {"x": fx, "y": fy, "z": fz}, "torque": {"x": tx, "y": ty, "z": tz}}}, late_ns + k)
        for k, t in enumerate(inside.markers.stamp_ns):
            pts = [{"x": float(p[0]), "y": float(p[1]), "z": float(p[2])} for p in inside.markers.positions_m[k]]
            w.write(MARKER_TOPIC, MARKER_TYPE, {"header": _header(int(t), "lab"), "names": list(inside.markers.names),
                                                "positions": pts}, late_ns + 10_000 + k)
    return Path(path)


def write_marker_only(path, rec) -> Path:
    """Markers and subject, no force plate."""
    with McapWriter(path) as w:
        s = rec.subject
        w.write(SUBJECT_TOPIC, SUBJECT_TYPE, {"header": _header(rec.start_ns, "lab"), "subject_id": s.subject_id,
                                              "body_mass": s.body_mass_kg, "body_height": s.body_height_m}, rec.start_ns)
        m = rec.markers
        for k, t in enumerate(m.stamp_ns):
            pts = [{"x": float(p[0]), "y": float(p[1]), "z": float(p[2])} for p in m.positions_m[k]]
            w.write(MARKER_TOPIC, MARKER_TYPE, {"header": _header(int(t), "lab"), "names": list(m.names), "positions": pts},
                    int(t))
    return Path(path)


def truncated(path, source: Path, fraction: float) -> Path:
    """The first ``fraction`` of ``source``'s bytes."""
    data = Path(source).read_bytes()
    Path(path).write_bytes(data[: int(len(data) * fraction)])
    return Path(path)
