"""The constant ("overall") stiffness model the seed compares against (Table 3).

Overall stiffness (seed, Results): ratio of the overall moment change to the
overall angle change of the moment-angle curve. Choice: the change from
touchdown (sample 0) to the sample of maximal flexion (max rho), where the
seed notes the moment peak and the angle peak coincide::

    K_overall = (tau[i_max] - tau[0]) / (rho[i_max] - rho0)

Its moment prediction from kinematics is ``tau[0] + K_overall (rho - rho0)``.
NaN when the joint flexes by 1 mrad or less beyond touchdown (:data:`MIN_FLEXION_CHANGE_RAD`).
"""

from __future__ import annotations

import numpy as np

#: Smallest angle change (rad) from touchdown to maximal flexion over which an overall stiffness is given.
#: Choice, one threshold for the per-stance metrics and the fit (issue 20; they were 1e-3 and 0): below
#: 1 mrad the ratio is mostly noise (2 N m of moment noise over 1 mrad is 2,000 N m/rad).
MIN_FLEXION_CHANGE_RAD = 1e-3


def overall_stiffness(angle_rad: np.ndarray, moment_nm: np.ndarray, min_change_rad: float = MIN_FLEXION_CHANGE_RAD) -> float:
    """Overall joint stiffness (N m/rad) from touchdown to maximal flexion (the seed's Table 2 "overall").

    Parameters
    ----------
    angle_rad : ndarray, shape (N,)
        Joint angle rho (rad), flexion positive; sample 0 is touchdown.
    moment_nm : ndarray, shape (N,)
        Inverse-dynamics moment (N m), extensor positive.
    min_change_rad : float
        Angle changes at or below this (rad) give NaN.

    Returns
    -------
    float
        ``(tau[i_max] - tau[0]) / (rho[i_max] - rho[0])`` with ``i_max`` the
        sample of maximal rho; NaN when the joint flexes by ``min_change_rad``
        or less beyond its touchdown angle.
    """
    rho = np.asarray(angle_rad, float)[:, None]
    return float(overall_stiffness_columns(rho, np.asarray(moment_nm, float)[:, None], min_change_rad)[0])


def overall_stiffness_columns(
    angle_rad: np.ndarray, moment_nm: np.ndarray, min_change_rad: float = MIN_FLEXION_CHANGE_RAD
) -> np.ndarray:
    """:func:`overall_stiffness` of J joints at once (the one implementation; N m/rad), shape (J,).

    ``angle_rad`` and ``moment_nm`` have shape (N, J), one joint per column.
    ``biomech.stance_metrics.overall_joint_stiffness`` (the analysis'
    per-stance metrics) is this function.
    """
    rho = np.asarray(angle_rad, float)
    tau = np.asarray(moment_nm, float)
    i_max = np.argmax(rho, axis=0)
    joints = np.arange(rho.shape[1])
    span = rho[i_max, joints] - rho[0]
    change = tau[i_max, joints] - tau[0]
    out = np.full(span.shape, np.nan)
    ok = span > min_change_rad
    out[ok] = change[ok] / span[ok]
    return out


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
    moment: np.ndarray = float(moment_nm[0]) + stiffness_nm_rad * (rho - rho[0])
    return moment


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
