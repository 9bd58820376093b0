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
    # one model per trial (issue 15): the demo says which structure each joint uses and why, and every accepted
    # profile of a joint carries exactly those terms
    from hop_impedance.io.mcap_io import MessageStream

    said = {line.split(":")[0].split()[1]: line.split(":")[1].split() for line in run.stdout.splitlines()
            if line.startswith("model ")}
    assert sorted(said) == ["ankle", "hip", "knee"] and all("given" in line or "fixed after" in line
                                                            for line in run.stdout.splitlines() if line.startswith("model "))
    terms = {}
    for m in MessageStream(out / "pipeline.mcap", ["/impedance/profile"]):
        if m.message.accepted:
            terms.setdefault(m.message.joint, set()).add(tuple(m.message.terms))
    assert {j: t for j, t in terms.items()} == {j: {tuple(said[j])} for j in said}
    seq, tables = column(load_store(rrd), S.STANCE_TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert list(seq) == list(range(10))
