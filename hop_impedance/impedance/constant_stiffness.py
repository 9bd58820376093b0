"""The constant ("overall") stiffness model the seed compares against (Table 3).

Overall stiffness (seed, Results): ratio of the overall moment change to the
overall angle change of the moment-angle curve. Choice: the change from
touchdown (sample 0) to the sample of maximal flexion (max rho), where the
seed notes the moment peak and the angle peak coincide::

    K_overall = (tau[i_max] - tau[0]) / (rho[i_max] - rho0)

Its moment prediction from kinematics is ``tau[0] + K_overall (rho - rho0)``.
"""

from __future__ import annotations

import numpy as np


def overall_stiffness(angle_rad: np.ndarray, moment_nm: np.ndarray) -> float:
    """Overall joint stiffness (N m/rad) from touchdown to maximal flexion.

    Parameters
    ----------
    angle_rad : ndarray, shape (N,)
        Joint angle rho (rad), flexion positive; sample 0 is touchdown.
    moment_nm : ndarray, shape (N,)
        Inverse-dynamics moment (N m), extensor positive.

    Returns
    -------
    float
        ``(tau[i_max] - tau[0]) / (rho[i_max] - rho[0])``; NaN when the joint
        never flexes beyond its touchdown angle.
    """
    rho = np.asarray(angle_rad, float)
    tau = np.asarray(moment_nm, float)
    i_max = int(np.argmax(rho))
    span = rho[i_max] - rho[0]
    if span <= 0.0:
        return float("nan")
    return float((tau[i_max] - tau[0]) / span)


def constant_stiffness_moment(angle_rad: np.ndarray, moment_nm: np.ndarray, stiffness_nm_rad: float) -> np.ndarray:
    """Moment predicted by a constant stiffness from the touchdown moment (N m).

    Parameters
    ----------
    angle_rad, moment_nm : ndarray, shape (N,)
        As in :func:`overall_stiffness`.
    stiffness_nm_rad : float
        Constant stiffness (N m/rad).

    Returns
    -------
    ndarray, shape (N,)
        ``tau[0] + K (rho - rho[0])``.
    """
    rho = np.asarray(angle_rad, float)
    return float(moment_nm[0]) + stiffness_nm_rad * (rho - rho[0])


def table3_error(sse: float, n_samples: int, frame_rate_hz: float) -> float:
    """The seed's Table 3 error metric ``(SSE x 1e-3) / N x FR``.

    Parameters
    ----------
    sse : float
        Sum of squared moment errors over the stance (N^2 m^2).
    n_samples : int
        Number of samples N in the stance.
    frame_rate_hz : float
        Sample (camera frame) rate FR (Hz); the seed used 50.

    Returns
    -------
    float
        Read literally as ``sse * 1e-3 / n_samples * frame_rate_hz``.
    """
    return float(sse * 1e-3 / n_samples * frame_rate_hz)
