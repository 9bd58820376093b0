"""Torque laws against numerical integration of Eq. 3, and the surface laws against the seed's numbers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid, solve_ivp

from hop_impedance.simulation.ground import HARD, RIGID, SOFT, GroundLaw, lossless, surface
from hop_impedance.simulation.impedance_laws import (
    BellActivation,
    CompositeLaw,
    Eq3Law,
    PushOff,
    TimeActivation,
    TouchdownReference,
    constant_stiffness,
)

REF = TouchdownReference(np.array([1.3, 3.5, 3.4]), np.array([2.0, 1.0, 0.5]))


def synthetic_path(n=4001):
    """A smooth stance-like joint trajectory (rad, rad/s, rad/s^2) from touchdown."""
    t = np.linspace(0.0, 0.25, n)
    amp = np.array([0.6, 0.3, 0.1])
    rho = REF.rho0_rad + amp * np.sin(np.pi * t / 0.25)[:, None] + (REF.omega0_rad_s - amp * np.pi / 0.25) * t[:, None]
    omega = amp * np.pi / 0.25 * np.cos(np.pi * t / 0.25)[:, None] + (REF.omega0_rad_s - amp * np.pi / 0.25)
    return t, rho, omega


def test_eq3_closed_form_equals_numerical_integral_of_stiffness_and_damping():
    """Eqs. 4-5: M = m0 + int K d(rho) + int B d(omega), integrated numerically along a path."""
    c = dict(m0=[1.0, -2.0, 0.5], k0=[300.0, 230.0, 175.0], k1=[950.0, 880.0, 900.0], k2=[200.0, 100.0, 50.0],
             k3=[20.0, 10.0, 5.0], b0=[0.5, 0.6, 0.7], b1=[0.05, 0.04, 0.03], b2=[0.01, 0.02, 0.01],
             b3=[2.0, 1.0, 1.5])
    law = Eq3Law(**c)
    t, rho, omega = synthetic_path()
    dr, dw = rho - REF.rho0_rad, omega - REF.omega0_rad_s
    stiffness = np.array(c["k0"]) + np.array(c["k1"]) * dr + np.array(c["k2"]) * dr**2 + np.array(c["k3"]) * dw
    damping = np.array(c["b0"]) + np.array(c["b1"]) * dw + np.array(c["b2"]) * dw**2 + np.array(c["b3"]) * dr
    expected = np.array(c["m0"]) + cumulative_trapezoid(stiffness, rho, axis=0, initial=0) + cumulative_trapezoid(
        damping, omega, axis=0, initial=0)
    # The law's extra state S = int (omega - omega0) omega dt, integrated by solve_ivp as in the simulator.
    sol = solve_ivp(lambda tt, s: law.state_rates(tt, np.array([np.interp(tt, t, rho[:, j]) for j in range(3)]),
                                                  np.array([np.interp(tt, t, omega[:, j]) for j in range(3)]), s, REF),
                    (0, t[-1]), np.zeros(3), t_eval=t, rtol=1e-10, atol=1e-12, max_step=1e-3)
    moments = law.moments_nm(t, rho, omega, sol.y.T, REF)
    assert np.abs(moments - expected).max() < 1e-3 * np.abs(expected).max()
    assert np.abs(expected).max() > 100


def test_constant_stiffness_is_linear_spring_about_touchdown():
    law = constant_stiffness([300.0, 200.0, 100.0])
    rho = REF.rho0_rad + np.array([0.1, -0.2, 0.3])
    m = law.moments_nm(0.1, rho, REF.omega0_rad_s, np.zeros(3), REF)
    assert m == pytest.approx([30.0, -40.0, 30.0])
    assert law.elastic_energy_j(rho, REF) == pytest.approx(0.5 * (300 * 0.01 + 200 * 0.04 + 100 * 0.09))


def test_elastic_energy_is_the_integral_of_the_moment():
    law = Eq3Law(m0=[2.0, 0.0, 1.0], k0=[300.0, 230.0, 175.0], k1=[950.0, 880.0, 900.0], k2=[100.0, 50.0, 20.0])
    rho = REF.rho0_rad + np.linspace(0, 0.5, 2001)[:, None] * np.array([1.0, 0.6, 0.3])
    m = law.moments_nm(0.0, rho, REF.omega0_rad_s, np.zeros((len(rho), 3)), REF)
    work = sum(np.trapezoid(m[:, j], rho[:, j]) for j in range(3))
    assert law.elastic_energy_j(rho[-1], REF) == pytest.approx(work, rel=1e-6)
    with pytest.raises(NotImplementedError):
        Eq3Law(k0=1.0, k3=1.0).elastic_energy_j(rho[-1], REF)


def test_time_activation_scales_stiffness_by_a_rising_fixed_time_course():
    act = TimeActivation(a_min=0.3, tau_s=0.04)
    assert act.value(0.0) == pytest.approx(0.3)
    assert act.value(0.04) == pytest.approx(0.3 + 0.7 * (1 - np.exp(-1)))
    assert act.value(10.0) == pytest.approx(1.0)
    law = Eq3Law(k0=[300.0, 200.0, 100.0], b0=1.0, activation=act)
    rho = REF.rho0_rad + 0.2
    early = law.moments_nm(0.0, rho, REF.omega0_rad_s, np.zeros(3), REF)
    late = law.moments_nm(1.0, rho, REF.omega0_rad_s, np.zeros(3), REF)
    assert early == pytest.approx(0.3 * late)
    with pytest.raises(ValueError):
        TimeActivation(a_min=1.5, tau_s=0.1)


def test_push_off_pulse_integral_and_composite_sum():
    push = PushOff([100.0, 30.0, 0.0], onset_s=0.1, duration_s=0.2)
    t = np.linspace(0, 0.5, 50001)
    m = push.moments_nm(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)), np.zeros((len(t), 0)), REF)
    assert np.trapezoid(m[:, 0], t) == pytest.approx(100.0 * 0.2 / 2, rel=1e-6)  # mean of sin^2 = 1/2
    assert m[t < 0.1].max() == 0 and m[t > 0.3].max() == 0
    spring = constant_stiffness([300.0, 200.0, 100.0])
    both = CompositeLaw((spring, push))
    rho = REF.rho0_rad + 0.1
    tot = both.moments_nm(0.2, rho, REF.omega0_rad_s, np.zeros(3), REF)
    assert tot == pytest.approx(spring.moments_nm(0.2, rho, REF.omega0_rad_s, np.zeros(3), REF) + [100, 30, 0])
    assert both.n_states == 3


def test_push_off_lag_starts_a_joint_later_and_ends_it_with_the_others():
    # the knee's push lagging by half the window: sin^2 over [0.2, 0.3], so its impulse is A * 0.1 / 2 and it peaks at
    # 0.25 s; the ankle's stays the unlagged pulse; a lag of 1 or more is refused
    push = PushOff([100.0, 30.0, 0.0], onset_s=0.1, duration_s=0.2, lag_fraction=(0.0, 0.5, 0.0))
    t = np.linspace(0, 0.5, 50001)
    m = push.moments_nm(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)), np.zeros((len(t), 0)), REF)
    assert np.trapezoid(m[:, 0], t) == pytest.approx(100.0 * 0.2 / 2, rel=1e-6)
    assert np.trapezoid(m[:, 1], t) == pytest.approx(30.0 * 0.1 / 2, rel=1e-6)
    assert t[np.argmax(m[:, 1])] == pytest.approx(0.25, abs=1e-5) and m[t < 0.2, 1].max() == 0
    assert m[t > 0.3].max() == 0
    assert push.with_amplitude([50.0, 15.0, 0.0]).lag_fraction.tolist() == [0.0, 0.5, 0.0]
    assert push.to_dict()["lag_fraction"] == [0.0, 0.5, 0.0]
    assert "lag_fraction" not in PushOff([1.0, 1.0, 1.0], 0.1, 0.2).to_dict()
    with pytest.raises(ValueError):
        PushOff([1.0, 1.0, 1.0], 0.1, 0.2, lag_fraction=(0.0, 1.0, 0.0))


def test_seed_surface_laws_reproduce_the_published_formulas():
    y, ydot = -0.01, -0.5
    assert SOFT.force_n(y, ydot) == pytest.approx(7.5e4 * 0.01**1.4 + 68.4 * 0.5)
    assert HARD.force_n(y, ydot) == pytest.approx(3.1e6 * 0.01**2 + 186.3 * 0.5)
    assert HARD.force_n(0.001, -1.0) == 0.0  # out of contact
    assert HARD.force_n(-0.001, 5.0) == 0.0  # never pulls
    assert surface("soft") is SOFT
    with pytest.raises(ValueError, match="unknown surface"):
        surface("ice")
    with pytest.raises(ValueError):
        GroundLaw("bad", -1.0, 1.0, 0.0)


def test_rigid_surface_penetration_is_about_a_millimetre_at_three_body_weights():
    f = 3 * 54.8 * 9.81
    pen = (f / RIGID.stiffness) ** (1 / RIGID.exponent)
    assert 0.5e-3 < pen < 2e-3
    assert RIGID.force_n(-1e-9, -1.0) < 1.0  # Hunt-Crossley: no force jump at touchdown
    assert lossless(HARD).damping_n_s_m == 0.0


def test_bell_activation_does_no_net_work_over_a_symmetric_stance():
    """Issue 17's bell activation (seed 000's bell-shaped stiffness in time): a_min at touchdown and at the end of
    its duration, 1 at mid-stance; over a flexion-extension mirror-symmetric about mid-stance the Eq. 3 spring
    scaled by it returns what it took (work ~ 0, to the quadrature's accuracy), while seed 001's rising
    activation (TimeActivation) makes the same spring do net positive work (loaded softer than unloaded)."""
    t_stance = 0.26
    bell = BellActivation(a_min=0.7, duration_s=t_stance)
    assert bell.value(np.array([0.0, t_stance / 2, t_stance, 2 * t_stance])) == pytest.approx([0.7, 1.0, 0.7, 0.7])
    t = np.linspace(0.0, t_stance, 20001)
    rho = 0.5 * np.sin(np.pi * t / t_stance)  # ankle flexion since touchdown (rad), back to zero at take-off
    omega = np.gradient(rho, t)
    ref = TouchdownReference(np.zeros(3), np.zeros(3))
    rho3, omega3 = np.repeat(rho[:, None], 3, axis=1), np.repeat(omega[:, None], 3, axis=1)

    def work_on_body_j(activation) -> float:
        law = Eq3Law(k0=np.full(3, 301.0), k1=np.full(3, 948.0), activation=activation)
        moment = law.moments_nm(t, rho3, omega3, np.zeros((len(t), 3)), ref)[:, 0]
        return float(np.trapezoid(-moment * omega, t))  # extensor moment against flexion: power -M omega

    loading = float(np.trapezoid((301.0 * rho + 474.0 * rho**2) * omega * (t < t_stance / 2), t))
    assert abs(work_on_body_j(bell)) < 1e-6 * loading
    assert work_on_body_j(TimeActivation(a_min=0.3, tau_s=0.04)) > 0.05 * loading
    with pytest.raises(ValueError):
        BellActivation(a_min=1.2, duration_s=0.2)
