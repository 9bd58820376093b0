"""Pieces of the views against hand-computed values, bad input, rejections, analytics and the CLI."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from hop_impedance.viz import style as S
from hop_impedance.viz.analytics import analytics_config_path, ensure_analytics_disabled
from hop_impedance.viz.chart import Chart, padded_range
from hop_impedance.viz.stance_view import JointFitView, StanceView, fit_table_markdown
from hop_impedance.viz.views import cop_x_from_wrench, stick_figure_strips

from .conftest import RECORDING
from .readback import column, load_store, scalars

# toe, heel, ankle, knee, hip, head in lab [x, z] (m)
STANDING = np.array([[0.15, 0.0], [-0.05, 0.0], [0.0, 0.08], [0.02, 0.5], [0.0, 0.9], [0.0, 1.6]])


def test_stick_figure_is_foot_triangle_and_leg_chain_with_z_flipped():
    strips, counts = stick_figure_strips(STANDING[None])
    assert counts == [2]
    np.testing.assert_array_equal(strips[0], STANDING[[0, 1, 2, 0]] * [1, -1])
    np.testing.assert_array_equal(strips[1], STANDING[[2, 3, 4, 5]] * [1, -1])


def test_occluded_marker_splits_its_chain_and_never_draws_nan():
    frames = np.stack([STANDING, STANDING, STANDING])
    frames[1, 3] = np.nan  # knee occluded: ankle alone is dropped, hip-head kept
    frames[2] = np.nan  # everything occluded
    strips, counts = stick_figure_strips(frames)
    assert counts == [2, 2, 0]
    np.testing.assert_array_equal(strips[3], STANDING[[4, 5]] * [1, -1])
    assert all(np.isfinite(s).all() for s in strips)


def test_cop_is_minus_torque_y_over_fz_and_nan_in_flight():
    force = np.array([[10.0, 0.0, 500.0], [0.0, 0.0, 5.0]])
    torque = np.array([[0.0, -50.0, 0.0], [0.0, 1.0, 0.0]])
    cop = cop_x_from_wrench(force, torque)
    assert cop[0] == pytest.approx(0.1)
    assert np.isnan(cop[1])


def test_chart_maps_ranges_to_box_corners_with_y_up():
    c = Chart((10.0, 30.0), (-100.0, 300.0), "x", "y", left=5.0, top=2.0, width=100.0, height=70.0)
    pts = c.to_view(np.array([10.0, 30.0, 20.0]), np.array([-100.0, 300.0, 100.0]))
    np.testing.assert_allclose(pts, [[5.0, 72.0], [105.0, 2.0], [55.0, 37.0]])


def test_padded_range_ignores_nan_and_includes_zero():
    assert padded_range(np.array([np.nan, 100.0, 200.0]), pad=0.1, include_zero=True) == pytest.approx((-20.0, 220.0))
    assert padded_range(np.array([np.nan])) == (0.0, 1.0)


def test_fit_table_lists_terms_statistics_and_rejections():
    good = JointFitView(
        None,
        time_s=np.arange(3.0),
        coefficients={"m0": 1.0, "k0": 512.25, "k1": -80.0},
        std_errors={"m0": 0.1, "k0": 12.0, "k1": 30.0},
        p_values={"m0": 0.5, "k0": 1e-6, "k1": 0.012},
        r_squared=0.987,
        rmse_nm=7.5,
        sse_variable=1234.0,
        sse_constant=5678.0,
        overall_stiffness_nm_per_rad=450.0,
    )
    view = StanceView(3, 1.769, 1.977, None, 0.208, 3.58, 2.21, {"ankle": good, "knee": JointFitView("flat angle trajectory")})
    text = fit_table_markdown(view)
    assert "### Stance 3: 1.769–1.977 s" in text
    assert "k0 = 512.2 ± 12 (p<0.001)" in text and "k1 = -80 ± 30 (p=0.012)" in text
    assert "m0" not in text.split("\n")[-2]
    assert "| 0.987 | 7.5 | 1234 / 5678 | 450 |" in text
    assert "| knee | rejected: flat angle trajectory |" in text
    assert good.coefficient("k2") == 0.0 and np.isnan(JointFitView("x").coefficient("k0"))
    rejected = fit_table_markdown(dataclasses.replace(view, rejection_reason="incomplete: cut by end of recording"))
    assert "**Rejected:** incomplete: cut by end of recording" in rejected


def test_analytics_disabled_by_rerun_cli_in_a_fresh_config(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "cfg"))
    monkeypatch.setenv("HOME", str(tmp_path))
    assert not analytics_config_path().exists()
    path = ensure_analytics_disabled()
    assert path == tmp_path / "cfg" / "rerun" / "analytics.json"
    assert json.loads(path.read_text())["analytics_enabled"] is False


def test_rejected_stances_are_logged_with_their_reason(tmp_path, analysed):
    """A knee-marker gap longer than the fill limit in stance 4 and a recording cut mid-stance 9."""
    from hop_impedance.io.recording_io import save_recording
    from hop_impedance.viz.session import write_rrd

    rec, analysis, _ = analysed
    s4, s9 = analysis.stances[4], analysis.stances[9]
    t = (rec.markers.stamp_ns - analysis.start_ns) * 1e-9
    positions = rec.markers.positions_m.copy()
    positions[(t > s4.touchdown_s + 0.05) & (t < s4.touchdown_s + 0.15), rec.markers.names.index("knee")] = np.nan
    cut_ns = analysis.start_ns + int((s9.touchdown_s + 0.1) * 1e9)
    keep_f, keep_m = rec.force.stamp_ns < cut_ns, rec.markers.stamp_ns < cut_ns
    force = dataclasses.replace(rec.force, stamp_ns=rec.force.stamp_ns[keep_f], force_n=rec.force.force_n[keep_f],
                                torque_nm=rec.force.torque_nm[keep_f])
    markers = dataclasses.replace(rec.markers, stamp_ns=rec.markers.stamp_ns[keep_m], positions_m=positions[keep_m])
    path = tmp_path / "bad.mcap"
    save_recording(path, dataclasses.replace(rec, force=force, markers=markers))
    summary = write_rrd(path, None, None, tmp_path / "bad.rrd")
    assert summary.stances == 10 and summary.fitted_stances == 8
    assert "knee" in summary.rejected[4] and "incomplete" in summary.rejected[9]
    store = load_store(tmp_path / "bad.rrd")
    _, tables = column(store, S.TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert len(tables) == 10
    assert f"**Rejected:** {summary.rejected[4]}" in tables[4][0]
    _, logs = column(store, S.TIMELINE, "/" + S.EVENT_LOG, "TextLog:text")
    _, levels = column(store, S.TIMELINE, "/" + S.EVENT_LOG, "TextLog:level")
    assert [lv[0] for lv in levels].count("WARN") == 2
    assert summary.rejected[9] in logs[9][0]
    seq, k0 = scalars(store, S.STANCE_TIMELINE, f"/{S.TREND}/k0/ankle")
    assert np.isnan(k0[[4, 9]]).all() and np.isfinite(np.delete(k0, [4, 9])).all()
    _, loops = column(store, S.TIMELINE, "/" + S.chart_path("ankle", "loop", "current", "measured"), "LineStrips2D:strips")
    assert len(loops) == 8


def test_view_command_writes_rrd_and_reports(tmp_path, capsys):
    from hop_impedance.cli.main import main

    out = tmp_path / "sub" / "v.rrd"
    assert main(["view", str(RECORDING), "--rrd", str(out)]) == 0
    assert "10 stances, 10 fitted" in capsys.readouterr().out
    _, tables = column(load_store(out), S.TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert len(tables) == 10


def test_view_command_errors_are_one_line(tmp_path, capsys, monkeypatch):
    from hop_impedance.cli.main import main

    assert main(["view", str(tmp_path / "missing.mcap"), "--rrd", str(tmp_path / "x.rrd")]) == 2
    assert "no such recording" in capsys.readouterr().err
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(RECORDING)]) == 2
    assert "no display" in capsys.readouterr().err
