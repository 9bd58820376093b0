"""Property test of the MCAP readers on damaged files (issue 14): random chunk spans, truncation
points and flipped bytes never raise anything but a one-line RecordingError, and every message
in the chunks before the damage is read, unchanged and in order.
"""

from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from hop_impedance.io.mcap_io import McapWriter, MessageStream, RecordingError, read_summary
from hop_impedance.io.recording_io import load_recording, write_recording_messages
from test.io.test_mcap_recordings import make_recording

REC = make_recording(seconds=1.5, seed=4)


def _write(path: Path, span_s: float, compression: str) -> list[tuple]:
    with McapWriter(path, compression=compression, max_chunk_span_s=span_s) as w:
        write_recording_messages(w, REC)
    with open(path, "rb") as fh:  # the intact file through mcap's own reader, not ours
        return [(c.topic, m.log_time, bytes(m.data)) for _, c, m in make_reader(fh).iter_messages(log_time_order=True)]


def _messages(path: Path) -> list[tuple]:
    return [(m.topic, m.log_time_ns, bytes(m.message)) for m in MessageStream(path, decode=False)]


def _intact_before(path: Path, offset: int, original: list[tuple]) -> int:
    """Messages of the intact file held in chunks that end at or before byte ``offset`` (a prefix: one chunk per time span)."""
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    ends = [c.message_end_time for c in summary.chunk_indexes if c.chunk_start_offset + c.chunk_length <= offset]
    last = max(ends, default=-1)
    return sum(1 for m in original if m[1] <= last)


def _read_everything(path: Path) -> list[tuple]:
    """Every reader the commands use; only RecordingError may come out."""
    try:
        got = _messages(path)
        list(MessageStream(path))  # decoded
        read_summary(path)
    except RecordingError:
        return []
    try:
        load_recording(path)
    except RecordingError:
        pass
    return got


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(span=st.sampled_from([0.02, 0.1, 0.25, 1.0]), compression=st.sampled_from(["zstd", "lz4", "none"]),
       cut=st.floats(0.0, 1.0), flips=st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(1, 255)), max_size=3))
def test_damaged_files_read_to_the_break(tmp_path_factory, span, compression, cut, flips):
    d = tmp_path_factory.mktemp("fuzz")
    good = d / "good.mcap"
    original = _write(good, span, compression)
    data = bytearray(good.read_bytes())
    end = int(cut * len(data))
    damage = end
    for where, xor in flips:
        k = int(where * (len(data) - 1))
        data[k] ^= xor
        damage = min(damage, k)
    bad = d / "bad.mcap"
    bad.write_bytes(bytes(data[:end]))
    got = _read_everything(bad)
    if damage <= 8:
        return  # magic bytes gone: a one-line "not an MCAP file" / "is empty" is the whole answer
    before = _intact_before(good, damage, original)
    assert got[:before] == original[:before]


def test_truncated_bundled_recording_keeps_three_stances(tmp_path):
    from hop_impedance.biomech.analysis import analyze_recording
    from test.cli.bad_recordings import BUNDLED, truncated

    cut = truncated(tmp_path / "half.mcap", BUNDLED, 0.5)
    rec = load_recording(cut)
    assert any("truncated or corrupt" in w for w in rec.warnings)
    stances = analyze_recording(rec).stances
    assert sum(s.rejection_reason is None for s in stances) >= 3
    full = load_recording(BUNDLED)
    n = len(rec.force)
    assert n > 0.45 * len(full.force)  # all but the last (<= 0.25 s) chunk of the first half
    np.testing.assert_array_equal(rec.force.force_n, full.force.force_n[:n])
