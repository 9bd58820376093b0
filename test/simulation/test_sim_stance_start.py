"""A stance integrated from a state inside it (``simulate_stance(..., start=StanceStart(...))``, session 22).

Restarted from its own state 50 ms after touchdown (the law's path integrals ``S`` included), a stance must go on as
the uninterrupted one: the same take-off, ground force and joint angles, to the solver's tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.simulation.dynamics import chain_from_body_model
from hop_impedance.simulation.ground import HARD
from hop_impedance.simulation.hopping_trial import touchdown_posture, touchdown_state
from hop_impedance.simulation.impedance_laws import Eq3Law
from hop_impedance.simulation.scenarios import DEFAULT_TOUCHDOWN_RHO, SEED_SUBJECT
from hop_impedance.simulation.stance import StanceStart, TouchdownState, simulate_stance

CHAIN = chain_from_body_model(body_model_from_stature(SEED_SUBJECT))


def test_a_stance_restarted_from_its_own_state_inside_it_goes_on_unchanged():
    # k3 and b3 act through the law's path integral S: the restart must carry it, and the touchdown reference
    law = Eq3Law(k0=[301.4, 230.9, 175.4], k1=[948.2, 884.8, 894.8], k3=[20.0, 10.0, 5.0], b0=0.5,
                 b3=[2.0, 1.0, 1.0])
    q = touchdown_posture(CHAIN, np.array(DEFAULT_TOUCHDOWN_RHO))
    td = touchdown_state(CHAIN, q, np.array([0.05, -1.0]), 0.0)
    t = np.arange(0.0, 0.6, 0.001)
    whole = simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6, sample_times_s=t, rtol=1e-10, atol=1e-12)
    assert whole.end_reason == "take_off" and whole.duration_s > 0.2
    t0 = 0.05
    y = whole.dense(t0)
    assert y[1] < -1e-4  # the toe is in the surface: the restart starts loaded, not at the touchdown's zero force
    start = StanceStart(t0, TouchdownState(y[0:6], y[6:12]), y[12:])
    late = simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6, sample_times_s=t, rtol=1e-10, atol=1e-12, start=start)
    assert late.start_s == t0 and late.t_s[0] >= t0 and whole.start_s == 0.0
    assert np.max(np.abs(late.t_s - t[(t >= t0) & (t <= late.duration_s)])) == 0.0
    assert late.duration_s == pytest.approx(whole.duration_s, abs=1e-6)
    k = np.searchsorted(whole.t_s, late.t_s[0])
    n = min(len(late.t_s), len(whole.t_s) - k)
    assert np.max(np.abs(late.grf_n[:n, 1] - whole.grf_n[k:k + n, 1])) < 1e-3 * np.max(whole.grf_n[:, 1])
    assert np.max(np.abs(late.rho_rad[:n] - whole.rho_rad[k:k + n])) < 1e-6
    # without the law's states the k3 / b3 terms differ from the uninterrupted stance's: the states are needed
    no_states = simulate_stance(CHAIN, law, HARD, td, t_max_s=0.6, sample_times_s=t, rtol=1e-10, atol=1e-12,
                                start=StanceStart(t0, start.state))
    assert np.max(np.abs(no_states.rho_rad[:n] - whole.rho_rad[k:k + n])) > 1e-4
