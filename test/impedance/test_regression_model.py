"""Regressors of Eqs. 3-5 and 8-9 against closed forms computed by hand."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.impedance.regression_model import (
    PARAMETER_NAMES,
    parameter_indices,
    stance_regressors,
)
from hop_impedance.impedance.synthetic import synthetic_stance


def column(rows: np.ndarray, name: str) -> np.ndarray:
    return rows[:, PARAMETER_NAMES.index(name)]


class TestStanceRegressors:
    """rho = rho0 + a t^2 (omega = 2 a t) has closed forms for every path integral."""

    a = 3.0
    t = np.linspace(0.0, 0.3, 61)
    rho = 1.2 + a * t**2
    omega = 2 * a * t

    def regs(self):
        return stance_regressors(self.t, self.rho, self.omega)

    def test_k3_column_is_int_w_omega_dt(self):
        # omega0 = 0: int w omega dt = int 4 a^2 t^2 dt = 4 a^2 t^3 / 3
        got = column(self.regs().moment_rows, "k3")
        np.testing.assert_allclose(got, 4 * self.a**2 * self.t**3 / 3, rtol=1e-9, atol=1e-12)

    def test_b3_column_is_int_d_domega(self):
        # int d d(omega) = int a t^2 2a dt = 2 a^2 t^3 / 3
        got = column(self.regs().moment_rows, "b3")
        np.testing.assert_allclose(got, 2 * self.a**2 * self.t**3 / 3, rtol=1e-9, atol=1e-12)

    def test_spring_energy_of_k3_term(self):
        # int (4 a^2 t^3 / 3) * 2 a t dt = 8 a^3 t^5 / 15
        got = column(self.regs().spring_energy_rows, "k3")
        want = 8 * self.a**3 * self.t**5 / 15
        # Simpson is exact to cubics; the integrand here is quartic (error O(h^4))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-6 * want.max())

    def test_spring_energy_columns_equal_the_full_rows_and_the_closed_form(self):
        # the column-subset path computes the k3 integral itself (fresh regressors)
        r = self.regs()
        with_k3 = parameter_indices(("k0", "k3", "b0"))
        got = r.spring_energy_columns(with_k3)
        want_k3 = 8 * self.a**3 * self.t**5 / 15
        np.testing.assert_allclose(got[:, 2], want_k3, rtol=0, atol=1e-6 * want_k3.max())
        np.testing.assert_allclose(got[:, 1], self.a**2 * self.t**4 / 2)  # d**2 / 2
        np.testing.assert_array_equal(got[:, 3], 0.0)  # b0 stores no spring energy
        for terms in (("k0", "k1", "b0"), ("k0", "k1", "k2", "k3", "b3")):
            columns = parameter_indices(terms)
            np.testing.assert_array_equal(r.spring_energy_columns(columns), r.spring_energy_rows[:, columns])

    def test_polynomial_columns(self):
        r = self.regs()
        d = self.a * self.t**2
        np.testing.assert_allclose(column(r.moment_rows, "k1"), d**2 / 2)
        np.testing.assert_allclose(column(r.moment_rows, "b1"), self.omega**2 / 2)
        np.testing.assert_allclose(column(r.stiffness_rows, "k2"), d**2)
        np.testing.assert_allclose(column(r.damping_rows, "b3"), d)
        np.testing.assert_allclose(column(r.spring_energy_rows, "k1"), d**3 / 6)

    def test_touchdown_values(self):
        r = self.regs()
        assert r.rho0_rad == pytest.approx(1.2)
        assert r.omega0_rad_s == 0.0
        assert r.delta_angle_rad[0] == 0.0


def test_moment_rows_reproduce_the_seed_law():
    """X theta equals the independently integrated reduced law of the synthetic data."""
    stance = synthetic_stance("knee", 1.87, b0=0.6, m0=4.0)
    r = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    c = stance.true_coefficients
    theta = np.zeros(len(PARAMETER_NAMES))
    for name in ("m0", "k0", "k1", "b0"):
        theta[PARAMETER_NAMES.index(name)] = c[name]
    np.testing.assert_allclose(r.moment_rows @ theta, stance.true_moment_nm, rtol=1e-12, atol=1e-9)


def test_damper_power_rows_are_moment_times_velocity():
    stance = synthetic_stance("ankle", 2.20)
    r = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    np.testing.assert_allclose(r.damper_power_rows, r.damper_moment_rows * stance.angular_velocity_rad_s[:, None])


def test_parameter_indices_rejects_unknown_terms():
    assert list(parameter_indices(("k0", "b0"))) == [0, 1, 5]
    with pytest.raises(ValueError, match="unknown impedance terms"):
        parameter_indices(("k9",))


def test_damper_power_columns_equal_the_full_rows_and_moment_halves_add_up():
    stance = synthetic_stance("knee", 1.53, np.random.default_rng(0), realistic_noise=True)
    r = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    for terms in (("k0", "k1", "b0"), ("k0", "k3", "b1", "b2", "b3"), ("k0", "k1")):
        columns = parameter_indices(terms)
        np.testing.assert_array_equal(r.damper_power_columns(columns), r.damper_power_rows[:, columns])
    np.testing.assert_array_equal(r.spring_moment_rows + r.damper_moment_rows, r.moment_rows)
    assert not r.spring_moment_rows[:, 5:].any() and not r.damper_moment_rows[:, :5].any()
