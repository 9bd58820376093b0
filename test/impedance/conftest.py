"""Shared helpers for the impedance tests."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.impedance.stance_fit import FitOptions, fit_joint_stance
from hop_impedance.impedance.synthetic import synthetic_stance

#: Low-pass cutoff of the synthetic noise (Hz), known to the fit as it would be from the pipeline.
NOISE_BANDWIDTH_HZ = 12.0
FREQUENCIES_HZ = (1.53, 1.87, 2.20)
JOINTS = ("ankle", "knee", "hip")


def fit_synthetic(stance, **option_overrides):
    """Fit a SyntheticStance with the test-suite default options."""
    options = FitOptions(noise_bandwidth_hz=NOISE_BANDWIDTH_HZ, **option_overrides)
    return fit_joint_stance(
        stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s, stance.moment_nm, options
    )


@pytest.fixture
def noisy_ankle_stance():
    """Ankle stance at 2.20 Hz with realistic noise (seed 3)."""
    return synthetic_stance("ankle", 2.20, np.random.default_rng(3), realistic_noise=True)
