"""Issue 17: which reading of the seed's "vertical excursion of hip" the realism bench binds (its docstring).

The choice rests on two pieces of arithmetic that are checked here against closed forms and the seed's own
Table 1/2 (no simulation): the bench's Newton drop for a force sin^n(pi t / Tc) of the right impulse, and the
seed's figures under the two readings.
"""

from __future__ import annotations

import importlib.util
import pathlib

import numpy as np
import pytest

BENCH = pathlib.Path(__file__).resolve().parents[2] / "bench" / "simulator_realism.py"


@pytest.fixture(scope="module")
def realism():
    spec = importlib.util.spec_from_file_location("simulator_realism", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_newton_drop_matches_the_half_sine_closed_form(realism):
    """A half-sine force with the impulse of one hop peaks at pi/2 x the mean force; its COM drop by mid-stance
    is v th + g th^2/2 - Fp (Tc/pi)(th - Tc/pi) (th = Tc/2, v = g (1/f - Tc)/2), and n comes back as 1."""
    g, f, tc = 9.81, 2.2, 0.282
    period = 1.0 / f
    fp = np.pi / 2.0 * g * period / tc  # per unit mass
    v, th = g * (period - tc) / 2.0, tc / 2.0
    closed = v * th + g * th**2 / 2.0 - fp * (tc / np.pi) * (th - tc / np.pi)
    n, drop = realism.newton_com_drop(f, tc, fp / g)
    assert n == pytest.approx(1.0, abs=1e-3)
    assert drop == pytest.approx(closed, abs=2e-4)


def test_seed_excursion_is_the_hips_range_in_stance_not_twice_the_compression(realism):
    """Table 2's leg stiffness is peak GRF over half Table 1's excursion (within 2 %), yet half the excursion is
    at most 0.7 x the COM drop that the seed's own peak GRF and stance time force (an upright trunk on the hip
    cannot fall that much further than the hip), while the whole excursion exceeds it at every frequency."""
    weight = 54.8 * 9.81
    for f, row in realism.SEED_TABLE1.items():
        k_half = row["grf_bw"] * weight / (row["hip_exc_m"] / 2.0) / 1000.0
        assert k_half == pytest.approx(realism.SEED_LEG_STIFFNESS_KN_M[f], rel=0.02)
        _, drop = realism.newton_com_drop(f, row["stance_ms"] / 1000.0, row["grf_bw"])
        assert row["hip_exc_m"] / 2.0 < 0.7 * drop
        assert row["hip_exc_m"] > 1.1 * drop
