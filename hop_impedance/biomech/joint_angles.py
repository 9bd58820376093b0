"""Segment and joint angles of the contract (the seed paper's Eq. 2).

Sign conventions (chosen here, tested in ``test/biomech/test_joint_angles.py``)
-------------------------------------------------------------------------------
- The sagittal picture is the lab's x-z plane seen from the subject's right
  side: x forward to the right, z up, counter-clockwise angles positive.
- Absolute segment angle q_i = atan2(dz, dx) of the vector from the segment's
  distal to its proximal point, measured from the forward horizontal:
  q1 foot = toe->ankle, q2 shank = ankle->knee, q3 thigh = knee->hip,
  q4 HAT = hip->head. Standing upright: q2 = q3 = q4 = pi/2.
- Joint angles (Eq. 2): rho1 = q1 - q2 + alpha, rho2 = q3 - q2 + pi,
  rho3 = q3 - q4 + pi. With these conventions every rho *increases with
  flexion* (ankle dorsiflexion, knee and hip flexion): upright standing gives
  rho2 = rho3 = pi and rho1 = pi/2 (alpha is the foot's toe angle, see
  :attr:`FootGeometry.alpha_rad`). This is the direction in which the seed's
  Table 2 k1 > 0 makes stiffness peak at maximal flexion (mid-stance).
- Net joint moments are reported extensor (ankle: plantarflexor) positive,
  i.e. positive moments act to *decrease* rho. Joint power is therefore
  P = -M * d(rho)/dt: negative while an extensor moment brakes flexion.
"""

from __future__ import annotations

import numpy as np

SEGMENT_ENDPOINTS: dict[str, tuple[str, str]] = {
    "foot": ("toe", "ankle"),
    "shank": ("ankle", "knee"),
    "thigh": ("knee", "hip"),
    "hat": ("hip", "head"),
}

JOINT_NAMES: tuple[str, ...] = ("ankle", "knee", "hip")


def segment_angle(distal_xz: np.ndarray, proximal_xz: np.ndarray) -> np.ndarray:
    """Absolute angle from the forward horizontal (rad), unwrapped in time.

    Parameters
    ----------
    distal_xz, proximal_xz : ndarray, shape (N, 2)
        Sagittal positions ``[x, z]`` (m) of the segment's distal and proximal point.

    Returns
    -------
    ndarray, shape (N,)
        q = atan2(dz, dx), counter-clockwise positive, unwrapped so that it is
        continuous over time (NaN samples are passed through).
    """
    d = np.asarray(proximal_xz, float) - np.asarray(distal_xz, float)
    q: np.ndarray = np.arctan2(d[..., 1], d[..., 0])
    ok = np.isfinite(q)
    if ok.any():
        q[ok] = np.unwrap(q[ok])
    return q


def joint_angles(q: np.ndarray, alpha_rad: float) -> np.ndarray:
    """Joint angles rho1..rho3 (ankle, knee, hip) from segment angles (Eq. 2).

    Parameters
    ----------
    q : ndarray, shape (N, 4)
        Segment angles q1..q4 (rad): foot, shank, thigh, HAT.
    alpha_rad : float
        Constant foot angle alpha (rad).

    Returns
    -------
    ndarray, shape (N, 3)
        rho (rad); increases with flexion (see module docstring).
    """
    q = np.asarray(q, float)
    return np.stack(
        [
            q[:, 0] - q[:, 1] + alpha_rad,
            q[:, 2] - q[:, 1] + np.pi,
            q[:, 2] - q[:, 3] + np.pi,
        ],
        axis=1,
    )


def joint_rates(qd: np.ndarray) -> np.ndarray:
    """Joint angular rates (rad/s), shape (N, 3), ankle, knee, hip: :func:`joint_angles` differentiated.

    ``qd`` are the segment rates q1..q4 (rad/s), shape (N, 4); alpha and pi
    are constant, so each rate is a difference of two segment rates.
    """
    return np.stack([qd[:, 0] - qd[:, 1], qd[:, 2] - qd[:, 1], qd[:, 2] - qd[:, 3]], axis=1)


def segment_angles_from_joint_angles(rho: np.ndarray, q_foot: np.ndarray, alpha_rad: float) -> np.ndarray:
    """Inverse of :func:`joint_angles` given the foot angle (rad), shape (N, 4)."""
    rho = np.atleast_2d(np.asarray(rho, float))
    q1 = np.asarray(q_foot, float)
    q2 = q1 + alpha_rad - rho[:, 0]
    q3 = rho[:, 1] + q2 - np.pi
    q4 = q3 + np.pi - rho[:, 2]
    return np.stack([q1, q2, q3, q4], axis=1)
