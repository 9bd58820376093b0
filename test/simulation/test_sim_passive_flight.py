"""The flight's passive phases (issue 17, session 25; hop_impedance.simulation.passive_flight).

Physics checked: in a passive phase the free chain moves with zero joint moments and no external moment (the flight's
kinematics put through the chain's equations of motion, which test_sim_dynamics checks against the Jacobian sums);
the touchdown and take-off states, and so every stance, are those of the flight without the phases, to the bit; the
angles stay C2 where the quintic meets a phase. The quintic alone, for contrast, needs tens of N m at the hip just
before an energy-keeping touchdown (what session 24 found the analysis reading into the stance).
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.simulation.dynamics import equations_of_motion
from hop_impedance.simulation.hopping_trial import HoppingConfig, simulate_hopping
from hop_impedance.simulation.passive_flight import KNOT_STEP_S, MAX_FLIGHT_FRACTION, passive_duration_s, passive_knots
from hop_impedance.simulation.scenarios import hopping_config

FD_STEP_S = 1e-5


def _trial(**passive):
    chain, config = hopping_config(2.2, "hard", 3, flight="energy_keeping", **passive)
    return chain, simulate_hopping(chain, config, seed=3)


@pytest.fixture(scope="module")
def trials():
    chain, plain = _trial()
    _, landing = _trial(passive_landing_s=0.06)
    _, both = _trial(passive_takeoff_s=0.04, passive_landing_s=0.06)
    return chain, plain, landing, both


def flight_moments(chain, flight, t_s: float) -> tuple[np.ndarray, float, np.ndarray]:
    """Joint moments (ankle, knee, hip; extensor positive), the external moment and the toe force the flight's
    kinematics need at ``t_s``, by the chain's equations of motion (accelerations by central differences)."""
    g, gd = flight.evaluate(chain, np.array([t_s]))
    _, gd_p = flight.evaluate(chain, np.array([t_s + FD_STEP_S]))
    _, gd_m = flight.evaluate(chain, np.array([t_s - FD_STEP_S]))
    gdd = (gd_p[0] - gd_m[0]) / (2 * FD_STEP_S)
    mass, bias, gravity = equations_of_motion(chain, g[0], gd[0])
    q = mass @ gdd + bias - gravity  # = Q_joints + Q_external
    moments = np.array([-q[2], q[3] + q[2], -(q[2] + q[3] + q[4])])  # Q_joints = -D^T M solved for M
    return moments, float(q[2:].sum()), q[0:2]


def test_every_stance_is_the_same_to_the_bit(trials):
    _, plain, landing, both = trials
    assert len(plain.stances) == len(landing.stances) == len(both.stances) == 3
    for a, b, c in zip(plain.stances, landing.stances, both.stances):
        assert a.t_touchdown_s == b.t_touchdown_s == c.t_touchdown_s
        np.testing.assert_array_equal(a.stance.g, b.stance.g)
        np.testing.assert_array_equal(a.stance.gd, c.stance.gd)
        np.testing.assert_array_equal(a.stance.moments_nm, c.stance.moments_nm)


def test_the_passive_phases_need_no_joint_or_external_moment(trials):
    chain, plain, landing, both = trials
    for flight, record in zip(both.flights[1:-1], both.stances[1:]):
        down = passive_duration_s(0.06, flight.duration_s)
        up = passive_duration_s(0.04, flight.duration_s)
        assert down == pytest.approx(0.06) and up == pytest.approx(0.04)
        t_td = record.t_touchdown_s
        assert flight.t_start_s + flight.duration_s == pytest.approx(t_td, abs=1e-12)
        for t in np.r_[t_td - np.linspace(0.002, down - 0.002, 6), flight.t_start_s + np.linspace(0.002, up - 0.002, 4)]:
            moments, external, toe = flight_moments(chain, flight, t)
            assert np.max(np.abs(moments)) < 0.05, (t, moments)
            assert abs(external) < 0.05 and np.max(np.abs(toe)) < 0.05
        # in the middle the quintic repositions the segments: real moments there
        assert np.max(np.abs(flight_moments(chain, flight, flight.t_start_s + 0.5 * flight.duration_s)[0])) > 1.0
    # the quintic to touchdown, on the same trial, needs a hip moment 20 ms before landing (the contrast)
    hips = [flight_moments(chain, f, r.t_touchdown_s - 0.02)[0][2] for f, r in zip(plain.flights[1:-1], plain.stances[1:])]
    assert max(abs(h) for h in hips) > 5.0, hips


def test_the_angles_are_continuous_to_the_second_derivative_and_meet_the_touchdown(trials):
    chain, _, _, both = trials
    for flight, record in zip(both.flights[1:-1], both.stances[1:]):
        angles = flight.angles
        for k in range(3):
            deriv = angles.derivative(k) if k else angles
            # the knots where the quintic meets each phase
            for tau in (passive_duration_s(0.04, flight.duration_s),
                        flight.duration_s - passive_duration_s(0.06, flight.duration_s)):
                np.testing.assert_allclose(deriv(tau - 1e-9), deriv(tau + 1e-9), atol=1e-4 * 10**k)
        g, gd = flight.evaluate(chain, np.array([record.t_touchdown_s]))
        np.testing.assert_allclose(g[0, 2:], record.stance.g[0, 2:], atol=1e-12)
        np.testing.assert_allclose(gd[0, 2:], record.stance.gd[0, 2:], atol=1e-10)


def test_a_phase_is_at_most_its_share_of_the_flight_in_whole_knots():
    assert passive_duration_s(0.08, 0.19) == pytest.approx(0.075)  # 0.4 x 0.19 = 0.076, rounded down to 5 ms
    assert passive_duration_s(0.08, 0.30) == pytest.approx(0.08)
    assert passive_duration_s(0.0, 0.30) == 0.0
    assert MAX_FLIGHT_FRACTION * 0.19 // KNOT_STEP_S == 15


def test_a_phase_ends_where_its_toe_would_pass_through_the_ground(trials):
    chain, _, _, both = trials
    td = both.stances[1].touchdown
    tau, knots = passive_knots(chain, td.g, td.gd, -0.06)
    assert len(tau) == 13 and tau[0] == pytest.approx(-0.06) and tau[-1] == 0.0
    np.testing.assert_array_equal(knots[-1, 0], td.g[2:])
    # the toe moving up at the contact: backward in time it was below the ground at once, so no phase
    rising = td.gd.copy()
    rising[1] = 0.5
    assert len(passive_knots(chain, td.g, rising, -0.06)[0]) == 1


def test_a_negative_phase_is_refused():
    _, config = hopping_config(2.2, "hard", 3)
    with pytest.raises(ValueError, match="passive_landing_s"):
        HoppingConfig(**{**config.__dict__, "passive_landing_s": -0.01})
