"""Held-out stances simulated from the measured state after the impact (issue 16, session 22; option, off).

Our simulator lands its segments at rest and the 12 Hz low-pass smears the impact's jump of the joint rates over the
stance's first tens of ms, which the soft 1.53 Hz stance amplifies: the generating law (``M_td`` estimated as a
candidate's) simulated from the measured touchdown state of this null takes off 69 ms RMS off its measured take-off
(two-sided; -96..+103 ms; ``bench/discovery_touchdown_sensitivity.py --freq 1.53 --seed 0 --noisy --start-after
0.06``). From the measured state 60 ms after touchdown (``forward_selection.SIMULATE_FROM_S`` = 0.06), the same for
every model, 6.5 ms (2.2 ms noise-free), and its held-out gap falls from 0.21 to 0.002.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.identify import touchdown_moments
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import FittedLaw, ModelSpec
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE, _stance_set_law, simulate_stance_set_recording

NULL = Effects(angle_dependent_stiffness=False, damping=False, push_off=False)


def _true_law_runs(trial, k0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The generating law (``M_td`` estimated as a candidate's) simulated as discovery simulates a held-out stance:
    (simulated minus measured take-off, ms; gap G) per stance."""
    level, scales = fs.take_off_level_n(trial), fs.gap_scales(trial)
    errors, gaps = [], []
    for s in trial.stances:
        law = FittedLaw(ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), fs.identification_reference(s))
        sim = fs.simulate_for_gap(trial.chain, law, RIGID_NO_BOUNCE, s)
        errors.append(1e3 * (fs.simulated_take_off_s(sim, s, level) - (s.takeoff_s - s.touchdown_s)))
        gaps.append(fs._gap_of(sim, s, 0.0, scales, level)["gap"])
    return np.array(errors), np.array(gaps)


def _null_1p53(sensors: SensorConfig):
    rec, _ = simulate_stance_set_recording(1.53, ("rigid",), 8, 0, NULL, sensors)
    trial = measure_trial(rec)
    law, _, _ = _stance_set_law(trial.chain, 1.53, NULL, None, RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    return trial, np.array(law.parts[0].k0, float)[:, None]


@pytest.mark.slow
@pytest.mark.parametrize(("sensors", "late_rms_ms", "late_max_ms", "late_gap"),
                         [(noise_free(SensorConfig()), 3.5, 7.0, 0.002), (SensorConfig(), 9.0, 20.0, 0.005)],
                         ids=["noise-free", "noisy"])
def test_the_true_law_takes_off_on_time_from_the_state_after_the_impact_at_1p53_hz(monkeypatch, sensors, late_rms_ms,
                                                                                   late_max_ms, late_gap):
    trial, k0 = _null_1p53(sensors)
    monkeypatch.setattr(fs, "TWO_SIDED_DURATION", True)  # a stance simulated too long counts too
    from_touchdown, gaps_td = _true_law_runs(trial, k0)
    monkeypatch.setattr(fs, "SIMULATE_FROM_S", 0.06)
    late, gaps_late = _true_law_runs(trial, k0)
    assert np.sqrt(np.mean(from_touchdown**2)) > 40.0  # 65.7 / 69.1 ms
    assert np.sum(np.abs(from_touchdown) > 50.0) >= 3
    assert np.mean(gaps_td) > 0.1  # 0.19 / 0.21
    assert np.sqrt(np.mean(late**2)) < late_rms_ms  # 2.2 / 6.5 ms
    assert np.max(np.abs(late)) < late_max_ms  # 5.1 / 15.0 ms
    assert np.mean(gaps_late) < late_gap  # 0.0005 / 0.0022


def test_the_late_start_carries_the_measured_force_and_is_compared_from_there(monkeypatch):
    """From the state 40 ms in: the toe starts at the depth where the rigid ground carries the measured (low-passed)
    plate force, the simulation is sampled and compared from that sample on, and the measured state at sample 0 is the
    touchdown state itself."""
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 5, 3, NULL, SensorConfig())
    trial = measure_trial(rec)
    monkeypatch.setattr(fs, "SIMULATE_FROM_S", 0.04)
    law, _, _ = _stance_set_law(trial.chain, 2.2, NULL, None, RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    k0 = np.array(law.parts[0].k0, float)[:, None]
    for s in trial.stances:
        k = fs.start_index(s)
        assert s.t_s[k] >= 0.04 > s.t_s[k - 1]
        fl = FittedLaw(ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), fs.identification_reference(s))
        start = fs.late_start(trial.chain, fl, RIGID_NO_BOUNCE, s)
        assert start.t_s == pytest.approx(s.t_s[k] - s.t_s[0])
        force = RIGID_NO_BOUNCE.force_n(start.state.g[1], start.state.gd[1])
        assert force == pytest.approx(s.fz_lp_n[k], rel=1e-6) and start.state.g[1] < 0
        sim = fs.simulate_for_gap(trial.chain, fl, RIGID_NO_BOUNCE, s)
        assert sim.start_s == start.t_s and sim.t_s[0] == s.t_s[k]
        out = fs._gap_of(sim, s, 0.0, fs.gap_scales(trial), np.nan, samples=True)
        assert out["samples"].shape[0] == min(len(sim.t_s), len(s.t_s) - k)
        # sampled on the clock a run from the touchdown has (0 at the touchdown state's sample, s.t_s[0] ~ 1 ms after
        # the detected touchdown), so the first compared sample is ~1 ms after the start: the force has risen ~2 %
        assert abs(sim.grf_n[0, 1] - s.fz_lp_n[k]) < 0.03 * s.fz_lp_n[k]
    monkeypatch.setattr(fs, "SIMULATE_FROM_S", 0.0)
    s = trial.stances[0]
    assert fs.start_index(s) == 0
    assert np.array_equal(fs.late_start(trial.chain, fl, RIGID_NO_BOUNCE, s).state.gd, s.touchdown.gd)


