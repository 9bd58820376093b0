"""Issue 14, offline half: every bad input of the table is a named one-line error (or a named
rejection) from ``hop-impedance analyze``/``info``, through the shared check module.

The bad recordings are built inside the tests from the bundled 2.20 Hz recording
(test/cli/bad_recordings.py). The live half is test/ros/test_live_checks.py.
"""

import json

import numpy as np
import pytest

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.cli.main import main
from hop_impedance.input_checks import InputChecks
from hop_impedance.recording import Subject
from test.cli import bad_recordings as bad


@pytest.fixture(scope="module")
def rec():
    return bad.bundled(seconds=4.0)


def _analyze(capsys, *argv):
    code = main(["analyze", *map(str, argv)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err


@pytest.mark.parametrize(
    ("make", "rule", "words"),
    [
        (bad.plate_sign, "force_sign", "force on the plate"),
        (bad.millimetres, "marker_units", "millimetres"),
        (bad.upper_case_names, "marker_names", "missing marker(s) toe"),
    ],
)
def test_bad_contract_input_is_a_named_one_line_error(tmp_path, capsys, rec, make, rule, words):
    path = bad.write(tmp_path / "bad.mcap", make(rec))
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit")
    assert code == 2
    assert f"input check {rule}:" in err and words in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o.json").exists()


def test_missing_subject_asks_for_mass_and_height(tmp_path, capsys, rec):
    path = bad.write(tmp_path / "nosub.mcap", bad.no_subject(rec))
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit")
    assert code == 2 and "no /subject message; give --mass-kg and --height-m" in err
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit", "--mass-kg", "54.8", "--height-m", "1.63")
    assert code == 0


@pytest.mark.parametrize(("flag", "value", "words"), [
    ("--height-m", "0", "body_height 0 m is implausible"),
    ("--mass-kg", "-5", "body_mass -5 kg is implausible"),
    ("--cutoff-hz", "0", "--cutoff-hz must be > 0"),
])
def test_zero_or_negative_sizes_are_one_line_errors(tmp_path, capsys, rec, flag, value, words):
    path = bad.write(tmp_path / "r.mcap", rec)
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit", flag, value)
    assert code == 2 and words in err


def test_cutoff_50_hz_is_a_rates_error_not_message_loss(tmp_path, capsys, rec):
    path = bad.write(tmp_path / "r.mcap", rec)
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit", "--cutoff-hz", "50")
    assert code == 2
    assert "input check rates: marker samples arrive at 100.0 Hz; the 50 Hz low-pass needs more than 100 Hz" in err
    assert "message loss" not in err


def test_duplicates_are_dropped_and_the_warning_is_printed(tmp_path, capsys, rec):
    clean = analyze_recording(rec)
    path = bad.write(tmp_path / "dup.mcap", bad.duplicates(rec, 0.1, seed=3))
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit")
    assert code == 0
    assert "warning:" in err and "/force_plate/wrench: 400 message(s) with a repeated header.stamp dropped" in err
    doc = json.loads((tmp_path / "o.json").read_text())
    assert [s["rejection_reason"] for s in doc["stances"]] == [s.rejection_reason for s in clean.stances]
    assert [s["contact_time_s"] for s in doc["stances"]] == pytest.approx([s.contact_time_s for s in clean.stances])


def test_force_gap_inside_a_stance_is_rejected(tmp_path, capsys, rec):
    clean = analyze_recording(rec)
    s = next(s for s in clean.stances if s.rejection_reason is None and s.index >= 2)
    # 0.3 s of force missing from 40 ms after touchdown (markers intact): contact time 0.207 s before the fix
    holed = bad.gap(rec, s.touchdown_s + 0.04, 0.3, markers=False)
    path = bad.write(tmp_path / "gap.mcap", holed)
    code, err = _analyze(capsys, path, "--json", tmp_path / "o.json", "--no-fit")
    assert code == 0 and "sample(s) missing in 1 gap(s)" in err  # the load warning is on the terminal
    doc = json.loads((tmp_path / "o.json").read_text())
    row = min(doc["stances"], key=lambda r: abs(r["touchdown_s"] - s.touchdown_s))
    assert row["touchdown_s"] == pytest.approx(s.touchdown_s, abs=1e-3)
    assert row["joints"] is None
    assert "(message loss)" in row["rejection_reason"]  # cut at the gap (or rejected for the samples it lost)


@pytest.mark.parametrize("content", [b"", b"hello, this is text\n"])
def test_empty_and_text_files(tmp_path, capsys, content):
    path = tmp_path / "x.mcap"
    path.write_bytes(content)
    for argv in (["analyze", path, "--json", tmp_path / "o.json"], ["info", path],
                 ["pipeline", path, "--out", tmp_path / "p"], ["replay", path, "--wait", "0"]):
        code = main([str(a) for a in argv])
        err = capsys.readouterr().err
        assert code == 2 and "Traceback" not in err
        assert ("is empty (0 bytes)" if not content else "not an MCAP file") in err


# -- the shared module itself, streamed as a node feeds it ---------------------------------------


def test_streamed_checks_decide_force_sign_within_the_first_stance(rec):
    flipped = bad.plate_sign(rec)
    checks = InputChecks()
    stamps, fz = flipped.force.stamp_ns, flipped.force.force_n[:, 2]
    decided = None
    for k in range(0, len(stamps), 5):  # 5-sample chunks, as a node's 5 ms processing period
        if checks.force(stamps[k:k + 5], fz[k:k + 5]) is not None:
            decided = k + 5
            break
    assert checks.failure.rule == "force_sign"
    first_load = int(np.argmax(-fz > 100))
    assert decided - first_load <= 60  # 50 samples past -100 N, plus one chunk
    good = InputChecks()
    good.force(rec.force.stamp_ns, rec.force.force_n[:, 2])
    assert good.failure is None


def test_streamed_checks_subject_wait_then_fallback_or_failure(rec):
    fz, stamps = rec.force.force_n[:, 2], rec.force.stamp_ns
    waiting = InputChecks(subject_wait_s=2.0)
    waiting.force(stamps[:1500], fz[:1500])
    assert waiting.failure is None  # 1.5 s: still waiting
    waiting.force(stamps[1500:2100], fz[1500:2100])
    assert waiting.failure.rule == "subject_missing"
    fallback = InputChecks(subject_wait_s=2.0, fallback=Subject("p", 60.0, 1.7))
    fallback.force(stamps[:2100], fz[:2100])
    assert fallback.failure is None and fallback.subject.body_mass_kg == 60.0 and "from parameters" in fallback.notes[0]
    late = InputChecks(subject_wait_s=2.0)
    late.set_subject(Subject("s", 0.0, 1.6))
    assert late.failure.rule == "subject_values"


def test_streamed_marker_checks(rec):
    names = list(rec.markers.names)
    checks = InputChecks()
    assert checks.marker_names(names) == list(range(6))
    for k in range(20):
        checks.markers(rec.markers.stamp_ns[k], rec.markers.positions_m[k])
    assert checks.failure is None
    mm = InputChecks()
    for k in range(20):
        if mm.markers(rec.markers.stamp_ns[k], rec.markers.positions_m[k] * 1000) is not None:
            break
    assert mm.failure.rule == "marker_units" and mm.frames == 10  # decided at the 10th frame
    upper = InputChecks()
    assert upper.marker_names([n.upper() for n in names]) is None and upper.failure.rule == "marker_names"


def test_info_and_replay_read_a_cut_recording_to_the_break(tmp_path, capfd):
    half = bad.truncated(tmp_path / "half.mcap", bad.BUNDLED, 0.5)
    assert main(["info", str(half)]) == 0
    out = capfd.readouterr().out
    from hop_impedance.io.mcap_io import MessageStream

    total = sum(1 for _ in MessageStream(bad.BUNDLED, topics=["/force_plate/wrench"], decode=False))
    kept = sum(1 for _ in MessageStream(half, topics=["/force_plate/wrench"], decode=False))
    force_row = next(line for line in out.splitlines() if line.startswith("/force_plate/wrench"))
    assert int(force_row.split()[2]) == kept > 0.4 * total  # (was an empty table with one 368 KB chunk)
    assert "warning: half.mcap: truncated or corrupt: read" in out and "stopped after t=" in out
    assert main(["replay", str(half), "--rate", "0", "--wait", "0"]) == 0
    captured = capfd.readouterr()
    assert f"/force_plate/wrench: {kept} messages published" in captured.out
    assert "hop-impedance replay: warning: half.mcap: truncated or corrupt" in captured.err
