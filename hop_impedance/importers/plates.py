"""Combine several force plates into the contract's single wrench.

The contract carries one wrench: the ground reaction force on the subject and
its moment about *one* origin on the ground, so that
``cop_x = -torque.y / force.z`` is the combined centre of pressure. With two
plates (one per foot) the forces add and the moments are carried to a common
origin: ``M_total = sum_i (M_i + (r_i - O) x F_i)``, where ``M_i`` is plate
i's moment about its reference point ``r_i`` (its top-surface centre, or the
centre of pressure with a free vertical torque as in OpenSim MOT files).

Choice (documented, tested): the common origin ``O`` is chosen by the caller
and becomes the contract frame's origin; markers are shifted by the same
origin, so the contract's COP formula lands in the markers' frame. The C3D
importer uses the first used plate's top centre; the MOT importer uses the lab
origin dropped to the ground level of the centres of pressure.
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


def orient_reaction(force_n: np.ndarray, moment_nm: np.ndarray, min_fz_n: float = 20.0) -> tuple[np.ndarray, np.ndarray, bool]:
    """Make the wrench the reaction *on the subject* (vertical force up).

    Plates report either the force the subject exerts on the plate (action,
    vertical component down) or the ground reaction on the subject. The
    contract wants the reaction; the file rarely says which, but gravity
    does: while someone is on the plate the reaction's vertical component is
    positive.

    Parameters
    ----------
    force_n, moment_nm : ndarray, shape (N, 3)
        Total wrench in the contract frame (z up).
    min_fz_n : float
        |Fz| (N) above which a sample counts as loaded.

    Returns
    -------
    force_n, moment_nm : ndarray, shape (N, 3)
        Reaction wrench (both negated if the input was the action).
    flipped : bool
        Whether the sign was flipped.

    Raises
    ------
    ValueError
        If no sample is loaded (no one stood on the plates).
    """
    fz = force_n[:, 2]
    loaded = np.isfinite(fz) & (np.abs(fz) > min_fz_n)
    if not loaded.any():
        raise ValueError(f"no force-plate sample has a vertical force above {min_fz_n:g} N: nobody stood on the plates")
    if np.median(fz[loaded]) < 0:
        return -force_n, -moment_nm, True
    return force_n, moment_nm, False
