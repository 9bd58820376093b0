"""Hop sequencing, sensors, truth file, command line and the round trip through the analysis."""

from __future__ import annotations

import numpy as np
import pytest
from moment_truth import analysed_and_true_moments

from hop_impedance.recording import MARKER_NAMES
from hop_impedance.simulation.ground import HARD, SOFT
from hop_impedance.simulation.hopping_trial import (
    calibrate,
    leg_stiffness_n_per_m,
    scale_push_off,
    simulate_hopping,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.scenarios import Effects, hopping_config
from hop_impedance.simulation.sensors import SensorConfig, noise_free, sample_recording
from hop_impedance.simulation.simulate import simulate_recording
from hop_impedance.simulation.stance import simulate_stance
from hop_impedance.simulation.truth import load_truth, truth_path


@pytest.fixture(scope="module")
def trial_22():
    chain, cfg = hopping_config(2.2, "hard", 4)
    return simulate_hopping(chain, cfg, seed=1)


@pytest.fixture(scope="module")
def clean_recording():
    return simulate_recording(2.2, "hard", 4, seed=1, sensors=noise_free(SensorConfig()))


def test_hopping_holds_the_target_frequency_in_place(trial_22):
    assert trial_22.stop_reason == ""
    assert trial_22.calibration.success
    td = np.array([s.t_touchdown_s for s in trial_22.stances])
    assert len(td) == 4
    periods = np.diff(td)
    assert np.mean(periods) == pytest.approx(1 / 2.2, rel=0.03)
    assert np.std(periods) > 1e-4  # hop-to-hop variability is present
    x_toe = [s.touchdown.g[0] for s in trial_22.stances]
    assert np.ptp(x_toe) < 0.1  # stays on the plate
    for rec in trial_22.stances:
        assert rec.stance.end_reason == "take_off"
        assert 0.1 < rec.stance.duration_s < 0.35


def test_flight_is_ballistic_and_force_free(trial_22):
    fl = trial_22.flights[2]
    t = np.linspace(fl.t_start_s + 1e-6, fl.t_start_s + fl.duration_s - 1e-6, 50)
    state = trial_22.sample(t)
    assert np.all(state["grf_n"] == 0)
    from hop_impedance.simulation.dynamics import body_com

    z = np.array([body_com(trial_22.chain, g)[1] for g in state["g"]])
    acc = np.polyfit(t, z, 2)[0] * 2
    assert acc == pytest.approx(-9.81, rel=1e-6)
    # Continuity of the toe at take-off and touchdown (no jumps in the markers).
    t_to, t_td = fl.t_start_s, fl.t_start_s + fl.duration_s
    eps = 1e-7
    a, b = trial_22.sample(np.array([t_to - eps, t_to + eps, t_td - eps, t_td + eps]))["g"].reshape(2, 2, 6)
    assert np.abs(a[0] - a[1]).max() < 1e-5 and np.abs(b[0] - b[1]).max() < 1e-5


def test_same_seed_same_trial_and_no_variability_means_identical_hops():
    chain, cfg = hopping_config(2.2, "hard", 3, variability=False)
    tr = simulate_hopping(chain, cfg, seed=5)
    d = [s.stance.duration_s for s in tr.stances]
    assert max(d) - min(d) < 2e-3


def test_without_push_off_the_lossy_hops_decay():
    chain, cfg = hopping_config(2.2, "hard", 3, Effects(push_off=False), variability=False)
    tr = simulate_hopping(chain, cfg, seed=1)
    speeds = [-s.touchdown.gd[1] for s in tr.stances]  # toe z speed at touchdown ~ COM speed
    assert len(speeds) >= 2
    assert speeds[1] < 0.95 * speeds[0]


def test_unexpected_hard_surface_lowers_leg_stiffness_as_in_seed_001():
    """Same time-based activation, same touchdown: leg stiffness lower on unexpected hard than on expected soft.

    Also the joint-level picture of seed 001 and of Moritz & Farley 2004
    (/work/shared/data_candidates/published_refs): more ankle and knee flexion,
    less extra hip flexion, and the difference already there 52 ms after landing.
    """
    chain, cfg = hopping_config(2.2, "soft", 1, Effects(time_activation=True), variability=False)
    q = touchdown_posture(chain, np.array(cfg.touchdown_rho_rad))
    cal = calibrate(chain, cfg, q)
    assert cal.success
    law = scale_push_off(cfg.law, cal.push_scale)
    td = touchdown_state(chain, q, np.array([0.0, -cal.speed_m_s]), 0.0)
    soft_stance, hard_stance = simulate_stance(chain, law, SOFT, td), simulate_stance(chain, law, HARD, td)
    soft, hard = leg_stiffness_n_per_m(chain, soft_stance), leg_stiffness_n_per_m(chain, hard_stance)
    assert hard[0] < 0.97 * soft[0]  # lower leg stiffness ...
    assert hard[2] > soft[2]  # ... from larger leg compression
    assert hard[1] > soft[1]  # while the peak force is higher (seed 001, Fig. 4A)
    # Seed 001: "increased flexion in the ankle and knee joint and, to a lesser extent, in the hip joint".
    extra = (np.max(hard_stance.rho_rad, axis=0) - hard_stance.rho_rad[0]) - (
        np.max(soft_stance.rho_rad, axis=0) - soft_stance.rho_rad[0]
    )
    assert extra[0] > 0.02 and extra[1] > 0.02 and 0.0 < extra[2] < min(extra[0], extra[1])  # measured 0.048/0.044/0.032
    # Moritz & Farley 2004 (abstract): on the surprise hard surface joint flexion increased within 52 ms of landing.
    ankle_at_52ms = [np.interp(0.052, st.t_s, st.rho_rad[:, 0]) for st in (hard_stance, soft_stance)]
    assert ankle_at_52ms[0] - ankle_at_52ms[1] > 0.02  # rad (measured 0.07)


def test_sensor_geometry_cop_and_effects(trial_22):
    rng = np.random.default_rng(0)
    subject = __import__("hop_impedance.simulation.scenarios", fromlist=["SEED_SUBJECT"]).SEED_SUBJECT
    clean, _ = sample_recording(trial_22, noise_free(SensorConfig()), subject, rng)
    # Segment lengths from noise-free markers are constant and equal the model's.
    pos = clean.markers.positions_m
    knee_hip = np.linalg.norm(pos[:, 4] - pos[:, 3], axis=1)
    assert np.ptp(knee_hip) < 1e-9
    assert knee_hip[0] == pytest.approx(trial_22.chain.length_m[2])
    assert np.all(pos[:, :, 1] == -0.1)
    # COP on the force's line of action: x_toe - z_toe Fx / Fz.
    fz = clean.force.force_n[:, 2]
    stance = fz > 200
    state = trial_22.sample((clean.force.stamp_ns - clean.start_ns) * 1e-9)
    g, f = state["g"][stance], clean.force.force_n[stance]
    expected = g[:, 0] - g[:, 1] * f[:, 0] / f[:, 2]
    assert np.abs(clean.force.cop_x_m()[stance] - expected).max() < 1e-9
    # Noise, offset, occlusions and stream delay.
    cfg = SensorConfig(force_noise_n=3.0, force_offset_n=25.0, marker_noise_m=0.002, occlusions_per_s=4.0,
                       marker_time_offset_s=0.02)
    noisy, st = sample_recording(trial_22, cfg, subject, np.random.default_rng(1))
    flight = clean.force.force_n[:, 2] == 0
    assert np.mean(noisy.force.force_n[flight, 2]) == pytest.approx(25.0, abs=0.3)
    assert np.std(noisy.force.force_n[flight, 0]) == pytest.approx(3.0, rel=0.1)
    nan_rows = np.isnan(noisy.markers.positions_m).any(axis=(1, 2))
    assert nan_rows.any() and len(st["occlusions"]) > 0
    delayed = noisy.markers.positions_m[~nan_rows] - clean.markers.positions_m[~nan_rows]
    assert np.nanstd(delayed[:, 2, 1]) == pytest.approx(0.002, rel=0.15)  # y has only the noise
    shifted = trial_22.sample(np.clip((clean.markers.stamp_ns - clean.start_ns) * 1e-9 - 0.02, 0, None))["g"][:, 0:2]
    resid = noisy.markers.positions_m[~nan_rows, 0, ::2] - shifted[~nan_rows]
    assert np.abs(resid).max() < 0.002 * 6  # toe marker = delayed toe + noise


def test_truth_events_match_force_plate_and_joint_samples(clean_recording):
    rec, truth = clean_recording
    fz = rec.force.force_n[:, 2]
    t = (rec.force.stamp_ns - rec.start_ns) * 1e-9
    on = np.nonzero((fz[1:] > 0) & (fz[:-1] <= 0))[0] + 1
    assert len(on) == len(truth["stances"])
    for k, s in zip(on, truth["stances"]):
        assert t[k] - s["touchdown_s"] == pytest.approx(0.0, abs=1.01e-3)
        assert s["touchdown_stamp_ns"] == rec.start_ns + round(s["touchdown_s"] * 1e9)
        m = np.array(s["samples"]["moments_nm"])
        parts = np.array(s["samples"]["eq3_moments_nm"]) + np.array(s["samples"]["push_off_moments_nm"]) + np.array(
            s["samples"]["trunk_balance_moments_nm"])
        assert np.abs(m - parts).max() < 1e-3
        assert set(s["impedance"]) == {"ankle", "knee", "hip"}
        assert s["impedance"]["ankle"]["k0"] == pytest.approx(301.4)
        assert 2.5 < s["peak_grf_bw"] < 5.0
    assert truth["effects"]["push_off"] is True


def test_command_line_writes_small_recording_and_truth(tmp_path):
    from hop_impedance.cli.main import main

    out = tmp_path / "sim.mcap"
    code = main(["simulate", "--freq", "2.2", "--hops", "2", "--seed", "3", "--out", str(out), "--no-damping",
                 "--force-offset", "10"])
    assert code == 0
    truth = load_truth(truth_path(out))
    assert truth["effects"]["damping"] is False and truth["sensors"]["force_offset_n"] == 10.0
    assert out.stat().st_size < 2e6 and truth_path(out).stat().st_size < 2e6
    io = pytest.importorskip("hop_impedance.io.recording_io")
    loaded = io.load_recording(out)
    assert loaded.markers.names == MARKER_NAMES
    assert len(loaded.force) == truth["sensors"]["n_force_samples"]
    assert main(["simulate", "--out", str(tmp_path / "x.mcap"), "--hops", "0"]) == 2


def test_truth_energy_budget_closes_hop_by_hop_and_the_push_off_replaces_the_losses(clean_recording):
    """Per-hop energy budget in the truth file (issue 17): in each stance the works of push-off, Eq. 3 law,
    trunk balance and ground add up to E(take-off) - E(touchdown); over a whole hop (stance + following
    flight) they add up to the change of touchdown energy, so the push-off is exactly what damping, the
    ground, springs left at take-off and the flight take away (up to the hop-to-hop change)."""
    _, truth = clean_recording
    stances = truth["stances"]
    for s in stances:
        e = s["energy_j"]
        assert abs(e["residual_j"]) < 0.1  # J, trapezoid at 0.2 ms (measured < 0.05)
        assert e["push_off_j"] > 1.0 and e["damping_j"] > 0.0 and e["ground_j"] < 0.0
        assert e["eq3_work_j"] == pytest.approx(-(e["damping_j"] + e["springs_left_j"]))
    for s, nxt in zip(stances[:-1], stances[1:]):
        e = s["energy_j"]
        works = e["push_off_j"] + e["eq3_work_j"] + e["trunk_balance_j"] + e["ground_j"] + e["flight_j"]
        assert nxt["energy_j"]["e_touchdown_j"] - e["e_touchdown_j"] == pytest.approx(works, abs=0.1)
        assert e["flight_j"] < -0.5  # the default (prescribed) flight discards segment energy
    assert "flight_j" not in stances[-1]["energy_j"]


@pytest.fixture(scope="module")
def clean_recording_250hz():
    from dataclasses import replace

    return simulate_recording(2.2, "hard", 4, seed=1, sensors=replace(noise_free(SensorConfig()), marker_rate_hz=250.0))


@pytest.mark.parametrize("markers", ["100 Hz", "250 Hz"])
def test_round_trip_inverse_dynamics_recovers_true_moments(clean_recording, clean_recording_250hz, markers):
    """Noise-free recording -> analyze_recording -> ID moments vs the simulator's true moments (issue 4: 2 %).

    Cut-off 20 Hz (noise-free data; the default 12 Hz is meant for noisy data).
    RMS error in % of each joint's peak, worst stance, 2.2 Hz with push-off:
    with 250 Hz markers (the contract's highest rate) the whole contact is
    within 2 % for every joint (measured 0.5 / 0.6 / 1.3 %); with 100 Hz
    markers the middle 80 % is (0.3 / 0.6 / 1.8 %) and the whole contact is
    0.5 / 0.9 / 2.05 %: the hip at touchdown, where the seed's hard law starts
    with a force step c |y'| (~240 N) that 100 Hz markers cannot follow. (The
    take-off used to end with a 27-85 N step of the horizontal force: 4-5 % at
    the hip before the simulator limited friction.)
    """
    pytest.importorskip("hop_impedance.biomech.analysis")
    rec, truth = clean_recording if markers == "100 Hz" else clean_recording_250hz
    for est, true in analysed_and_true_moments(rec, truth):
        ok = np.isfinite(est).all(axis=1)
        assert ok.mean() > 0.95
        n = len(true)
        inner = np.zeros(n, bool)
        inner[int(0.1 * n):int(0.9 * n)] = True
        peak = np.abs(true).max(axis=0)

        def rms(sel, est=est, true=true, peak=peak):
            return np.sqrt(np.mean((est[sel] - true[sel]) ** 2, axis=0)) / peak

        assert np.all(rms(ok & inner) < 0.02), rms(ok & inner)
        assert np.all(rms(ok) < (0.02 if markers == "250 Hz" else [0.02, 0.02, 0.025])), rms(ok)


@pytest.mark.parametrize("name", [n for n in Effects.names() if n != "push_off"])
def test_each_law_effect_switches_on_its_own_and_keeps_a_sane_stance(name):
    """Toggling one effect changes the moments measurably; the stance still ends in take-off."""
    base = Effects(push_off=False)
    flipped = Effects(**{**base.to_dict(), name: not getattr(base, name)})
    out = []
    for eff in (base, flipped):
        chain, cfg = hopping_config(2.2, "hard", 1, eff, variability=False)
        q = touchdown_posture(chain, np.array(cfg.touchdown_rho_rad))
        st = simulate_stance(chain, cfg.law, cfg.surface, touchdown_state(chain, q, np.array([0.0, -1.2]), 0.0),
                             sample_times_s=np.linspace(0, 0.15, 151))
        assert st.end_reason == "take_off"
        assert np.abs(st.omega_rad_s).max() < 30.0  # no whipping segment
        out.append(st.moments_nm)
    assert np.abs(out[1] - out[0]).max() > 0.5
