"""``hop-impedance analyze --per-leg`` on a contract v2 MCAP of the real OpenCap drop jump (issue 21)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hop_impedance.bilateral import save_bilateral
from hop_impedance.biomech.per_leg import analyze_legs
from hop_impedance.importers.bilateral_import import import_opensim_bilateral
from hop_impedance.io.recording_io import save_recording

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
TRC, MOT = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
pytestmark = pytest.mark.skipif(not TRC.exists(), reason="shared data set opencap_dropjump not present")


def _analyze(*args):
    return subprocess.run([sys.executable, "-m", "hop_impedance.cli", "analyze", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_per_leg_json_matches_the_library(tmp_path):
    bilateral = import_opensim_bilateral(TRC, MOT, mass_kg=60.0)
    path = tmp_path / "dj_v2.mcap"
    save_bilateral(path, bilateral)
    out = tmp_path / "legs.json"
    run = _analyze(path, "--per-leg", "--json", out)
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    assert doc["schema"] == "hop_impedance.analyze_per_leg/1"
    assert doc["legs"]["left"]["segments"]["thigh"]["mass_kg"] == pytest.approx(0.1478 * 60.0)
    legs = analyze_legs(bilateral)
    for side in ("left", "right"):
        mine = [s for s in doc["stances"] if s["side"] == side and s["joints"] is not None]
        lib = [s for s in legs[side].stances if s.joints is not None]
        assert len(mine) == len(lib) == 1
        knee = np.array(mine[0]["joints"]["knee"]["moment_nm"])
        np.testing.assert_allclose(knee, lib[0].joints.moment_nm[:, 1], rtol=1e-6, atol=1e-6)
        assert mine[0]["joints"]["knee"]["fit"]["status"] == "solved"
    assert "2 with inverse dynamics" in run.stderr
    for side in ("left", "right"):  # each leg's kinematics are named: its rigid fit and how close the markers were to it
        assert sum(w.startswith(f"{side} leg: kinematics of a rigid-segment fit") for w in doc["warnings"]) == 1


def test_per_leg_on_a_v1_file_is_a_one_line_error(tmp_path):
    path = tmp_path / "dj_v1.mcap"
    save_recording(path, import_opensim_bilateral(TRC, MOT, mass_kg=60.0).recording)
    run = _analyze(path, "--per-leg", "--json", tmp_path / "x.json")
    assert run.returncode != 0
    assert "Traceback" not in run.stderr and "per-leg analysis needs contract v2" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_import_both_legs_then_analyze_per_leg(tmp_path):
    """hop-impedance import --both-legs writes contract v2; its per-plate topics read back equal to the library's."""
    from hop_impedance.bilateral import load_bilateral

    out = tmp_path / "dj.mcap"
    run = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "import", "--trc", str(TRC), "--mot", str(MOT),
                          "--mass-kg", "60", "--both-legs", "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "ground_force_2 -> left foot" in run.stdout
    back, lib = load_bilateral(out), import_opensim_bilateral(TRC, MOT, mass_kg=60.0)
    assert back.is_bilateral
    np.testing.assert_allclose(back.plates["left"].force_n, lib.plates["left"].force_n, atol=1e-9)
    bad = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "import", "--mot", str(MOT), "--mass-kg", "60",
                          "--both-legs", "--out", str(tmp_path / "x.mcap")], capture_output=True, text=True, timeout=120)
    assert bad.returncode != 0 and "Traceback" not in bad.stderr and "--both-legs needs markers" in bad.stderr
