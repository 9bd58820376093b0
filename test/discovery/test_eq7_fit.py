"""``identify.EQ7_FIT`` (session 16, an option): the joint law identified subject to seed 000's Eq. 7 (K >= 0, B >= 0).

Synthetic stances built from the package's own feature function (``stance_features``, through ``fit_joint_law``):
four stances with a flex-extend angle course per joint, moments of a known law ``M = k0 dr + b0 dw + b1 dw^2 / 2``
plus noise. A non-passive truth (``b1`` large, so ``B = b0 + b1 dw`` < 0 once the joint extends) pushes the
unconstrained fit to B < 0; the constrained one keeps B >= 0 on every training sample and is the optimum of the
constrained least squares (its KKT conditions checked). A passive truth leaves both fits identical.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import nnls

from hop_impedance.discovery import identify
from hop_impedance.discovery.model import ModelSpec, feature_names, stance_features
from hop_impedance.impedance.qp_fit import exact_constrained_lstsq
from test.discovery.synthetic_stances import sine_stances

SPEC = ModelSpec(effects=("joint_damping",))
K0 = np.array([300.0, 150.0, 120.0])


def stances(b0: float, b1: float, noise_nm: float, seed: int = 0) -> list[SimpleNamespace]:
    """Four stances of 0.25 s at 1 kHz, moments of ``M = 20 + k0 dr + b0 dw + b1 dw^2 / 2`` plus white noise."""
    return sine_stances((0.25, 0.3, 0.35, 0.4), (0.6, 1.0, 0.5), lambda dr, dw: K0 * dr + b0 * dw + b1 * dw**2 / 2,
                        noise_nm, seed)


def damping_on_samples(coefs: np.ndarray, data: list[SimpleNamespace]) -> np.ndarray:
    """``B = b0 + b1 dw`` per joint on every sample of ``data``, shape (n_samples, 3)."""
    names = feature_names(SPEC)
    ib0, ib1 = names.index("b0"), names.index("b1")
    return np.concatenate([coefs[:, ib0] + coefs[:, ib1] * (s.omega_rad_s - s.omega_rad_s[0]) for s in data])


def test_non_passive_data_constrained_fit_keeps_b_nonnegative_and_is_the_optimum(monkeypatch):
    data = stances(b0=0.5, b1=3.0, noise_nm=0.5)
    monkeypatch.setattr(identify, "EQ7_FIT", False)
    free, sse_free = identify.fit_joint_law(SPEC, data)
    b_free = damping_on_samples(free, data)
    assert b_free.min() < -15.0  # the unconstrained fit recovers the non-passive truth: B down to ~ -22
    monkeypatch.setattr(identify, "EQ7_FIT", True)
    fixed, sse_fixed = identify.fit_joint_law(SPEC, data)
    b_fixed = damping_on_samples(fixed, data)
    assert b_fixed.min() >= -1e-9
    assert b_fixed.min() < 1e-6  # the constraint is active: B touches 0 somewhere
    assert np.all(fixed[:, 0] > 0)  # K = k0 stays positive
    assert sse_fixed > sse_free * 1.5  # Eq. 7 costs fit here
    # optimality (KKT), joint by joint: the gradient of the squared residual is a non-negative combination of the
    # active rows (those at B = 0 or K = 0), and moving off them in any feasible direction only raises the sum
    feats = [stance_features(SPEC, s.t_s, s.rho_rad, s.omega_rad_s) for s in data]
    cores = [identify.core(len(s.t_s)) for s in data]
    for j in range(3):
        x = np.concatenate([f[j][c] - f[j][c].mean(axis=0) for f, c in zip(feats, cores)])
        y = np.concatenate([s.moment_nm[c, j] - s.moment_nm[c, j].mean() for s, c in zip(data, cores)])
        rows = np.concatenate([identify.passivity_rows(SPEC, s)[j] for s in data])
        grad = -2.0 * x.T @ (y - x @ fixed[j])
        active = rows[rows @ fixed[j] <= 1e-9]
        assert len(active) >= 1
        multipliers, residual = nnls(active.T, grad)
        assert residual <= 1e-6 * np.linalg.norm(2.0 * x.T @ y)
        assert np.linalg.norm(grad) > 1.0  # the constraint binds: the unconstrained gradient is not zero there


def test_passive_data_both_fits_agree(monkeypatch):
    data = stances(b0=2.0, b1=-0.5, noise_nm=0.5, seed=1)
    monkeypatch.setattr(identify, "EQ7_FIT", False)
    free, sse_free = identify.fit_joint_law(SPEC, data)
    assert damping_on_samples(free, data).min() > 0.0  # the unconstrained optimum keeps Eq. 7 already
    monkeypatch.setattr(identify, "EQ7_FIT", True)
    fixed, sse_fixed = identify.fit_joint_law(SPEC, data)
    np.testing.assert_allclose(fixed, free, rtol=0, atol=1e-8)
    assert sse_fixed == pytest.approx(sse_free, rel=1e-12)


def test_exact_constrained_lstsq_on_an_interior_optimum_matches_lstsq():
    rng = np.random.default_rng(3)
    x = rng.standard_normal((200, 3))
    c_true = np.array([1.0, 2.0, 3.0])
    y = x @ c_true + 0.01 * rng.standard_normal(200)
    rows = np.eye(3)  # c >= 0, inactive at the optimum
    c = exact_constrained_lstsq(x, y, rows)
    np.testing.assert_allclose(c, np.linalg.lstsq(x, y, rcond=None)[0], rtol=0, atol=1e-8)
