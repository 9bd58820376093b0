"""The forward gap's two-sided duration term (issue 16, session 14's option ``forward_selection.TWO_SIDED_DURATION``).

Before session 14 (and still by default) the held-out simulation is sampled at the measured times only and its
duration is its last sample: a stance simulated too long has a duration error of 0. With the option the simulated
take-off is read as the stance detector reads the measured one (the force at the detector's take-off level), on the
clock of the measured touchdown.
Checked on a noise-free null of our simulator: a softer model (longer stance) has a positive error, and the detector
itself, run over the simulated force, places the same take-off.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.stance_detection import StanceDetector
from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.forward import ground_of
from hop_impedance.discovery.identify import identify, touchdown_moments
from hop_impedance.discovery.measurement import measure_trial, weight_n
from hop_impedance.discovery.model import FittedLaw, ModelSpec
from hop_impedance.simulation.scenarios import Effects
from hop_impedance.simulation.sensors import SensorConfig, noise_free
from hop_impedance.simulation.stance_set import simulate_stance_set_recording

_CACHE: dict = {}


@pytest.fixture(autouse=True)
def two_sided(monkeypatch):
    """Every test here runs with the two-sided term."""
    monkeypatch.setattr(fs, "TWO_SIDED_DURATION", True)


def null_trial():
    """A noise-free 2.2 Hz null of our simulator (5 hops, rigid ground), measured, and its baseline identified."""
    if not _CACHE:
        rec, _ = simulate_stance_set_recording(2.2, ("rigid",), 5, 3, Effects(angle_dependent_stiffness=False,
                                               damping=False, push_off=False), noise_free(SensorConfig()))
        trial = measure_trial(rec)
        _CACHE.update(trial=trial, fit=identify(ModelSpec(), trial, trial.stances))
    return _CACHE["trial"], _CACHE["fit"]


def runs(k0_factor: float) -> list[tuple]:
    """Per stance (stance, simulation, gap figures) of the baseline with its k0 scaled by ``k0_factor``."""
    trial, (spec, coefs) = null_trial()
    coefs = np.array(coefs, float)
    coefs[:, 0] *= k0_factor
    scales, level = fs.gap_scales(trial), fs.take_off_level_n(trial)
    out = []
    for s in trial.stances:
        law = FittedLaw(spec, coefs, touchdown_moments(spec, coefs, s))
        sim = fs.simulate_for_gap(trial.chain, law, ground_of(spec, s), s)
        out.append((s, sim, fs._gap_of(sim, s, 0.0, scales, level)))
    return out


def test_a_stance_simulated_too_long_has_a_positive_duration_error():
    """k0 x 0.6 lengthens the stance (spring-mass: by ~1/sqrt(0.6) = +29 %): the duration error, the simulated
    take-off minus the measured one, both since the measured touchdown, is at least +15 ms on every stance (a 280 ms
    stance); the simulation's own end (force zero) is within 2 ms after the take-off read at the detector's level.
    Before session 14 it was 0 on every stance (the simulation sampled at the measured times only)."""
    for s, sim, gap in runs(0.6):
        assert sim.end_reason == "take_off"
        err = gap["duration_error_s"]
        assert err > 0.015
        own_end = float(s.t_s[0] + sim.t_s[-1]) - float(s.takeoff_s - s.touchdown_s)
        assert 0.0 <= own_end - err < 0.002


def test_the_detector_places_the_simulated_take_off_where_the_gap_reads_it():
    """The stance detector (``biomech.stance_detection``, the analysis' own), run over the simulated plate force
    padded with flights of zero force, finds the take-off that ``simulated_take_off_s`` reads, within 0.05 ms."""
    trial, _ = null_trial()
    level = fs.take_off_level_n(trial)
    for s, sim, _ in runs(0.8):
        dt = float(np.median(np.diff(s.t_s)))
        t_stance = s.t_s[0] + sim.t_s
        t = np.r_[t_stance[0] - dt * np.arange(300, 0, -1), t_stance, t_stance[-1] + dt * np.arange(1, 101)]
        fz = np.r_[np.zeros(300), sim.grf_n[:, 1], np.zeros(100)]
        det = StanceDetector(body_weight_n=weight_n(trial))
        det.push(t, fz)
        det.flush()
        assert det.levels_n[1] == pytest.approx(level, abs=1e-6)
        (found,) = [x for x in det.stances if x.complete]
        assert found.takeoff_s == pytest.approx(fs.simulated_take_off_s(sim, s, level), abs=5e-5)
