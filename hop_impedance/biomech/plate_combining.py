"""Several force plates as the contract's one wrench (pure core, no ROS).

The contract carries one wrench: the ground reaction force on the subject and
its moment about *one* origin, so that ``cop_x = -torque.y / force.z`` is the
combined centre of pressure. With one plate per foot the forces add and each
plate's moment is carried to the common origin:
``M = sum_i (M_i + (r_i - O) x F_i)`` (:func:`total_wrench`). The importers
(C3D, MOT) and the live plate combiner (``nodes/plate_combiner.py``) both use
this one function.
"""

from __future__ import annotations

import numpy as np


def total_wrench(
    forces_n: np.ndarray, moments_nm: np.ndarray, points_m: np.ndarray, origin_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sum of several plates' wrenches, moment about one common origin.

    Parameters
    ----------
    forces_n : ndarray, shape (P, N, 3)
        Force of each of P plates at N samples (N), any frame common to all.
    moments_nm : ndarray, shape (P, N, 3)
        Moment of each plate about its reference point (N m), same frame.
    points_m : ndarray, shape (P, N, 3) or (P, 3)
        Reference point of each plate's moment (m), same frame (per sample,
        e.g. the centre of pressure, or fixed, e.g. the plate centre).
    origin_m : ndarray, shape (3,)
        The common origin (m).

    Returns
    -------
    force_n : ndarray, shape (N, 3)
        Total force.
    moment_nm : ndarray, shape (N, 3)
        Total moment about ``origin_m``.

    Notes
    -----
    Samples where a plate is unloaded often carry NaN or garbage centres of
    pressure; a plate with zero force contributes only its moment, and a NaN
    reference point is treated as zero lever arm when the force is exactly
    zero.
    """
    f = np.asarray(forces_n, float)
    m = np.asarray(moments_nm, float)
    r = np.asarray(points_m, float)
    if r.ndim == 2:
        r = np.broadcast_to(r[:, None, :], f.shape)
    lever = r - np.asarray(origin_m, float)
    unloaded = np.all(f == 0.0, axis=-1, keepdims=True)
    lever = np.where(unloaded & ~np.isfinite(lever), 0.0, lever)
    return f.sum(axis=0), (m + np.cross(lever, f)).sum(axis=0)