def _run_and_gap(monkeypatch, trial, law, s, simulate_from):
    """Stance ``s`` simulated as discovery does with ``SIMULATE_FROM_S`` = ``simulate_from``, and its gap figures."""
    monkeypatch.setattr(fs, "SIMULATE_FROM_S", simulate_from)
    sim = fs.simulate_for_gap(trial.chain, law, RIGID_NO_BOUNCE, s)
    return sim, fs._gap_of(sim, s, 0.0, fs.gap_scales(trial), np.nan, samples=True)


def test_two_segments_compare_the_touchdown_run_before_the_start_and_the_late_run_after(monkeypatch):
    """``TWO_SEGMENT`` (session 23): the compared samples before the start sample are the run from the touchdown's
    (integrated only that far, so equal to the default run's to the solver's tolerance, not to the bit), those from it
    on the late run's to the bit; the duration is the late run's, the net work the two runs' together against the
    whole measured stance's."""
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 3, 3, NULL, SensorConfig())
    trial = measure_trial(rec)
    law, _, _ = _stance_set_law(trial.chain, 2.2, NULL, None, RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    k0 = np.array(law.parts[0].k0, float)[:, None]
    scales = fs.gap_scales(trial)
    monkeypatch.setattr(fs, "TWO_SEGMENT", True)
    for s in trial.stances:
        fl = FittedLaw(ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), fs.identification_reference(s))

        default, from_td = _run_and_gap(monkeypatch, trial, fl, s, None)  # TWO_SEGMENT alone changes nothing
        assert not isinstance(default, fs.TwoSegmentRun)
        two, joined = _run_and_gap(monkeypatch, trial, fl, s, 0.04)
        k = fs.start_index(s)
        monkeypatch.setattr(fs, "TWO_SEGMENT", False)
        _, late = _run_and_gap(monkeypatch, trial, fl, s, 0.04)
        monkeypatch.setattr(fs, "TWO_SEGMENT", True)
        assert isinstance(two, fs.TwoSegmentRun) and two.k == k > 0 and two.reached == k
        assert np.array_equal(two.measured_index, np.arange(k + len(two.late.t_s)))
        assert np.allclose(joined["samples"][:k], from_td["samples"][:k], rtol=0, atol=1e-4)
        assert np.array_equal(joined["samples"][k:], late["samples"])
        assert joined["duration_error_s"] == late["duration_error_s"]
        early_work = fs._simulated_work_j(two.early, None)
        assert joined["net_work_j"] == pytest.approx(early_work + late["net_work_j"], abs=1e-9)
        measured = fs.measured_net_works_j(trial, compared=True)[trial.stances.index(s)]
        assert measured == pytest.approx(fs.measured_net_work_j(s), abs=1e-9)
        assert joined["terms"][1] * scales[8] == pytest.approx(joined["net_work_j"] - measured, abs=1e-9)


def test_a_touchdown_run_that_takes_off_before_the_start_is_skipped_there_or_compared_in_flight(monkeypatch):
    """A law twice the generator's stiffness leaves the ground at once from the measured touchdown state (its run ends
    at 20 samples, before the start sample 40): with ``TWO_SEGMENT`` the samples between are not compared, with
    ``TWO_SEGMENT_FLIGHT`` they are, against zero force and the last angles, and the measured work over the whole
    stance."""
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 3, 3, NULL, SensorConfig())
    trial = measure_trial(rec)
    law, _, _ = _stance_set_law(trial.chain, 2.2, NULL, None, RIGID_NO_BOUNCE, DEFAULT_TOUCHDOWN_RHO)
    k0 = 2.0 * np.array(law.parts[0].k0, float)[:, None]
    scales = fs.gap_scales(trial)
    s = trial.stances[0]
    fl = FittedLaw(ModelSpec(), k0, touchdown_moments(ModelSpec(), k0, s), fs.identification_reference(s))
    monkeypatch.setattr(fs, "TWO_SEGMENT", True)
    two, skipped = _run_and_gap(monkeypatch, trial, fl, s, 0.04)
    j, k = len(two.early.t_s), two.k
    assert two.early.end_reason == "take_off" and 1 < j < k
    assert two.reached == j and skipped["samples"].shape[0] == j + len(two.late.t_s)
    monkeypatch.setattr(fs, "TWO_SEGMENT_FLIGHT", True)
    _, flight = _run_and_gap(monkeypatch, trial, fl, s, 0.04)
    assert two.reached == k and flight["samples"].shape[0] == k + len(two.late.t_s)
    assert np.array_equal(flight["samples"][j:k, 0], s.fz_raw_n[j:k] / scales[0])
    assert np.array_equal(flight["samples"][j:k, 1], (s.rho_rad[j:k, 0] - two.early.rho_rad[-1, 0]) / scales[1])
    assert np.array_equal(flight["samples"][k:], skipped["samples"][j:])
    assert flight["net_work_j"] == skipped["net_work_j"]
    work_error = flight["terms"][1] * scales[8]
    assert work_error == pytest.approx(flight["net_work_j"] - fs.measured_net_work_j(s), abs=1e-9)
