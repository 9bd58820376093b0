"""Per-stance summary figures: joint work, overall joint stiffness, leg stiffness, hip excursion.

Definitions (the seed paper's Tables 1 and 2; choices documented here)
----------------------------------------------------------------------
- Brake / push work of a joint: time integrals (trapezoid) of the negative /
  positive part of the joint power over the stance (J); brake work is
  reported as a positive number of joules absorbed.
- Overall joint stiffness: "moment change over angle change" (seed, after
  Farley et al. 1998): (M(t*) - M(td)) / (rho(t*) - rho(td)) with t* the
  instant of maximal flexion (maximal rho) during the stance (N m / rad).
  NaN if the joint does not flex (angle change below 1e-3 rad).
- Leg stiffness: peak vertical GRF over the maximal downward displacement of
  the centre of mass (N/m). The displacement comes from integrating
  (Fz - m g) / m twice over the stance. The touchdown velocity is chosen so
  that take-off and touchdown vertical speeds are equal and opposite
  (v_td = -Delta v / 2, Delta v the stance impulse over m), the usual
  assumption of steady hopping (Cavagna 1975; Blickhan 1989); it needs no
  flight-phase data. The cross-check uses the whole-body COM from segment
  kinematics (displacement from its value at touchdown).
- Vertical hip excursion: range (max - min) of the hip marker's height
  during the stance (m).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_trapezoid, trapezoid

from hop_impedance.impedance.constant_stiffness import overall_stiffness_columns
from hop_impedance.recording import GRAVITY_M_S2


def joint_work(t_s: np.ndarray, power_w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Brake and push work per joint over a stance (J).

    Parameters
    ----------
    t_s : ndarray, shape (N,)
    power_w : ndarray, shape (N, J)

    Returns
    -------
    brake_j : ndarray, shape (J,)
        Energy absorbed (positive number): -integral of min(P, 0).
    push_j : ndarray, shape (J,)
        Energy generated: integral of max(P, 0).
    """
    p = np.asarray(power_w, float)
    return -trapezoid(np.minimum(p, 0.0), t_s, axis=0), trapezoid(np.maximum(p, 0.0), t_s, axis=0)


def overall_joint_stiffness(rho_rad: np.ndarray, moment_nm: np.ndarray, min_change_rad: float = 1e-3) -> np.ndarray:
    """Moment change over angle change from touchdown to maximal flexion (N m/rad), shape (J,).

    :func:`hop_impedance.impedance.constant_stiffness.overall_stiffness_columns`
    (one implementation for these metrics and the fit).

    Parameters
    ----------
    rho_rad : ndarray, shape (N, J)
        Joint angles over the stance, first sample at touchdown (rad).
    moment_nm : ndarray, shape (N, J)
        Extensor-positive moments (N m).
    """
    return overall_stiffness_columns(rho_rad, moment_nm, min_change_rad)


def com_displacement_from_grf(t_s: np.ndarray, fz_n: np.ndarray, mass_kg: float) -> np.ndarray:
    """Vertical COM displacement from touchdown (m), shape (N,), by double integration.

    Assumes the touchdown velocity is minus the take-off velocity (see the
    module docstring).

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Stance samples, touchdown to take-off (s).
    fz_n : ndarray, shape (N,)
        Vertical GRF (N), zeroed.
    mass_kg : float
        Body mass (kg).
    """
    acc = np.asarray(fz_n, float) / mass_kg - GRAVITY_M_S2
    dv = cumulative_trapezoid(acc, t_s, initial=0.0)
    v = dv - 0.5 * dv[-1]
    z: np.ndarray = cumulative_trapezoid(v, t_s, initial=0.0)
    return z


def leg_stiffness(peak_grf_n: float, displacement_m: np.ndarray) -> float:
    """Peak GRF over maximal downward COM displacement (N/m); NaN if the COM does not go down."""
    drop = -float(np.nanmin(displacement_m))
    return peak_grf_n / drop if drop > 1e-6 else float("nan")


def hip_excursion(hip_z_m: np.ndarray) -> float:
    """Range of the hip marker height during the stance (m)."""
    return float(np.nanmax(hip_z_m) - np.nanmin(hip_z_m))
