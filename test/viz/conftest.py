"""Fixtures of the viz tests: an isolated Rerun config (analytics off) and one .rrd per recording."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
RECORDING = REPO / "recordings" / "sim_2p20hz_hard.mcap"


@pytest.fixture(scope="session", autouse=True)
def rerun_home(tmp_path_factory):
    """HOME and XDG_CONFIG_HOME in a throw-away folder, so the real analytics.json is never touched."""
    home = tmp_path_factory.mktemp("rerun_home")
    saved = {k: os.environ.get(k) for k in ("HOME", "XDG_CONFIG_HOME")}
    os.environ["HOME"] = str(home)
    os.environ["XDG_CONFIG_HOME"] = str(home / "config")
    yield home
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture(scope="session")
def analysed():
    """(recording, analysis, fits) of the bundled 2.2 Hz hard-surface trial."""
    from hop_impedance.io.recording_io import load_recording
    from hop_impedance.viz.session import analyze_and_fit

    rec = load_recording(RECORDING)
    analysis, fits = analyze_and_fit(rec)
    return rec, analysis, fits


@pytest.fixture(scope="session")
def truth():
    """The simulator's truth file of :data:`RECORDING`."""
    return json.loads(RECORDING.with_suffix("").with_suffix(".truth.json").read_text())


@pytest.fixture(scope="session")
def rrd(tmp_path_factory, analysed):
    """.rrd of :data:`RECORDING` written through :func:`write_rrd`, and its summary."""
    from hop_impedance.viz.session import write_rrd

    _, analysis, fits = analysed
    out = tmp_path_factory.mktemp("rrd") / "session.rrd"
    summary = write_rrd(RECORDING, analysis, fits, out)
    return out, summary
