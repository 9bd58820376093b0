"""Recording I/O: round trip, repairs, and the expected-problem messages."""

import numpy as np
import pytest

from hop_impedance.io.mcap_io import McapWriter, MessageStream, RecordingError, summarize
from hop_impedance.io.recording_io import load_recording, save_recording
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

T0 = 1_700_000_000_000_000_000


def make_recording(seconds=2.0, force_hz=1000, marker_hz=100, seed=0):
    rng = np.random.default_rng(seed)
    nf, nm = int(seconds * force_hz), int(seconds * marker_hz)
    tf = T0 + np.arange(nf, dtype=np.int64) * (1_000_000_000 // force_hz)
    tm = T0 + np.arange(nm, dtype=np.int64) * (1_000_000_000 // marker_hz)
    force = rng.normal(0, 5, (nf, 3))
    force[:, 2] += 800 * np.clip(np.sin(2 * np.pi * 2 * np.arange(nf) / force_hz), 0, None)
    torque = rng.normal(0, 1, (nf, 3))
    pos = rng.normal(0.5, 0.3, (nm, 6, 3))
    pos[5, 2] = np.nan  # an occluded marker
    return Recording(
        ForcePlateSeries(tf, force, torque),
        MarkerSeries(tm, MARKER_NAMES, pos),
        Subject("s01", 54.8, 1.63),
    )


def test_round_trip_is_exact(tmp_path):
    rec = make_recording()
    path = tmp_path / "rec.mcap"
    save_recording(path, rec)
    back = load_recording(path)
    assert back.warnings == []
    np.testing.assert_array_equal(back.force.stamp_ns, rec.force.stamp_ns)
    np.testing.assert_array_equal(back.force.force_n, rec.force.force_n)
    np.testing.assert_array_equal(back.force.torque_nm, rec.force.torque_nm)
    np.testing.assert_array_equal(back.markers.stamp_ns, rec.markers.stamp_ns)
    np.testing.assert_array_equal(back.markers.positions_m, rec.markers.positions_m)  # NaN == NaN here
    assert back.subject == rec.subject


def test_summary_counts_and_rates(tmp_path):
    path = tmp_path / "rec.mcap"
    save_recording(path, make_recording(seconds=3.0))
    info = {t.topic: t for t in summarize(path)}
    assert info[FORCE_TOPIC].count == 3000 and info[MARKER_TOPIC].count == 300 and info[SUBJECT_TOPIC].count == 1
    assert info[FORCE_TOPIC].rate_hz == pytest.approx(1000.0, rel=1e-6)
    assert info[MARKER_TOPIC].rate_hz == pytest.approx(100.0, rel=1e-6)
    assert info[FORCE_TOPIC].schema_name == "geometry_msgs/msg/WrenchStamped"


def _write_raw(path, rec, order):
    """Write the force messages in a given order (to fake out-of-order arrival)."""
    with McapWriter(path) as w:
        for i in order:
            t = int(rec.force.stamp_ns[i])
            f, m = rec.force.force_n[i], rec.force.torque_nm[i]
            w.write(FORCE_TOPIC, "geometry_msgs/msg/WrenchStamped", {
                "header": {"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "frame_id": "force_plate"},
                "wrench": {"force": dict(zip("xyz", map(float, f))), "torque": dict(zip("xyz", map(float, m)))},
            }, T0 + len(order))  # identical log times: only header.stamp orders them


def test_out_of_order_duplicates_and_gaps_are_repaired_and_counted(tmp_path):
    rec = make_recording(seconds=0.2)
    order = list(range(200))
    order[10], order[11] = order[11], order[10]  # swapped pair
    order.insert(50, 50)  # a duplicate
    del order[120:125]  # five dropped samples
    path = tmp_path / "messy.mcap"
    _write_raw(path, rec, order)
    back = load_recording(path)
    assert np.all(np.diff(back.force.stamp_ns) > 0)
    assert len(back.force) == 195
    text = " | ".join(back.warnings)
    assert "1 message(s) arrived out of order" in text
    assert "1 message(s) with a repeated header.stamp dropped" in text
    assert "5 sample(s) missing in 1 gap(s)" in text
    assert "/subject: missing" in text


def test_truncated_file_reads_what_is_there_and_says_where_it_stopped(tmp_path):
    path = tmp_path / "full.mcap"
    save_recording(path, make_recording(seconds=4.0), compression="none", chunk_size=32 * 1024)
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    back = load_recording(cut)
    assert 1000 < len(back.force) < 3500
    assert any("truncated or corrupt" in w and "stopped after t=" in w for w in back.warnings)


def test_not_mcap_and_missing_file_give_one_line_errors(tmp_path):
    bogus = tmp_path / "notes.txt"
    bogus.write_text("time,force\n0,1\n")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        load_recording(bogus)
    with pytest.raises(RecordingError, match="no such file"):
        load_recording(tmp_path / "nope.mcap")


def test_missing_markers_are_named_and_mapping_resolves_them(tmp_path):
    rec = make_recording(seconds=0.5)
    lab_names = ("MT5", "HEE", "ANK", "KNE", "GTR", "HEAD")
    rec.markers = MarkerSeries(rec.markers.stamp_ns, lab_names, rec.markers.positions_m)
    path = tmp_path / "lab.mcap"
    save_recording(path, rec)
    with pytest.raises(RecordingError, match=r"missing marker\(s\) toe, heel, ankle, knee, hip, head"):
        load_recording(path)
    back = load_recording(path, marker_map=dict(zip(MARKER_NAMES, lab_names)))
    np.testing.assert_array_equal(back.markers.positions_m, rec.markers.positions_m)


def test_millimetre_markers_and_plate_force_sign_are_refused(tmp_path):
    rec = make_recording(seconds=0.5)
    rec.markers.positions_m *= 1000.0
    save_recording(tmp_path / "mm.mcap", rec)
    with pytest.raises(RecordingError, match="look like millimetres"):
        load_recording(tmp_path / "mm.mcap")
    rec = make_recording(seconds=0.5)
    rec.force.force_n[:, 2] *= -1
    save_recording(tmp_path / "neg.mcap", rec)
    with pytest.raises(RecordingError, match="force on the plate"):
        load_recording(tmp_path / "neg.mcap")


def test_unknown_topics_are_ignored_by_the_stream(tmp_path):
    path = tmp_path / "rec.mcap"
    save_recording(path, make_recording(seconds=0.1))
    stream = MessageStream(path, topics=["/does/not/exist"])
    assert list(stream) == [] and stream.stopped_at is None
