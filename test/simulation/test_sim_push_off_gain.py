"""The hop-by-hop push-off controller's gain (HoppingConfig.push_off_gain): default the deadbeat correction."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from hop_impedance.simulation.hopping_trial import _hop_push_scale
from hop_impedance.simulation.scenarios import hopping_config

CAL = SimpleNamespace(speed_m_s=1.0, push_scale=1.0, d_speed_d_scale=0.5)


@pytest.fixture(scope="module")
def config():
    return hopping_config(2.2, "hard", 1, variability=False)[1]


def test_default_gain_is_the_deadbeat_correction(config):
    assert config.push_off_gain == 1.0
    # touchdown 0.1 m/s too slow: deadbeat adds 0.1 / 0.5 to the scale
    assert _hop_push_scale(config, CAL, 0.9, np.random.default_rng(0)) == pytest.approx(1.2)


def test_gain_scales_the_correction(config):
    half = dataclasses.replace(config, push_off_gain=0.5)
    assert _hop_push_scale(half, CAL, 0.9, np.random.default_rng(0)) == pytest.approx(1.1)
    off = dataclasses.replace(config, push_off_gain=0.0)
    assert _hop_push_scale(off, CAL, 0.9, np.random.default_rng(0)) == pytest.approx(1.0)


def test_negative_gain_rejected(config):
    with pytest.raises(ValueError, match="push_off_gain"):
        dataclasses.replace(config, push_off_gain=-0.5)
