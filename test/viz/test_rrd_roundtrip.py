"""Write an .rrd from a bundled recording and read it back with Rerun's dataframe API.

What the recording implies: 10 hops (truth file), every stance complete and
fitted; the force and marker message counts of the file; the fitted k0 of
each stance; the instants at which the simulator's true vertical force crosses
the stance detector's level (on the shoe pad of session 14's recording the
contact itself begins 2.0-2.9 ms before and ends 8-11 ms after them: the pad's
last 16 N hold 3 mm of its compression).
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.biomech.stance_detection import DetectorOptions
from hop_impedance.recording import GRAVITY_M_S2
from hop_impedance.viz import style as S

from .readback import column, entity_paths, load_store, scalars


@pytest.fixture(scope="module")
def store(rrd):
    return load_store(rrd[0])


def test_entities_present(store):
    paths = entity_paths(store)
    expected = {"/" + p for p in (S.SEGMENTS, S.MARKERS, S.GRF_ARROW, S.GRF_BW, S.IN_STANCE, S.TABLE, S.EVENT_LOG)}
    for joint in JOINT_NAMES:
        expected |= {
            f"/{S.ANGLE}/{joint}",
            f"/{S.VELOCITY}/{joint}",
            f"/{S.POWER}/{joint}",
            f"/{S.STIFFNESS}/{joint}",
            "/" + S.moment_path(joint, "inverse_dynamics"),
            "/" + S.moment_path(joint, "variable_fit"),
            f"/{S.TREND}/k0/{joint}",
            f"/{S.TREND}/k1/{joint}",
            "/" + S.chart_path(joint, "loop", "current", "measured"),
            "/" + S.chart_path(joint, "loop", "current", "variable_fit"),
            "/" + S.chart_path(joint, "loop", "current", "constant_fit"),
            "/" + S.chart_path(joint, "k_rho", "current"),
        }
    assert expected <= paths, sorted(expected - paths)


def force_events(truth: dict) -> tuple[np.ndarray, np.ndarray]:
    """Per stance, the times (s) at which the truth's noise-free vertical GRF first rises to and last falls to the
    detector's event level (its take-off level: the larger of the floor and the body-weight fraction; the recording's
    2 N noise puts the noise term below both), linearly interpolated between the force-plate samples."""
    opts = DetectorOptions()
    level = max(opts.takeoff_n, opts.takeoff_bw * truth["subject"]["body_mass_kg"] * GRAVITY_M_S2)
    td, to = [], []
    for s in truth["stances"]:
        t, fz = np.asarray(s["samples"]["t_s"]), np.asarray(s["samples"]["grf_n"])[:, 1]
        above = np.flatnonzero(fz >= level)
        i, j = above[0], above[-1]
        td.append(np.interp(level, [fz[i - 1], fz[i]], [t[i - 1], t[i]]) if i > 0 else t[0])
        to.append(np.interp(level, [fz[j + 1], fz[j]], [t[j + 1], t[j]]) if j + 1 < len(t) else t[-1])
    return np.array(td), np.array(to)


def test_one_stance_log_per_hop(store, truth, rrd):
    n = len(truth["stances"])
    assert n == 10
    assert rrd[1].stances == n and rrd[1].fitted_stances == n and rrd[1].rejected == {}
    t, tables = column(store, S.TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert len(tables) == n
    seq, _ = column(store, S.STANCE_TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert list(seq) == list(range(n))
    for k, text in enumerate(tables):
        assert text[0].startswith(f"### Stance {k}:")
    # Logged at take-off: the simulator's true force reaching the detector's level within 3 ms.
    assert np.max(np.abs(t - force_events(truth)[1])) < 3e-3
    for joint in JOINT_NAMES:
        _, loops = column(store, S.TIMELINE, "/" + S.chart_path(joint, "loop", "current", "measured"), "LineStrips2D:strips")
        assert len(loops) == n
        history = [p for p in entity_paths(store) if p.startswith("/" + S.chart_path(joint, "loop", "history"))]
        assert len(history) == n


def test_stance_marks_match_truth_events(store, truth):
    t, v = scalars(store, S.TIMELINE, "/" + S.IN_STANCE)
    td, to = t[v == 1.0], t[v == 0.0]
    assert len(td) == len(to) == len(truth["stances"])
    true_td, true_to = force_events(truth)
    assert np.max(np.abs(td - true_td)) < 3e-3
    assert np.max(np.abs(to - true_to)) < 3e-3


def test_trend_values_are_the_fitted_coefficients(store, analysed):
    _, _, fits = analysed
    for joint in JOINT_NAMES:
        seq, k0 = scalars(store, S.STANCE_TIMELINE, f"/{S.TREND}/k0/{joint}")
        assert list(seq) == list(range(len(fits)))
        np.testing.assert_allclose(k0, [f[joint].coefficients["k0"] for f in fits], rtol=1e-12)
        _, k1 = scalars(store, S.STANCE_TIMELINE, f"/{S.TREND}/k1/{joint}")
        np.testing.assert_allclose(k1, [f[joint].coefficients.get("k1", 0.0) for f in fits], rtol=1e-12)
    # Seed-paper scale (Table 2 at 2.2 Hz, both legs): ankle k0 of a few hundred N m/rad.
    _, ankle = scalars(store, S.STANCE_TIMELINE, f"/{S.TREND}/k0/ankle")
    assert 300.0 < np.median(ankle) < 900.0


def test_signal_rows_match_the_recording(store, analysed):
    rec, analysis, _ = analysed
    t, grf = scalars(store, S.TIMELINE, "/" + S.GRF_BW)
    assert len(grf) == len(rec.force)
    np.testing.assert_allclose(grf, rec.force.force_n[:, 2] / rec.subject.body_weight_n, rtol=1e-12)
    np.testing.assert_allclose(t, (rec.force.stamp_ns - analysis.start_ns) * 1e-9, atol=1e-9)
    _, markers = column(store, S.TIMELINE, "/" + S.MARKERS, "Points2D:positions")
    assert len(markers) == len(rec.markers)
    # First frame: the head marker drawn at (x, -z) of the recorded head (float32 in Rerun).
    head = rec.markers.marker("head")[0]
    np.testing.assert_allclose(markers[0][5], [head[0], -head[2]], atol=1e-6)
    # Joint series: one sample per stance sample plus one NaN line break per stance.
    n_samples = sum(len(s.joints.time_s) for s in analysis.stances)
    _, angle = scalars(store, S.TIMELINE, f"/{S.ANGLE}/knee")
    assert len(angle) == n_samples + len(analysis.stances)
    assert np.count_nonzero(np.isnan(angle)) == len(analysis.stances)
    expected = np.concatenate([np.degrees(s.joints.angle_rad[:, 1]) for s in analysis.stances])
    np.testing.assert_allclose(angle[np.isfinite(angle)], expected, rtol=1e-12)


def test_grf_arrow_only_in_contact(store, analysed):
    rec, _, _ = analysed
    _, arrows = column(store, S.TIMELINE, "/" + S.GRF_ARROW, "Arrows2D:vectors")
    assert len(arrows) == len(rec.force)
    drawn = np.array([len(a) for a in arrows])
    assert np.array_equal(drawn == 1, rec.force.force_n[:, 2] > S.MIN_COP_FORCE_N)
    k = int(np.argmax(rec.force.force_n[:, 2]))
    expected = rec.force.force_n[k, [0, 2]] * [1, -1] * S.GRF_ARROW_M_PER_BW / rec.subject.body_weight_n
    np.testing.assert_allclose(arrows[k][0], expected, rtol=1e-5)


def test_blueprint_stored(rrd):
    from rerun.chunk import RrdReader

    assert len(RrdReader(str(rrd[0])).blueprints()) == 1
