"""Synthetic stances obeying the seed's reduced law, for tests and benchmarks.

Until simulator recordings are available, recovery is checked on stances whose
moment is generated from Eqs. 10-11 (``K = k0 + k1 (rho - rho0)``, ``B = b0``)
with the seed's Table 2 coefficients and Table 1 stance times and ranges of
flexion, integrated in closed form (independently of the regressor code)::

    M = m0 + k0 d + k1 d**2 / 2 + b0 * omega          (d = rho - rho0)

Angle: ``rho = rho0 + A sin(pi s) - e s`` with a warped time
``s = t/T - c sin(2 pi t/T) / (2 pi)`` (c = 0.2: faster flexion than extension)
and a take-off angle ``e = 0.1 A`` more extended than touchdown.

Noise (``realistic_noise=True``): 1 mm marker noise gives a raw joint-angle
noise of about sqrt(2) * 1 mm / segment length (ankle 0.01 rad with the short
foot segment, knee and hip 0.005 rad) and, through the lever arm of a
~3 BW ground reaction force, about 2 N m of raw moment noise (the 2 N force
noise adds under 2 N m at the hip's ~1 m lever arm). Both are white at the
sample rate and then low-pass filtered at 12 Hz with zero lag, over a window
padded by one stance on each side so that the stance edges are filtered like
the inside of a recording. The filter is a 4th-order Butterworth run forwards
and backwards (8th order in effect), steeper than the pipeline's own
``biomech.filtering.lowpass`` (2nd order each way): kept because every rate
and tolerance measured on these stances (tests, docs/impedance_model.md)
rests on it; with ``lowpass`` instead, a KKT test's stance
(test_qp_fit.py, 4 terms) no longer has an active constraint. The
angular velocity carries the derivative of the filtered angle noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from hop_impedance.biomech.filtering import DEFAULT_CUTOFF_HZ
from hop_impedance.seed_tables import FREQUENCIES_HZ, JOINTS, RANGE_OF_FLEXION_RAD, STANCE_TIME_S, eq10_k0_k1

#: Seed Table 2 (mean values): frequency (Hz) -> joint -> (k0, k1) in N m/rad (:mod:`hop_impedance.seed_tables`).
TABLE2_COEFFICIENTS: dict[float, dict[str, tuple[float, float]]] = {
    f: {joint: eq10_k0_k1(f, joint) for joint in JOINTS} for f in FREQUENCIES_HZ
}
#: Seed Table 1: frequency (Hz) -> stance time (s).
TABLE1_STANCE_TIME_S = STANCE_TIME_S
#: Seed Table 1: frequency (Hz) -> joint -> range of flexion (rad).
TABLE1_RANGE_OF_FLEXION_RAD = RANGE_OF_FLEXION_RAD
#: Raw (unfiltered) joint-angle noise (rad) from 1 mm marker noise.
ANGLE_NOISE_RAD: dict[str, float] = {"ankle": 0.010, "knee": 0.005, "hip": 0.005}
#: Raw joint-moment noise (N m) from 1 mm markers x GRF lever and 2 N force noise.
MOMENT_NOISE_NM = 2.0
#: Touchdown angles (rad) in the joint_angles convention (upright knee/hip = pi).
TOUCHDOWN_ANGLE_RAD: dict[str, float] = {"ankle": 1.35, "knee": 3.0, "hip": 2.95}


@dataclass(frozen=True)
class SyntheticStance:
    """One synthetic stance of one joint.

    Attributes
    ----------
    time_s, angle_rad, angular_velocity_rad_s, moment_nm : ndarray, shape (N,)
        Measured signals (noisy when requested); time starts at 0 (touchdown).
    true_coefficients : dict
        ``m0`` (N m), ``k0``, ``k1`` (N m/rad), ``b0`` (N m s/rad); the other
        Eq. 3 terms are zero.
    true_moment_nm : ndarray, shape (N,)
        Noise-free moment.
    """

    time_s: np.ndarray
    angle_rad: np.ndarray
    angular_velocity_rad_s: np.ndarray
    moment_nm: np.ndarray
    true_coefficients: dict[str, float]
    true_moment_nm: np.ndarray


def _filtered_noise(rng: np.random.Generator, n: int, sigma: float, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    sos = signal.butter(4, cutoff_hz, fs=rate_hz, output="sos")
    raw = rng.normal(0.0, sigma, 3 * n)
    filtered: np.ndarray = signal.sosfiltfilt(sos, raw)  # scipy.signal has no type information
    return filtered[n : 2 * n]


def seed_trajectory(joint: str, frequency_hz: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time (s), angle rho (rad) and omega (rad/s), shapes (N,), of a stance with Table 1's time and range of flexion.

    ``rho = rho0 + A sin(pi s) - e s`` with the warped time
    ``s = t/T - c sin(2 pi t/T) / (2 pi)`` (module docstring), sampled at ``rate_hz`` from touchdown.
    """
    T = TABLE1_STANCE_TIME_S[frequency_hz]
    A = TABLE1_RANGE_OF_FLEXION_RAD[frequency_hz][joint]
    e, c = 0.1 * A, 0.2
    n = int(round(T * rate_hz)) + 1
    t = np.arange(n) / rate_hz
    s = t / T - c * np.sin(2 * np.pi * t / T) / (2 * np.pi)
    s_dot = (1.0 - c * np.cos(2 * np.pi * t / T)) / T
    rho = TOUCHDOWN_ANGLE_RAD[joint] + A * np.sin(np.pi * s) - e * s
    omega = (A * np.pi * np.cos(np.pi * s) - e) * s_dot
    return t, rho, omega


