"""A 1 s force gap that starts inside a stance (message loss), offline and through ``analyze``.

It used to send the detector into unbounded recursion: the first samples after
the gap (in flight) made the "stance" look longer than ``max_stance_s`` with a
steady force far from body weight, the failure test re-ran the stance's
samples with a baseline equal to the one in use, which found the same failure
again (RecursionError; the in-process pipeline printed "node inverse_dynamics
failed: RecursionError"). Built from the bundled recording, with the gap
starting at 70 % of the fourth stance (the recursion needed a gap that ends in
a flight; 60-90 % of that stance all did).
"""

import json

import numpy as np
import pytest

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.biomech.stance_detection import detect_stances
from hop_impedance.cli.main import main
from test.cli import bad_recordings as bad


@pytest.fixture(scope="module")
def rec():
    return bad.bundled()


@pytest.fixture(scope="module")
def clean(rec):
    return analyze_recording(rec)


def gap_start_s(clean, frac: float = 0.7) -> float:
    s = clean.stances[3]
    return s.touchdown_s + frac * (s.takeoff_s - s.touchdown_s)


def test_gap_stance_rejected_as_message_loss_others_unchanged(rec, clean):
    start = gap_start_s(clean)
    holed = analyze_recording(bad.gap(rec, start, 1.0, markers=False))
    assert not any("detector failure" in w for w in holed.warnings)  # a gap is not a wrong baseline
    lost = [s for s in holed.stances if s.rejection_reason is not None]
    # the stance ends at the gap (never bridged over it: two stances must not merge); the gap ends in
    # stance or flight, and a stance cut at its start by the gap is a second rejected row
    assert 1 <= len(lost) <= 2 and all("(message loss)" in s.rejection_reason for s in lost)
    assert lost[0].touchdown_s == clean.stances[3].touchdown_s < lost[0].takeoff_s < start
    assert lost[0].rejection_reason.startswith("incomplete: cut by a 1.00")
    assert all(s.takeoff_s < start or s.touchdown_s >= start + 1.0 - 1e-3 for s in holed.stances)
    # every stance that does not touch the gap [start, start + 1 s] is found again with the same events and data
    outside = [c for c in clean.stances if c.takeoff_s < start or c.touchdown_s > start + 1.0]
    accepted = [s for s in holed.stances if s.rejection_reason is None]
    assert len(accepted) == len(outside) == 7
    first_after = min(i for i, c in enumerate(outside) if c.touchdown_s > start)
    for i, (s, c) in enumerate(zip(accepted, outside)):
        # the first stance after the gap has another flight for its baseline: the gap ends 5.4 ms after the take-off
        # before it, inside the 20 ms of plate ringing (settle_s) the clean run leaves out, but the detector starts
        # afresh after a gap and averages those samples in (-3.3 to 4.3 N): its baseline is 0.141 N, not 0.084 N. That
        # +0.057 N raises the detector's 16 N crossing level on both edges, so the touchdown comes later and the
        # take-off earlier, each by 0.057 N over the force's slope there (25.2 N/ms rising, 6.9 N/ms falling on
        # session 33's recording, the trunk-still flight): +2.3 / -8.3 us (this test's figures; the d8eda79 recording:
        # +0.063 N, +3.0 / -16.5 us); every other stance's events to 1e-6 s
        if i == first_after:
            assert 0 < s.touchdown_s - c.touchdown_s < 1e-5 and -2.5e-5 < s.takeoff_s - c.takeoff_s < 0
        else:
            assert abs(s.touchdown_s - c.touchdown_s) < 1e-6 and abs(s.takeoff_s - c.takeoff_s) < 1e-6
        peak = np.max(np.abs(c.joints.moment_nm), axis=0)
        moved = np.max(np.abs(s.joints.moment_nm - c.joints.moment_nm), axis=0)
        if i == first_after:
            # another plate zeroing: the flight before it lies partly in the gap, so its offset is the mean of other
            # samples (the force noise's 2 N over ~150 samples: 0.16 N s.d.) and interpolated from another centre;
            # at its touchdown the zeroed Fx / Fz / My move by 0.073 N / -0.040 N / 0.020 N m, the moments up to
            # 0.027 / 0.061 / 0.081 N m, most at the hip (longest lever): 0.9e-4 / 7.6e-4 / 1.19e-3 of the peaks
            # (session 33's recording; the d8eda79 recording's draw: 0.022 N Fx, up to 0.03 N m, 4e-4 of the peak)
            assert np.all(moved < 2e-3 * peak)
        else:  # the same data: round-off and the filters' far edge only (up to 2.8e-7 of the peak, measured)
            assert np.all(moved < 1e-5 * peak)


def test_long_gaps_run_without_recursion(rec, clean):
    """Gaps of 1-20 s from several points of a stance: never a RecursionError, never more stances than samples allow."""
    t = (rec.force.stamp_ns - rec.start_ns) * 1e-9
    fz = rec.force.force_n[:, 2]
    bw = rec.subject.body_mass_kg * 9.81
    for frac in (0.1, 0.5, 0.9):
        start = gap_start_s(clean, frac)
        for length in (1.0, 2.5):
            keep = ~((t >= start) & (t < start + length))
            stances = detect_stances(t[keep], fz[keep], body_weight_n=bw)
            before = [s for s in stances if s.takeoff_s < start and not s.cut_end]
            assert [s.touchdown_s for s in before] == [s.touchdown_s for s in clean.stances[:3]]
            assert not [s for s in stances if s.touchdown_s < start < s.takeoff_s]  # never bridged over the gap
            cut = [s for s in stances if s.touchdown_s < start and s.cut_end]
            assert len(cut) == 1 and "force gap (message loss)" in cut[0].rejection_reason
    # 18 s missing from inside a stance, stance then flight after it: the stance ends at the gap, the part after
    # it is a stance cut at its start by the gap; no failure re-run
    tt = np.concatenate([np.arange(0, 1.0, 1e-3), np.arange(19.0, 20.0, 1e-3)])
    ff = np.where(((tt > 0.3) & (tt < 0.5)) | ((tt > 0.8) & (tt < 19.2)), 2 * bw, 0.0)
    stances = detect_stances(tt, ff, body_weight_n=bw)
    assert [(round(s.touchdown_s, 2), round(s.takeoff_s, 2)) for s in stances] == [(0.3, 0.5), (0.8, 1.0), (19.0, 19.2)]
    assert [s.rejection_reason for s in stances] == [
        None, "incomplete: cut by a 18.001 s force gap (message loss)", "incomplete: cut by a 18.001 s force gap (message loss)"]


def test_analyze_cli_exit_zero_and_reason_in_json(tmp_path, rec, clean, capsys):
    path = bad.write(tmp_path / "gap.mcap", bad.gap(rec, gap_start_s(clean), 1.0, markers=False))
    assert main(["analyze", str(path), "--json", str(tmp_path / "a.json")]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "RecursionError" not in err
    assert "/force_plate/wrench: 1000 sample(s) missing in 1 gap(s)" in err
    assert "8 stances, 7 with inverse dynamics" in err
    rows = json.loads((tmp_path / "a.json").read_text())["stances"]
    reasons = [r["rejection_reason"] for r in rows if r["rejection_reason"]]
    assert len(reasons) == 1 and "(message loss)" in reasons[0]
