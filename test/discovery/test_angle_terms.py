"""``model.ANGLE_TERMS``: the angle law as seed 000's reduced Eq. 10, ``K = k0 + k1 (rho - rho0)`` (session 18's option,
the default since session 30), or Eq. 3's ``k1, k2``.

Synthetic stances built from the package's own feature function (through ``fit_joint_law``): four stances with a
flex-extend angle course per joint and the moments of a touchdown-referenced angle law
``M = M_td + kc dr + k1 dr^2 / 2`` (``K`` from ``kc`` at touchdown, growing with flexion, as the second generator's
default angle case and the outside generator's) plus white noise. With the option the law has exactly the terms
``k0, k1`` and the fit on the stances' cores returns ``kc`` and ``k1``; Eq. 3's option has ``k1, k2``.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.discovery import identify, model, stiffness_gate
from hop_impedance.discovery.model import ModelSpec, feature_names
from test.discovery.synthetic_stances import sine_stances

KC = np.array([90.0, 110.0, 100.0])
K1 = 2.5 * KC
SPEC = ModelSpec(effects=("angle_dependent_stiffness",))


def stances(noise_nm: float, seed: int = 0):
    """Four stances of 0.25 s at 1 kHz: flexion amplitudes 0.7-1.0 x (0.8, 0.45, 0.12) rad, the law plus noise."""
    return sine_stances((0.7, 0.8, 0.9, 1.0), (0.8, 0.45, 0.12), lambda dr, dw: KC * dr + K1 * dr**2 / 2, noise_nm,
                        seed, rho0=0.3, touchdown_moment=lambda i: 15.0 * (i + 1))


def test_reduced_angle_law_has_eq10_terms_and_recovers_the_touchdown_stiffness(monkeypatch):
    assert feature_names(SPEC) == ("k0", "k1")  # the default: Eq. 10's k1
    monkeypatch.setattr(model, "ANGLE_TERMS", ("k1", "k2"))
    assert feature_names(SPEC) == ("k0", "k1", "k2")  # Eq. 3's option
    monkeypatch.setattr(model, "ANGLE_TERMS", ("k1",))
    assert stiffness_gate.effect_terms(SPEC, "angle_dependent_stiffness") == ("k1",)
    monkeypatch.setattr(identify, "EQ7_FIT", False)
    coefs, _ = identify.fit_joint_law(SPEC, stances(noise_nm=2.0))
    # K at touchdown and its slope: ankle within 3 %, knee within 8 % (seeds 0-3: <= 2 % and <= 7 %), the hip's k0
    # within 25 % (<= 23 %); over the hip's 0.08-0.12 rad of flexion its k1 is not determined by 2 N m of noise
    # (-96..+128 % over seeds 0-3), as in the second generator's hip (model.ANGLE_TERMS says what that does forward)
    np.testing.assert_allclose(coefs[0], [KC[0], K1[0]], rtol=0.03)
    np.testing.assert_allclose(coefs[1], [KC[1], K1[1]], rtol=0.08)
    assert abs(coefs[2, 0] / KC[2] - 1.0) < 0.25
