"""fit_joint_stance: recovery of Table 2 coefficients, seed findings, rejections, JSON."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from conftest import FREQUENCIES_HZ, JOINTS, fit_synthetic

from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.stance_fit import FIT_JSON_KEYS, FitOptions, fit_joint_stance, fit_to_json
from hop_impedance.impedance.synthetic import TABLE2_COEFFICIENTS, synthetic_stance

REDUCED_LAW = dict(reduce=False, terms=("k0", "k1", "b0"))


@pytest.mark.parametrize("freq", FREQUENCIES_HZ)
@pytest.mark.parametrize("joint", JOINTS)
def test_noise_free_recovery_within_2_percent(joint, freq):
    """Full pipeline (reduction + OSQP) on exact data: k0, k1 within 2 %, b0 within 0.02."""
    st = synthetic_stance(joint, freq, b0=0.5)
    fit = fit_synthetic(st)
    assert fit.ok and fit.status == "solved"
    for name in ("k0", "k1"):
        assert fit.coefficients[name] == pytest.approx(st.true_coefficients[name], rel=0.02)
    assert fit.coefficients.get("b0", 0.0) == pytest.approx(0.5, abs=0.02)
    assert fit.r_squared > 0.9999


@functools.cache
def noisy_reduced_law_errors(joint, freq, n_stances=40):
    """Relative errors (k0, k1) of the reduced-law fit over n_stances noisy stances.

    Cached for the session: the recording test and the ankle per-stance test
    use the same stances (seeds 100-139); callers must not modify the array.
    """
    solver = ConstrainedLeastSquares()
    errors = []
    for seed in range(n_stances):
        st = synthetic_stance(joint, freq, np.random.default_rng(100 + seed), realistic_noise=True)
        fit = fit_joint_stance(
            st.time_s, st.angle_rad, st.angular_velocity_rad_s, st.moment_nm,
            FitOptions(noise_bandwidth_hz=12.0, **REDUCED_LAW), solver=solver,
        )
        assert fit.ok, fit.rejection_reason
        true_k0, true_k1 = TABLE2_COEFFICIENTS[freq][joint]
        errors.append([fit.coefficients["k0"] / true_k0 - 1, fit.coefficients["k1"] / true_k1 - 1])
    return np.array(errors)


@pytest.mark.parametrize("freq", FREQUENCIES_HZ)
@pytest.mark.parametrize("joint", JOINTS)
def test_noisy_recovery_over_a_recording(joint, freq):
    """Realistic noise: mean of k0 and k1 over 40 stances within 10 % of Table 2.

    Measured (seeds 100-139) per-stance SD of k1: ankle ~5 %, knee 6-13 %, hip
    20-65 % (hip moment ~25 N m against ~0.7 N m filtered noise). For the hip
    at 2.20 Hz the standard error of a 40-stance mean (~10 %) is itself at the
    10 % limit, so there the test is unbiasedness: within 3 standard errors.
    """
    err = noisy_reduced_law_errors(joint, freq)
    mean = err.mean(axis=0)
    if (joint, freq) == ("hip", 2.20):
        se = err.std(axis=0, ddof=1) / np.sqrt(len(err))
        assert np.all(np.abs(mean) < 3 * se)
    else:
        assert np.all(np.abs(mean) < 0.10), mean


@pytest.mark.parametrize("freq", FREQUENCIES_HZ)
def test_ankle_single_stance_recovery_within_10_percent(freq):
    """Per stance, the ankle meets 10 % in >= 90 % of stances (measured 92-98 %)."""
    err = noisy_reduced_law_errors("ankle", freq)
    assert np.mean(np.all(np.abs(err) < 0.10, axis=1)) >= 0.90


def fits_by_frequency(joint):
    out = {}
    for freq in FREQUENCIES_HZ:
        out[freq] = [
            fit_synthetic(synthetic_stance(joint, freq, np.random.default_rng(s), realistic_noise=True))
            for s in range(8)
        ]
    return out


@pytest.mark.parametrize("joint", JOINTS)
def test_seed_findings_hold(joint):
    """Stiffness rises with frequency, damping negligible, variable model error << constant."""
    fits = fits_by_frequency(joint)
    avg = {f: np.mean([x.average_stiffness for x in fs]) for f, fs in fits.items()}
    overall = {f: np.mean([x.overall_stiffness for x in fs]) for f, fs in fits.items()}
    assert avg[1.53] < avg[1.87] < avg[2.20]
    assert overall[1.53] < overall[1.87] < overall[2.20]
    for fs in fits.values():
        for fit in fs:
            assert fit.ok
            damper = fit.coefficients.get("b0", 0.0) * np.abs(np.gradient(fit.angle_rad, fit.time_s))
            assert damper.max() < 0.06 * np.abs(fit.moment_nm).max()  # seed: <= 6 %
        variable = np.mean([x.table3_variable for x in fs])
        constant = np.mean([x.table3_constant for x in fs])
        if joint != "hip":
            assert variable < 0.1 * constant
        else:  # hip: small k1 relative to noise, still clearly better
            assert variable < 0.5 * constant


def test_stiffness_profile_peaks_near_mid_stance_with_nonzero_ends():
    st = synthetic_stance("ankle", 1.87, np.random.default_rng(0), realistic_noise=True)
    fit = fit_synthetic(st)
    k = fit.stiffness
    i_peak = int(np.argmax(k))
    assert 0.25 < i_peak / (k.size - 1) < 0.65
    assert k[0] > 0.3 * k.max() and k[-1] > 0.0
    assert fit.max_stiffness > fit.initial_stiffness
    assert fit.initial_stiffness == pytest.approx(fit.coefficients["k0"])


class TestRejections:
    def good(self):
        return synthetic_stance("knee", 1.87, np.random.default_rng(0), realistic_noise=True)

    def fit(self, t, rho, omega, m):
        return fit_joint_stance(t, rho, omega, m, FitOptions(noise_bandwidth_hz=12.0))

    def test_nan_markers(self):
        st = self.good()
        rho = st.angle_rad.copy()
        rho[10:13] = np.nan
        fit = self.fit(st.time_s, rho, st.angular_velocity_rad_s, st.moment_nm)
        assert fit.status == "rejected" and fit.rejection_reason == "3 of 68 angle samples are NaN or infinite"

    def test_too_few_samples(self):
        st = self.good()
        fit = self.fit(st.time_s[::10], st.angle_rad[::10], st.angular_velocity_rad_s[::10], st.moment_nm[::10])
        assert fit.rejection_reason == "too few samples: 7 < 10"

    def test_too_short(self):
        st = self.good()
        t = st.time_s[:12] * 0.1
        fit = self.fit(t, st.angle_rad[:12], st.angular_velocity_rad_s[:12], st.moment_nm[:12])
        assert fit.rejection_reason.startswith("stance too short: 0.006 s")

    def test_flat_angle(self):
        st = self.good()
        n = st.time_s.size
        fit = self.fit(st.time_s, np.full(n, 2.0), np.zeros(n), st.moment_nm)
        assert fit.rejection_reason.startswith("flat angle trajectory")

    def test_zero_moment(self):
        """A joint moment that is 0 everywhere (no force data reached the ID) is rejected, not a ValueError."""
        st = self.good()
        fit = self.fit(st.time_s, st.angle_rad, st.angular_velocity_rad_s, np.zeros_like(st.moment_nm))
        assert fit.rejection_reason.startswith("moment is zero at every fitted sample")

    def test_given_model_with_a_vanishing_regressor(self):
        """Constant angular velocity: every omega - omega0 term is 0. With reduce=False (model given) that is a
        rejection naming the terms; with the reduction they are removed as singular and the fit goes on."""
        t = np.linspace(0.0, 0.25, 60)
        rho = 1.0 + 0.8 * t
        omega = np.full_like(t, 0.8)
        moment = 3.0 + 100.0 * (rho - rho[0])
        given = fit_joint_stance(t, rho, omega, moment, FitOptions(reduce=False, terms=("k0", "k1", "k3", "b0", "b1")))
        assert given.rejection_reason == (
            "regressor of k3, b1 is zero at every sample: the given model is singular on this stance"
        )
        reduced = fit_joint_stance(t, rho, omega, moment, FitOptions(terms=("k0", "k1", "k3", "b0", "b1")))
        assert reduced.ok and "k3" not in reduced.terms and "b1" not in reduced.terms
        assert reduced.coefficients["k0"] == pytest.approx(100.0, rel=1e-3)

    def test_non_increasing_time(self):
        st = self.good()
        t = st.time_s.copy()
        t[5] = t[4]
        assert self.fit(t, st.angle_rad, st.angular_velocity_rad_s, st.moment_nm).rejection_reason == (
            "time stamps are not strictly increasing"
        )

    def test_solver_failure_rejects(self):
        st = self.good()
        fit = fit_joint_stance(
            st.time_s, st.angle_rad, st.angular_velocity_rad_s, st.moment_nm,
            FitOptions(noise_bandwidth_hz=12.0, reduce=False),
            solver=ConstrainedLeastSquares(max_iter=2),
        )
        assert fit.status == "maximum iterations reached"
        assert fit.rejection_reason == "OSQP did not converge: status 'maximum iterations reached'"

    def test_rest_of_recording_still_analysed(self):
        good = [synthetic_stance("ankle", 2.20, np.random.default_rng(s), realistic_noise=True) for s in range(3)]
        bad_rho = good[1].angle_rad.copy()
        bad_rho[0] = np.nan
        solver = ConstrainedLeastSquares()
        fits = [
            fit_joint_stance(st.time_s, rho, st.angular_velocity_rad_s, st.moment_nm, FitOptions(noise_bandwidth_hz=12.0),
                             solver=solver)
            for st, rho in zip(good, [good[0].angle_rad, bad_rho, good[2].angle_rad])
        ]
        assert [f.ok for f in fits] == [True, False, True]

    def test_mismatched_lengths_raise(self):
        with pytest.raises(ValueError, match="one length"):
            fit_joint_stance(np.arange(20.0), np.arange(19.0), np.arange(20.0), np.arange(20.0))


def test_json_has_exactly_the_contract_keys(noisy_ankle_stance):
    fit = fit_synthetic(noisy_ankle_stance)
    out = fit_to_json(fit)
    assert tuple(out) == FIT_JSON_KEYS
    text = json.dumps(out, allow_nan=False)
    back = json.loads(text)
    assert back["terms"] == list(fit.terms)
    assert set(back["coefficients"]) == {"m0", *fit.terms}
    assert len(back["stiffness"]) == noisy_ankle_stance.time_s.size
    assert back["status"] == "solved" and back["rejection_reason"] is None
    assert back["sse_variable"] < back["sse_constant"]
    assert 0.0 <= back["p_values"]["k1"] < 0.05


def test_json_of_rejected_stance():
    n = 5
    fit = fit_joint_stance(np.arange(n) / 200, np.linspace(1, 1.1, n), np.ones(n), np.ones(n))
    out = fit_to_json(fit)
    assert tuple(out) == FIT_JSON_KEYS
    assert out["status"] == "rejected" and out["rejection_reason"] == "too few samples: 5 < 10"
    assert out["rmse"] is None and out["stiffness"] == []
    json.dumps(out, allow_nan=False)


@pytest.mark.parametrize("reduce", [True, False])
def test_standard_errors_and_p_values_against_an_independent_ols_formula(reduce):
    """se = sqrt(sigma^2 diag((X^T X)^-1) n / n_eff), p from Student t (scipy.stats), X of the kept terms.

    Both routes of the fit: the reduction's downdated (X^T X)^-1 (reduce=True)
    and the pseudo-inverse of the kept design (reduce=False).
    """
    from scipy import stats

    from hop_impedance.impedance.regression_model import parameter_indices, stance_regressors

    st = synthetic_stance("knee", 1.53, np.random.default_rng(11), realistic_noise=True)
    fit = fit_synthetic(st, reduce=reduce)
    assert fit.ok and len(fit.terms) >= 2
    r = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
    X = r.moment_rows[:, parameter_indices(fit.terms)]
    n, p = X.shape
    sigma2 = fit.sse_variable / (n - p)
    se = np.sqrt(np.diag(np.linalg.inv(X.T @ X)) * sigma2 * n / fit.effective_samples)
    names = ["m0", *fit.terms]
    np.testing.assert_allclose([fit.std_errors[k] for k in names], se, rtol=1e-7)
    coef = np.array([fit.coefficients[k] for k in names])
    p_values = 2 * stats.t.sf(np.abs(coef / se), fit.effective_samples - p)
    np.testing.assert_allclose([fit.p_values[k] for k in names], p_values, rtol=1e-6)
