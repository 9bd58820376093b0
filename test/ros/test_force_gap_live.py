"""Live half of the in-stance force gap (test/biomech/test_force_gap.py): the node graph on the same file.

Before the fix the in-process pipeline ended with "node inverse_dynamics
failed: RecursionError" at the first force message after the gap.
"""

from hop_impedance.cli.main import main
from hop_impedance.cli.pipeline_cmd import print_report
from hop_impedance.io.mcap_io import MessageStream
from hop_impedance.nodes.common import STANCE_KINETICS_TOPIC, stamp_ns
from hop_impedance.nodes.runner import PipelineConfig, run_pipeline
from test.biomech.test_force_gap import gap_start_s
from test.cli import bad_recordings as bad


def test_force_gap_in_stance_live_rows_match_analyze(tmp_path, capfd):
    import json

    from hop_impedance.biomech.analysis import analyze_recording

    rec = bad.bundled()
    path = bad.write(tmp_path / "gap.mcap", bad.gap(rec, gap_start_s(analyze_recording(rec)), 1.0, markers=False))
    assert main(["analyze", str(path), "--json", str(tmp_path / "a.json"), "--no-fit"]) == 0
    offline = {r["touchdown_stamp_ns"]: r["rejection_reason"] for r in json.loads((tmp_path / "a.json").read_text())["stances"]}
    capfd.readouterr()
    report = run_pipeline(PipelineConfig(recording=str(path), out_dir=str(tmp_path / "out"), timeout_s=60.0))
    code = print_report(report, str(path))
    captured = capfd.readouterr()
    text = captured.out + captured.err
    assert report.finished and "Traceback" not in text and "failed" not in text, text
    rows = [m.message for m in MessageStream(report.output_mcap, topics=[STANCE_KINETICS_TOPIC])]
    live = {stamp_ns(m.touchdown_stamp): (m.rejection_reason or None) for m in rows}
    assert len(live) == len(offline) == 8
    for td, reason in live.items():
        match = min(offline, key=lambda t: abs(t - td))
        assert abs(match - td) <= 1_000_000  # same touchdown within one force sample
        assert reason == offline[match]
    lost = [r for r in live.values() if r is not None]
    assert len(lost) == 1 and "(message loss)" in lost[0]
    # the 1000 samples the file lacks are not losses on the way: exit 0
    assert code == 0, text
