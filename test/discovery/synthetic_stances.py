"""Synthetic stances for joint-law fits: known moment laws on flex-extend angle courses (test_eq7_fit, test_angle_terms).

Built for ``identify.fit_joint_law`` (which reads ``index``, ``t_s``, ``rho_rad``, ``omega_rad_s``, ``moment_nm``), so
a fit's coefficients can be checked against the law that made the moments.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np


def sine_stances(amps, shares, law, noise_nm: float, seed: int = 0, rho0: float = 0.2,
                 touchdown_moment=lambda i: 20.0) -> list[SimpleNamespace]:
    """One 0.25 s stance at 1 kHz per amplitude in ``amps``: ``rho = rho0 + amp shares sin(pi t / T)`` per joint.

    Moments: ``touchdown_moment(i) + law(dr, dw)`` (``dr = rho - rho[0]``, ``dw = omega - omega[0]``, shape (N, 3))
    plus white noise of ``noise_nm`` (seeded).
    """
    rng = np.random.default_rng(seed)
    out = []
    for i, amp in enumerate(amps):
        t = np.arange(250) / 1000.0
        a = amp * np.asarray(shares, float)
        rho = rho0 + a * np.sin(np.pi * t / 0.25)[:, None]
        omega = a * (np.pi / 0.25) * np.cos(np.pi * t / 0.25)[:, None]
        dr, dw = rho - rho[0], omega - omega[0]
        moment = touchdown_moment(i) + law(dr, dw) + noise_nm * rng.standard_normal(dr.shape)
        out.append(SimpleNamespace(index=i, t_s=t, rho_rad=rho, omega_rad_s=omega, moment_nm=moment))
    return out
