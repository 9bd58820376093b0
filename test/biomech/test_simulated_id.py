"""Inverse dynamics against the simulator's true joint moments when the markers resolve the stance edges.

The simulated hard-surface stance starts with a force step (the surface law
Fz = 3.1e6 y^2 - 186.3 ydot is at 140-470 N 1 ms after touchdown) and ends
with the horizontal force still at 27-85 N at the last sample before
take-off (Fz 1-24 N), figures printed by bench/id_error_budget.py (see the
module docstring of test/impedance/test_simulated_recordings.py). No low-pass that removes marker noise
can follow those edges, so the 100 Hz / 12-20 Hz analysis of the recordings
misses the true moment there. Here the same noise-free trial is sampled with
1 kHz markers and analysed at a 100 Hz cut-off: then every joint moment must
match the truth, which checks the whole chain (MCAP, stance detection, plate
zeroing, filtering, spline kinematics, body model from markers, Newton-Euler)
against the simulator's independent ODE integration, and shows that the
errors of the 100 Hz case come from the bandwidth, not from the equations.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

SEED = 11
FREQ_HZ = 1.87
N_HOPS = 4


@pytest.fixture(scope="module")
def resolved_trial(tmp_path_factory):
    """Noise-free push-off-free trial with 1 kHz markers, analysed at 100 Hz; returns (analysis, truth)."""
    from dataclasses import replace

    from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
    from hop_impedance.biomech.body_model import body_model_from_stature
    from hop_impedance.io.recording_io import load_recording
    from hop_impedance.simulation.hopping_trial import simulate_hopping
    from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects, hopping_config
    from hop_impedance.simulation.sensors import SensorConfig, noise_free, sample_recording
    from hop_impedance.simulation.simulate import write_simulated_recording
    from hop_impedance.simulation.truth import trial_truth

    effects = Effects(push_off=False)
    chain, config = hopping_config(FREQ_HZ, "hard", N_HOPS, effects)
    trial = simulate_hopping(chain, config, seed=SEED)
    sensors = noise_free(replace(SensorConfig(), marker_rate_hz=1000.0))
    rec, sensor_truth = sample_recording(trial, sensors, SEED_SUBJECT, np.random.default_rng([SEED, 1]))
    truth = trial_truth(trial, sensors, SEED_SUBJECT, body_model_from_stature(SEED_SUBJECT), effects.to_dict(), sensor_truth, {})
    path = tmp_path_factory.mktemp("resolved") / "resolved.mcap"
    write_simulated_recording(path, rec, truth)
    analysis = analyze_recording(load_recording(path), AnalysisOptions(marker_cutoff_hz=100.0, force_cutoff_hz=100.0))
    return analysis, json.loads(path.with_name("resolved.truth.json").read_text())


def _rms_errors(analysis, truth) -> np.ndarray:
    """Per stance and joint: RMS of (ID - true) moment over the middle 80 % and the whole stance, / peak |true|.

    Shape (stances, 2, 3); the truth is interpolated onto the analysis' force times.
    """
    ours = {round(s.touchdown_s, 2): s for s in analysis.stances if s.joints is not None}
    out = []
    for ts in truth["stances"]:
        s = ours.get(round(ts["touchdown_s"], 2))
        if s is None:
            continue
        t_true = np.asarray(ts["samples"]["t_s"], float)
        m_true = np.asarray(ts["samples"]["moments_nm"], float)
        t = s.joints.time_s + s.touchdown_s
        inside = (t >= t_true[0]) & (t <= t_true[-1])
        phase = (t[inside] - ts["touchdown_s"]) / (ts["takeoff_s"] - ts["touchdown_s"])
        mid = (phase >= 0.1) & (phase <= 0.9)
        row = []
        for sel in (mid, np.ones_like(mid)):
            err = [
                np.sqrt(np.mean((s.joints.moment_nm[inside, j][sel] - np.interp(t[inside][sel], t_true, m_true[:, j])) ** 2))
                / np.max(np.abs(m_true[:, j]))
                for j in range(3)
            ]
            row.append(err)
        out.append(row)
    return np.asarray(out)


@pytest.mark.slow
def test_moments_match_the_simulator_when_markers_resolve_the_edges(resolved_trial):
    """Middle 80 %: within 0.2 % of peak; whole stance: within 2 % of peak (issue #4's target), every joint.

    Measured (this seed, 4 stances): middle 80 % at most 0.003 % (ankle),
    0.02 % (knee), 0.06 % (hip); whole stance at most 0.04 %, 0.55 %, 1.76 %:
    what remains is the touchdown step, a few milliseconds wide even at 100 Hz.
    """
    analysis, truth = resolved_trial
    errors = _rms_errors(analysis, truth)
    assert errors.shape[0] >= N_HOPS - 1, "stances lost on the way"
    assert np.all(errors[:, 0, :] < 0.002), errors[:, 0, :]
    assert np.all(errors[:, 1, :] < 0.02), errors[:, 1, :]
