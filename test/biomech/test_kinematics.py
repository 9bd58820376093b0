"""Filtering, gap filling and the marker -> kinematics -> inverse dynamics chain against analytic truth."""

import numpy as np
import pytest
from biomech_synth import make_model, markers_from_points, pinned_chain

from hop_impedance.biomech.filtering import fill_gaps, lowpass
from hop_impedance.biomech.inverse_dynamics import inverse_dynamics_2d
from hop_impedance.biomech.kinematics import body_model_from_markers, compute_kinematics, wrench_through_marker_chain
from hop_impedance.recording import MARKER_NAMES, MarkerSeries, Subject


def test_lowpass_gain_matches_butterworth_design():
    """Forward-backward 2nd-order Butterworth: gain |H(f)|^2 of the one-pass design, 0.5 at the cut-off."""
    from scipy.signal import butter, sosfreqz

    fs, fc = 1000.0, 12.0
    t = np.arange(0, 10, 1 / fs)
    sos = butter(2, fc, fs=fs, output="sos")
    for f in (2.0, 12.0, 40.0):
        expected = float(np.abs(sosfreqz(sos, [f], fs=fs)[1][0]) ** 2)
        if f == fc:
            assert expected == pytest.approx(0.5, rel=1e-9)
        y = lowpass(np.sin(2 * np.pi * f * t), fs, fc)
        mid = slice(2000, 8000)
        gain = np.std(y[mid]) / np.std(np.sin(2 * np.pi * f * t)[mid])
        assert gain == pytest.approx(expected, rel=2e-3)
    # Zero lag: the filtered 2 Hz sine peaks where the input does.
    y = lowpass(np.sin(2 * np.pi * 2 * t), fs, fc)
    assert np.argmax(y[4000:4500]) == np.argmax(np.sin(2 * np.pi * 2 * t[4000:4500]))
    with pytest.raises(ValueError, match="cutoff_hz"):
        lowpass(y, fs, 600.0)
    with pytest.raises(ValueError, match="NaN"):
        lowpass(np.r_[y[:10], np.nan], fs, fc)


def test_gap_filling_short_and_long():
    t = np.arange(0, 2, 0.01)
    x = np.stack([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)], axis=1)[:, :, None]
    x_bad = x.copy()
    x_bad[50:53, 0] = np.nan  # 3 missing samples: span 0.04 s <= 0.05 s
    x_bad[100:120, 1] = np.nan  # 20 missing samples: span 0.21 s
    filled, reliable, gaps = fill_gaps(t, x_bad, max_gap_s=0.05)
    assert np.all(np.isfinite(filled))
    # Cubic spline through a 1 Hz sine sampled at 100 Hz: error < 1e-5 over a 4-sample gap.
    assert np.max(np.abs(filled[50:53, 0] - x[50:53, 0])) < 1e-5
    assert reliable[50:53, 0].all() and not reliable[100:120, 1].any()
    assert [(g.column, g.filled) for g in gaps] == [(0, True), (1, False)]
    assert gaps[1].duration_s == pytest.approx(0.21)


def _chain_markers(duration_s=3.0, marker_hz=100.0):
    model = make_model()
    tm = np.arange(0, duration_s, 1 / marker_hz)
    c = pinned_chain(tm, model)
    return model, tm, markers_from_points(c["points"], model)


def test_body_model_from_markers_recovers_lengths_and_foot():
    model, tm, mk = _chain_markers()
    mk[::7, 3] = np.nan  # occlusions do not matter for the medians
    est = body_model_from_markers(Subject("s", 60.0, 1.65), MarkerSeries(tm.astype(np.int64), MARKER_NAMES, mk))
    assert est.shank.length_m == pytest.approx(0.42, abs=1e-9)
    assert est.thigh.length_m == pytest.approx(0.40, abs=1e-9)
    assert est.hat.length_m == pytest.approx(0.75, abs=1e-9)
    assert est.foot_geometry.alpha_rad == pytest.approx(model.foot_geometry.alpha_rad, abs=1e-9)
    for a, b in zip(est.segments, model.segments):  # same scaling as the generating model
        assert a.mass_kg == pytest.approx(b.mass_kg) and a.inertia_kgm2 == pytest.approx(b.inertia_kgm2, rel=1e-9)
        assert a.com_along_m == pytest.approx(b.com_along_m, abs=1e-9)


