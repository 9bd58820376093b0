"""``--json -``: the JSON document alone on stdout, whatever else writes to file descriptor 1."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hop_impedance.cli.json_output import json_output

RECORDING = Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap"


def test_c_level_and_print_output_go_to_stderr_and_the_document_to_stdout(capfd):
    with json_output("-") as write_json:
        os.write(1, b"Polishing not needed - no active set detected at optimal point\n")  # as OSQP's C code does
        print("a stray print")
        write_json('{"stances": []}')
    print("after the block")  # stdout is restored
    out, err = capfd.readouterr()
    assert out == '{"stances": []}\nafter the block\n'
    assert "Polishing not needed" in err and "a stray print" in err


def test_file_is_written_only_when_the_document_is(tmp_path):
    path = tmp_path / "out.json"
    with pytest.raises(RuntimeError):
        with json_output(str(path)):
            raise RuntimeError("analysis failed")
    assert not path.exists()
    with json_output(str(path)) as write_json:
        write_json('{"a": 1}')
    assert json.loads(path.read_text()) == {"a": 1}


@pytest.mark.skipif(not RECORDING.exists(), reason="bundled recording missing")
def test_analyze_to_stdout_is_one_parseable_document():
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    done = subprocess.run(
        [sys.executable, "-m", "hop_impedance.cli", "analyze", str(RECORDING), "--json", "-"],
        capture_output=True, text=True, env=env, timeout=300, check=True,
    )
    doc = json.loads(done.stdout)
    assert len(doc["stances"]) == 10
    assert "10 stances" in done.stderr
