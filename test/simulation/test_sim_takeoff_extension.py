"""Issue 17, session 12: a push-off lasting to take-off leaves the joints extended past their touchdown angles.

At take-off the ground force is zero, so the net moment at the ankle is only what the light foot itself needs; a
push-off still active then is balanced by the Eq. 3 spring stretched the other way, i.e. the ankle extended beyond
its touchdown angle, and the hip stands higher than at touchdown (bench/simulator_hip_excursion_variants.py).
"""

from __future__ import annotations

import numpy as np

from hop_impedance.simulation.dynamics import joint_positions
from hop_impedance.simulation.hopping_trial import push_off_part, touchdown_posture, touchdown_state
from hop_impedance.simulation.scenarios import hopping_config, seed_like_options
from hop_impedance.simulation.stance import simulate_stance


def stance_with_push(timing: tuple[float, float]):
    options = {**seed_like_options(), "bell_activation_min": 0.9, "push_timing": timing}
    chain, cfg = hopping_config(2.2, "hard", 1, variability=False, **options)
    q = touchdown_posture(chain, np.array(cfg.touchdown_rho_rad))
    st = simulate_stance(chain, cfg.law, cfg.surface, touchdown_state(chain, q, np.array([0.0, -0.9]), 0.0),
                         trunk_balance=cfg.trunk_balance)
    assert st.end_reason == "take_off"
    return chain, cfg.law, st


def test_push_off_at_take_off_is_held_by_the_spring_stretched_past_touchdown():
    """2.2 Hz, bell a_min 0.9, push-off scale 1, touchdown at 0.9 m/s, hard surface; measured: the push-off 35.6 N m
    at take-off against a net ankle moment of -3.0 N m, the ankle 0.185 rad past its touchdown angle, the hip
    +31.4 mm above its touchdown height (+4.1 mm with the push-off from 0.5 for 0.5 of the passive stance)."""
    chain, law, st = stance_with_push((0.6, 0.8))
    push = push_off_part(law)
    push_ankle = float(push.profile(st.t_s[-1:])[0] * push.amplitude_nm[0])
    assert push_ankle > 10.0  # still pushing (N m) when the force reaches zero
    assert st.grf_n[-1, 1] < 1e-3 * st.grf_n[:, 1].max()
    assert abs(st.moments_nm[-1, 0]) < 0.25 * push_ankle  # the net ankle moment: the foot's own, small
    assert st.rho_rad[-1, 0] < st.rho_rad[0, 0]  # so the ankle ends extended past its touchdown angle
    hip = joint_positions(chain, st.g)[:, 3, 1]
    _, _, early = stance_with_push((0.5, 0.5))
    hip_early = joint_positions(chain, early.g)[:, 3, 1]
    assert hip[-1] - hip[0] > hip_early[-1] - hip_early[0] + 0.015  # the hip takes off higher