def seed_law_moment(d: np.ndarray, omega: np.ndarray, coefficients: tuple[float, float, float, float]) -> np.ndarray:
    """Moment (N m) of the seed's reduced law (Eqs. 10-11) in closed form, independent of the regressor code.

    ``M = m0 + k0 d + k1 d**2 / 2 + b0 omega`` for ``coefficients = (m0, k0, k1, b0)``
    and ``d = rho - rho0`` (rad), ``omega`` (rad/s).
    """
    m0, k0, k1, b0 = coefficients
    return m0 + k0 * d + k1 * d**2 / 2 + b0 * omega


def synthetic_stance(
    joint: str,
    frequency_hz: float,
    rng: np.random.Generator | None = None,
    rate_hz: float = 200.0,
    realistic_noise: bool = False,
    b0: float = 0.5,
    m0: float = 0.0,
    coefficient_scale: float = 1.0,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
) -> SyntheticStance:
    """A stance of ``joint`` at one of the seed's hopping frequencies.

    Parameters
    ----------
    joint : {"ankle", "knee", "hip"}
    frequency_hz : {1.53, 1.87, 2.20}
        Selects Table 1 stance time and range of flexion and Table 2 k0, k1.
    rng : numpy.random.Generator, optional
        Noise source (required when ``realistic_noise``).
    rate_hz : float
        Sample rate (Hz).
    realistic_noise : bool
        Add filtered angle and moment noise (module docstring).
    b0 : float
        Constant damping (N m s/rad); the seed reports below 0.72.
    m0 : float
        Touchdown spring moment (N m).
    coefficient_scale : float
        Multiplies k0 and k1 (between-stance variability in tests).
    cutoff_hz : float
        Low-pass cutoff of the noise (Hz).

    Returns
    -------
    SyntheticStance
    """
    k0, k1 = (coefficient_scale * c for c in TABLE2_COEFFICIENTS[frequency_hz][joint])
    t, rho, omega = seed_trajectory(joint, frequency_hz, rate_hz)
    moment = seed_law_moment(rho - rho[0], omega, (m0, k0, k1, b0))
    angle_meas, omega_meas, moment_meas = rho.copy(), omega.copy(), moment.copy()
    if realistic_noise:
        if rng is None:
            raise ValueError("synthetic_stance: realistic_noise needs an rng")
        angle_noise = _filtered_noise(rng, t.size, ANGLE_NOISE_RAD[joint], rate_hz, cutoff_hz)
        angle_meas = rho + angle_noise
        omega_meas = omega + np.gradient(angle_noise, t)
        moment_meas = moment + _filtered_noise(rng, t.size, MOMENT_NOISE_NM, rate_hz, cutoff_hz)
    return SyntheticStance(
        time_s=t,
        angle_rad=angle_meas,
        angular_velocity_rad_s=omega_meas,
        moment_nm=moment_meas,
        true_coefficients={"m0": m0, "k0": k0, "k1": k1, "b0": b0},
        true_moment_nm=moment,
    )
