"""``hop-impedance import``: files in, contract MCAP out, one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.cli.main import main
from hop_impedance.importers import write_c3d

from .conftest import CMJ, OPENCAP

recording_io = pytest.importorskip("hop_impedance.io.recording_io", reason="MCAP recording I/O not available yet")


def test_c3d_to_mcap_and_back(hopping, tmp_path, capsys):
    c3d = write_c3d(hopping, tmp_path / "s.c3d", lab_up="+Z", lab_forward="-Y")
    assert main(["import", str(c3d), "--markers", "contract", "--forward=-Y", "--out", str(tmp_path / "r.mcap")]) == 0
    assert "wrote" in capsys.readouterr().out
    back = recording_io.load_recording(tmp_path / "r.mcap")
    np.testing.assert_allclose(back.force.force_n, hopping.force.force_n, atol=1e-3)
    np.testing.assert_allclose(back.markers.positions_m, hopping.markers.positions_m, atol=1e-6)
    assert back.subject.body_mass_kg == hopping.subject.body_mass_kg


@pytest.mark.skipif(not OPENCAP.exists(), reason="shared data set opencap_dropjump not present")
def test_trc_mot(tmp_path, capsys):
    args = ["import", "--trc", str(OPENCAP / "Subject4_DJ1_markers_trc.txt"), "--mot", str(OPENCAP / "Subject4_DJ1_grf_mot.txt")]
    assert main(args + ["--out", str(tmp_path / "r.mcap")]) == 2
    assert capsys.readouterr().err.strip().startswith("hop-impedance import: error: body mass unknown")
    assert main(args + ["--mass-kg", "60", "--out", str(tmp_path / "r.mcap")]) == 0
    out = capsys.readouterr().out
    assert "subject faces lab" in out and "269 frames at 100 Hz" in out
    # The terminal says which label fed each contract marker.
    assert "note: marker map opencap_right: hip <- R_HJC" in out and "note: marker map opencap_right: head <- R_Shoulder" in out
    assert recording_io.load_recording(tmp_path / "r.mcap").subject.body_mass_kg == 60.0


@pytest.mark.skipif(not CMJ.exists(), reason="shared data set bmc_cmj_grf not present")
def test_force_only_says_what_cannot_be_computed(tmp_path, capsys):
    assert main(["import", "--force-txt", str(CMJ), "--out", str(tmp_path / "r.mcap")]) == 0
    out = capsys.readouterr().out
    assert "joint angles, joint moments" in out and "estimated from quiet standing" in out
    assert recording_io.load_recording(tmp_path / "r.mcap").markers is None


def test_conflicting_inputs(tmp_path, capsys):
    assert main(["import", "a.c3d", "--force-txt", "b.txt", "--out", str(tmp_path / "r.mcap")]) == 2
    assert "exactly one input" in capsys.readouterr().err
