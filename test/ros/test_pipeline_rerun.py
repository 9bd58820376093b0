"""``pipeline --rrd`` (formerly ``--rerun-save``): the Rerun bridge runs inside the pipeline on this headless
machine and writes an .rrd that holds one stance log per stance the pipeline summarised, with the pipeline's own
coefficients."""

import os

import numpy as np
import pytest

pytest.importorskip("rclpy")
pytest.importorskip("rerun")

from hop_impedance.nodes.runner import PipelineConfig, run_pipeline  # noqa: E402
from hop_impedance.viz import style as S  # noqa: E402
from test.viz.readback import column, load_store, scalars  # noqa: E402

REC = "recordings/sim_2p20hz_hard.mcap"


@pytest.fixture()
def rerun_home(tmp_path, monkeypatch):
    """Rerun's config (analytics) in a throw-away HOME."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "home" / "config"))


def test_pipeline_writes_rrd_with_every_stance(tmp_path, rerun_home):
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    rrd = tmp_path / "live.rrd"
    report = run_pipeline(PipelineConfig(REC, str(tmp_path), rate=0.0, rerun_save=str(rrd), timeout_s=60))
    assert report.finished and report.rrd == str(rrd)
    assert rrd.stat().st_size > 0
    store = load_store(rrd)
    summaries = sorted(report.summaries, key=lambda s: s.stance_index)
    assert len(summaries) == 10
    # one stance table per summarised stance, in order, on the stance timeline
    seq, tables = column(store, S.STANCE_TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert list(seq) == [s.stance_index for s in summaries]
    assert all(t[0].startswith(f"### Stance {s.stance_index}:") for s, t in zip(summaries, tables))
    # the k0 trend holds the coefficients the estimator published
    for j, joint in enumerate(("ankle", "knee", "hip")):
        k_seq, k0 = scalars(store, S.STANCE_TIMELINE, f"/{S.TREND}/k0/{joint}")
        assert list(k_seq) == [s.stance_index for s in summaries]
        np.testing.assert_allclose(k0, [s.k0[j] for s in summaries], rtol=1e-12)
    # the GRF was logged for the whole replay (1 kHz force, one row per sample)
    t_grf, grf = scalars(store, S.TIMELINE, "/" + S.GRF_BW)
    from hop_impedance.io.mcap_io import summarize

    assert grf.size == {i.topic: i.count for i in summarize(REC)}["/force_plate/wrench"]
    assert np.nanmax(grf) > 2.0  # hopping peaks exceed two body weights
