"""Discovery workflow on simulated recordings with a known hidden effect (issue 8).

Recordings come from the stance-set generator (8-10 independent stances,
default sensor noise: 2 N force, 1 mm markers) and are cached per session.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hop_impedance.cli.main import main as cli_main
from hop_impedance.discovery.identify import fit_compliance, fit_offset, identify
from hop_impedance.discovery.measurement import measure_trial, shift_marker_stream
from hop_impedance.discovery.model import EFFECT_NAMES, ModelSpec, push_profile
from hop_impedance.discovery.workflow import discover
from hop_impedance.io.recording_io import save_recording
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig
from hop_impedance.simulation.stance_set import simulate_stance_set_recording

BASE = dict(angle_dependent_stiffness=False, damping=False, push_off=False)
_CACHE: dict = {}


def recording(name: str, seed: int = 2):
    """Cached simulated recording of a named case."""
    cases = {
        "null": ({}, ("rigid",), {}),
        "angle": ({"angle_dependent_stiffness": True}, ("rigid",), {}),
        "soft": ({}, ("soft",), {}),
        "offset": ({}, ("rigid",), {"force_offset_n": 15.0}),
        "latency": ({}, ("rigid",), {"marker_time_offset_s": 0.01}),
        "push": ({"push_off": True}, ("rigid",), {}),
    }
    key = (name, seed)
    if key not in _CACHE:
        law, surfaces, sensors = cases[name]
        _CACHE[key] = simulate_stance_set_recording(2.2, surfaces, 10, seed=seed, effects=Effects(**{**BASE, **law}),
                                                    sensors=SensorConfig(**sensors), rtol=1e-6)[0]
    return _CACHE[key]


def test_effect_names_are_the_issues():
    assert EFFECT_NAMES == ("angle_dependent_stiffness", "rate_dependent_stiffness", "joint_damping",
                            "surface_compliance", "time_dependent_activation", "stream_latency",
                            "force_plate_offset", "active_push_off")


def test_push_profile_is_the_simulators_sin2_pulse():
    from hop_impedance.simulation.impedance_laws import PushOff

    t = np.linspace(0, 0.4, 401)
    ref = PushOff(np.ones(3), 0.1, 0.15).profile(t)
    assert np.allclose(push_profile(t, 0.1, 0.15), ref)


def test_baseline_stiffness_recovers_the_simulated_k0():
    """Null recording: the baseline's k0 per joint is the simulated constant stiffness (Table 2 at 2.2 Hz)."""
    trial = measure_trial(recording("null"))
    _, coefs = identify(ModelSpec(), trial, trial.stances)
    assert coefs[:, 0] == pytest.approx([301.4, 230.9, 175.4], rel=0.1)


def test_offset_and_latency_parameters_match_the_sensor_truth():
    trial = measure_trial(recording("offset"))
    assert fit_offset(trial.stances) == pytest.approx(15.0, abs=0.5)
    trial = measure_trial(recording("latency"))
    spec, _ = identify(ModelSpec(), trial, trial.stances, "stream_latency")
    assert spec.latency_s == pytest.approx(0.01, abs=0.002)


def test_soft_surface_displacement_law_matches_seed_001():
    """Soft surface Fz = 7.5e4 |y|^1.4 - 68.4 y': exponent p = 1/n near 1/1.4 and 1500 N gives ~6.1 cm.

    Measured: p = 0.6 (grid 0.5/0.6/0.7; the law's viscous term and the low-pass
    bias the static fit), 6.8 cm at 1500 N (+11 %).
    """
    trial = measure_trial(recording("soft"))
    c, p = fit_compliance(trial.stances, 0.0)
    assert p == pytest.approx(1 / 1.4, abs=0.15)
    assert c * 1500.0**p == pytest.approx((1500 / 7.5e4) ** (1 / 1.4), rel=0.15)


def test_shift_marker_stream_moves_stamps_earlier():
    rec = recording("null")
    shifted = shift_marker_stream(rec, 0.01)
    assert np.all(rec.markers.stamp_ns - shifted.markers.stamp_ns == 10_000_000)


@pytest.mark.parametrize("name,expected", [
    ("null", []),  # joint_damping shrinks its held-out gap by 21 % here but worsens the energy balance
    # measured (issue 16, second session): the stiffness shrinks the held-out gap by 90 % (p = 2e-8); the
    # false second step of the first session is gone, but narrowly: stream_latency then shrinks it by 9.7 %
    # (p = 0.009), just under the 10 % relevance floor, and damping by 16 % at p = 0.007 > 0.05/7
    ("angle", ["angle_dependent_stiffness"]),
])
def test_hidden_effect_is_named_and_nothing_else(name, expected):
    doc = discover(recording(name))
    assert doc["effects_found"] == expected, doc["selection"]["rounds"]


def test_too_few_stances_is_a_clear_error():
    rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 3, seed=1, rtol=1e-6)
    with pytest.raises(ValueError, match="at least 5 usable stances"):
        discover(rec)


def test_cli_writes_schema_json_and_figures(tmp_path):
    path = tmp_path / "rec.mcap"
    save_recording(path, recording("offset"))
    out = tmp_path / "out.json"
    assert cli_main(["discover", str(path), "--json", str(out), "--report", str(tmp_path / "rep"),
                     "--rrd", str(tmp_path / "d.rrd")]) == 0
    doc = json.loads(out.read_text())
    assert doc["effects_found"] == ["force_plate_offset"]
    step = doc["steps"][0]
    assert {"effect", "evidence", "parameters", "gap_before", "gap_after", "p_value"} <= set(step)
    assert step["parameters"]["offset_n"] == pytest.approx(15.0, abs=0.5)
    assert step["gap_after"]["total"] < step["gap_before"]["total"]
    assert step["gap_after"]["grf"]["rms"] < step["gap_before"]["grf"]["rms"]
    assert doc["final_gap"] == step["gap_after"] and "baseline_gap" in doc
    assert (tmp_path / "rep" / "gap_per_step.png").stat().st_size > 1000
    assert (tmp_path / "d.rrd").stat().st_size > 1000
