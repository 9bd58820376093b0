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

# One implementation of the moment transfer, shared with the live plate combiner (nodes/plate_combiner.py).
from hop_impedance.biomech.plate_combining import total_wrench

__all__ = ["orient_reaction", "total_wrench"]


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