def test_marker_pipeline_moments_match_truth():
    """Markers at 100 Hz -> 12 Hz filter -> splines on 1 kHz force time -> ID, vs analytic top-down moments.

    The motion (2 Hz) is far below the cut-off, so the chain must be nearly
    exact: within 0.1 % of each joint's peak moment away from the record edges
    (measured: about 0.001 %, 0.008 %, 0.05 %).
    """
    model, tm, mk = _chain_markers()
    tf = np.arange(0, 3, 0.001)
    truth = pinned_chain(tf, model)
    kin, gaps = compute_kinematics(tm, mk[..., [0, 2]], tf, model)
    assert gaps == []
    loads = inverse_dynamics_2d(kin.points_xz, kin.com_xz, kin.com_acc, kin.qdd, truth["wrench"], model)
    sel = (tf > 0.5) & (tf < 2.5)
    err = np.max(np.abs(loads.moment_ccw_nm - truth["moment_ccw"])[sel], axis=0)
    peak = np.max(np.abs(truth["moment_ccw"]), axis=0)
    assert np.all(err < 1e-3 * peak)
    np.testing.assert_allclose(kin.q[sel], truth["q"][sel], atol=1e-3)
    # Joint angles follow Eq. 2 from the true segment angles.
    rho_true = np.stack([truth["q"][:, 0] - truth["q"][:, 1] + model.foot_geometry.alpha_rad,
                         truth["q"][:, 2] - truth["q"][:, 1] + np.pi,
                         truth["q"][:, 2] - truth["q"][:, 3] + np.pi], axis=1)
    np.testing.assert_allclose(kin.rho[sel], rho_true[sel], atol=1e-3)
    assert kin.reliable[sel].all()
    # Outside the marker span the kinematics are flagged, not extrapolated.
    kin2, _ = compute_kinematics(tm, mk[..., [0, 2]], np.array([-0.1, 3.5]), model)
    assert not kin2.reliable.any() and np.all(np.isnan(kin2.q))


def _double_integral_of_ramp(t, start_s, rise_s):
    """Exact double time integral of a force rising linearly from 0 at ``start_s`` to 1 at ``start_s + rise_s``, then 1."""
    def cube(x):
        return np.maximum(x, 0.0) ** 3 / 6

    return (cube(t - start_s) - cube(t - start_s - rise_s)) / rise_s


def test_wrench_passes_the_markers_chain():
    """A 1 ms touchdown step between two 100 Hz marker frames, through the markers' chain: the closed-form double
    integral sampled at the marker stamps, low-passed there (40 Hz) and differentiated twice by scipy's not-a-knot
    ``make_interp_spline`` (not the code's CubicSpline) at the plate times; the per-leg variant (markers measured at
    100 Hz, filtered on a 1 kHz grid) likewise. A force linear in time comes back unchanged; outside the marker
    span, or with a cut-off the markers' grid cannot carry, the wrench is low-passed on the plate clock."""
    from scipy.interpolate import make_interp_spline

    tf = np.arange(0.0, 1.0, 0.001)
    tm = np.arange(0.0037, 0.99, 0.01)  # marker stamps between plate samples
    step = np.clip((tf - 0.503) / 0.001, 0.0, 1.0)  # 0 until 503 ms, 1 from 504 ms
    ramp = 0.3 + 2.0 * tf
    wrench = np.column_stack([400.0 * step, 700.0 * step, ramp])
    out = wrench_through_marker_chain(tf, wrench, tm, tm, 40.0)
    inside = (tf >= tm[0]) & (tf <= tm[-1])
    mid = (tf > 0.2) & (tf < 0.8)  # away from the ends, where filtering second differences or samples differ
    chain = lowpass(_double_integral_of_ramp(tm, 0.503, 0.001), 100.0, 40.0)
    expected = make_interp_spline(tm, chain, k=3).derivative(2)(tf[mid])
    # within 1 N of a 700 N step (measured 0.47 N: the code filters second differences, here the samples)
    np.testing.assert_allclose(out[mid, 1], 700.0 * expected, atol=1.0)
    np.testing.assert_allclose(out[mid, 0], 400.0 * expected, atol=1.0)
    np.testing.assert_allclose(out[mid, 2], ramp[mid], rtol=1e-5)
    plain = lowpass(wrench, 1000.0, 40.0)
    np.testing.assert_allclose(out[~inside], plain[~inside], rtol=1e-12, atol=1e-9)
    # Not the plate-clock filter: the step reaches the wrench as the markers' knots spread it.
    assert np.max(np.abs(out[inside, 1] - plain[inside, 1])) > 0.05 * 700
    # Per leg: markers measured at 100 Hz, splined onto the 1 kHz plate clock and filtered there: the step as the
    # 100 Hz spline's second derivative, low-passed at 1 kHz (measured 0.55 N apart, second differences vs the
    # spline's derivative across its knots; the plate-clock filter of the step is 44 N away).
    grid = tf[inside]
    out_leg = wrench_through_marker_chain(tf, wrench, tm, grid, 40.0)
    fine = lowpass(700.0 * make_interp_spline(tm, _double_integral_of_ramp(tm, 0.503, 0.001), k=3).derivative(2)(grid),
                   1000.0, 40.0)
    np.testing.assert_allclose(out_leg[inside, 1][mid[inside]], fine[mid[inside]], atol=1.0)
    np.testing.assert_allclose(wrench_through_marker_chain(tf, wrench, tm, tm, 60.0), lowpass(wrench, 1000.0, 60.0), atol=1e-9)


def test_missing_marker_raises_clear_error():
    model, tm, mk = _chain_markers(1.0)
    mk[:, 4] = np.nan
    with pytest.raises(ValueError, match="hip"):
        compute_kinematics(tm, mk[..., [0, 2]], tm, model)
