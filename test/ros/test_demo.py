"""``hop-impedance demo`` (what ``make demo`` runs): exits 0 by itself, prints one row per stance, writes the
output MCAP and a Rerun .rrd with one stance log per stance, and says how to open it."""

import subprocess
import sys

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("rerun")

from hop_impedance.child_env import child_env  # noqa: E402
from hop_impedance.io.mcap_io import summarize  # noqa: E402
from hop_impedance.viz import style as S  # noqa: E402
from test.viz.readback import column, load_store  # noqa: E402


def test_demo_table_mcap_and_rrd(tmp_path):
    rrd, out = tmp_path / "demo.rrd", tmp_path / "demo_out"
    env = child_env({"HOME": str(tmp_path), "XDG_CONFIG_HOME": str(tmp_path / "config")})
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    run = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "demo", "--out", str(out), "--rrd", str(rrd)],
                         env=env, capture_output=True, text=True, timeout=90)
    assert run.returncode == 0, run.stdout + run.stderr
    rows = [line for line in run.stdout.splitlines() if line.rstrip().endswith("| accepted")]
    assert len(rows) == 10
    assert f"open it with: .venv/bin/rerun {rrd}" in run.stdout
    counts = {i.topic: i.count for i in summarize(out / "pipeline.mcap")}
    inputs = {i.topic: i.count for i in summarize("recordings/sim_2p20hz_hard.mcap")}
    assert counts["/impedance/stance_summary"] == 10 and counts["/force_plate/wrench"] == inputs["/force_plate/wrench"]
    seq, tables = column(load_store(rrd), S.STANCE_TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert list(seq) == list(range(10))
