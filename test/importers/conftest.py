"""Shared fixtures for the importer tests: a synthetic hopping recording with a known answer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hop_impedance.recording import GRAVITY_M_S2, MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording, Subject

DATA = Path("/work/shared/data_candidates")
OPENCAP = DATA / "opencap_dropjump"
CMJ = DATA / "bmc_cmj_grf" / "jump1.txt"


def hopping_recording(seed: int = 3, duration_s: float = 2.0, mass_kg: float = 62.0) -> Recording:
    """Two-legged hopping at 2 Hz, contact 0.3 s: a physically consistent contract recording.

    Vertical force: half-sine pulses whose impulse equals m g per hop period
    (momentum balance); the COP moves heel->toe (x from -0.05 to +0.10 m) and
    ``torque_y = -cop_x * Fz``; a small free moment about z and a braking /
    propulsive Fx. Markers at 200 Hz on a leg that flexes in stance, with
    seeded noise and one occluded stretch of the knee marker.
    """
    rng = np.random.default_rng(seed)
    f_rate, m_rate, period, contact = 1000, 200, 0.5, 0.3
    t = np.arange(int(duration_s * f_rate)) / f_rate
    phase = np.mod(t, period)
    in_contact = phase < contact
    peak = mass_kg * GRAVITY_M_S2 * period * np.pi / (2 * contact)
    fz = np.where(in_contact, peak * np.sin(np.pi * phase / contact), 0.0)
    s = np.clip(phase / contact, 0, 1)
    cop_x = -0.05 + 0.15 * s
    fx = np.where(in_contact, -0.15 * fz * np.cos(np.pi * s), 0.0)
    fy = np.where(in_contact, 5.0 * np.sin(2 * np.pi * s), 0.0)
    force = np.stack([fx, fy, fz], axis=1) + rng.normal(0, 0.5, (t.size, 3))
    torque = np.stack([0.01 * fz, -cop_x * fz, np.where(in_contact, 2.0 * np.sin(np.pi * s), 0.0)], axis=1)
    tm = np.arange(int(duration_s * m_rate)) / m_rate
    flex = 0.3 * np.sin(2 * np.pi * tm / period) ** 2
    base = np.array([[0.10, -0.1, 0.02], [-0.08, -0.1, 0.03], [-0.02, -0.1, 0.09], [0.0, -0.1, 0.5], [-0.02, -0.1, 0.92],
                     [-0.05, -0.1, 1.62]])
    pos = np.repeat(base[None], tm.size, axis=0)
    pos[:, 3, 0] += 0.25 * flex
    pos[:, 4:, 2] -= 0.1 * flex[:, None]
    pos += rng.normal(0, 5e-4, pos.shape)
    pos[40:47, MARKER_NAMES.index("knee"), :] = np.nan
    return Recording(
        ForcePlateSeries(np.round(t * 1e9).astype(np.int64), force, torque),
        MarkerSeries(np.round(tm * 1e9).astype(np.int64), MARKER_NAMES, pos),
        Subject("sim01", mass_kg, 1.68, "female"),
        "synthetic",
    )


@pytest.fixture
def hopping() -> Recording:
    return hopping_recording()
