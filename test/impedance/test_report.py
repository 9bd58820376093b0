"""Report tables/figures and the analyze CLI's fit objects and --report."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import JOINTS, fit_synthetic

from hop_impedance.impedance.report import fit_records, write_report
from hop_impedance.impedance.stance_fit import FIT_JSON_KEYS
from hop_impedance.impedance.synthetic import synthetic_stance

REPO = Path(__file__).resolve().parents[2]


def _fits(freq, seed, n=4):
    rng = np.random.default_rng(seed)
    return [{j: fit_synthetic(synthetic_stance(j, freq, rng, realistic_noise=True)) for j in JOINTS} for _ in range(n)]


def test_report_tables_hold_the_fits_mean_and_sd(tmp_path):
    fits = {"1.53": _fits(1.53, 1), "2.20": _fits(2.20, 2)}
    records = [r for c, f in fits.items() for r in fit_records(f, c, "s1")]
    written = write_report(records, list(fits), tmp_path)
    assert {p.name for p in written} == {
        "table2.csv", "table3.csv", "report.md", "moment_angle.png", "stiffness_time.png", "max_vs_initial_stiffness.png"
    }
    for p in written:
        if p.suffix == ".png":
            assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000
    rows = list(csv.reader(open(tmp_path / "table2.csv")))
    assert rows[0] == ["joint", "quantity", "1.53", "2.20"]
    row = next(r for r in rows if r[0] == "knee" and r[1].startswith("k0"))
    k0 = np.array([f["knee"].coefficients["k0"] for f in fits["2.20"]])
    assert row[3] == f"{k0.mean():.1f} ({k0.std(ddof=1):.1f})"
    md = (tmp_path / "report.md").read_text()
    assert "SSE variable vs constant" in md and "1.53 vs 2.20" in md


def test_rejected_fits_are_left_out_of_the_records():
    fits = _fits(1.87, 3, n=2)
    t = np.linspace(0, 0.3, 5)  # too few samples: rejected
    from hop_impedance.impedance.stance_fit import fit_joint_stance

    fits[1]["hip"] = fit_joint_stance(t, t, np.ones(5), t)
    assert not fits[1]["hip"].ok
    records = fit_records(fits, "1.87", "s")
    assert len(records) == 5 and sum(r.joint == "hip" for r in records) == 1


BUNDLED = [REPO / "recordings" / f"sim_{f}hz_hard.mcap" for f in ("1p87", "2p20")]


@pytest.mark.skipif(not all(p.exists() for p in BUNDLED), reason="bundled recordings missing")
def test_cli_analyze_two_recordings_writes_fits_and_report(tmp_path):
    out = tmp_path / "out.json"
    rep = tmp_path / "rep"
    r = subprocess.run(
        [sys.executable, "-m", "hop_impedance.cli", "analyze", *map(str, BUNDLED), "--json", str(out), "--report", str(rep)],
        capture_output=True, text=True, cwd=REPO, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    docs = json.loads(out.read_text())
    assert isinstance(docs, list) and len(docs) == 2
    for doc in docs:
        for stance in doc["stances"]:
            for joint in JOINTS:
                fit = stance["joints"][joint]["fit"]
                assert tuple(fit) == FIT_JSON_KEYS
                assert fit["status"] == "solved" and fit["rejection_reason"] is None
                assert len(fit["stiffness"]) == len(stance["joints"][joint]["time_s"])
    rows = list(csv.reader(open(rep / "table2.csv")))
    # the columns are the hop frequencies measured on the recordings (session 14's seed-like hopper: 1.87 / 2.19 Hz,
    # `.venv/bin/python -m hop_impedance.cli demo recordings/sim_2p20hz_hard.mcap` prints "hopping at 2.19 Hz")
    assert rows[0] == ["joint", "quantity", "1.87 Hz", "2.19 Hz"]
    # seed finding on these recordings: average stiffness higher at the higher frequency
    for joint in JOINTS:
        avg = next(r for r in rows if r[0] == joint and r[1].startswith("Average"))
        assert float(avg[2].split()[0]) < float(avg[3].split()[0])
    r = subprocess.run(
        [sys.executable, "-m", "hop_impedance.cli", "analyze", str(BUNDLED[0]), "--json", str(out), "--no-fit"],
        capture_output=True, text=True, cwd=REPO, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "fit" not in json.loads(out.read_text())["stances"][0]["joints"]["ankle"]
