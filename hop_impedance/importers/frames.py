"""Map a lab's axes to the contract frame (x forward, y left, z up).

Labs differ: Vicon and most C3D files are z-up, OpenSim files (TRC/MOT) are
y-up, and the direction the subject faces is whatever the lab's layout made it.
The contract wants x = the subject's forward (anterior) direction, z = up and
y = z x x (to the subject's left), so that the sagittal plane is x-z.

Everything here builds or applies one rotation matrix ``R`` (3, 3) whose rows
are the contract axes written in lab coordinates, so that a lab vector ``v``
becomes ``R @ v`` in the contract frame. Positions are shifted by an origin
first (the contract frame's origin is the force plates' common origin, see
:mod:`hop_impedance.importers.plates`).

Choice (documented and tested): the forward direction is the *horizontal*
direction the subject faces, taken exactly (not snapped to a lab axis), so a
subject standing at 10 degrees to the lab's X axis still gets a clean sagittal
plane. Give ``forward`` explicitly (e.g. ``"+X"``) to snap it to a lab axis.
"""

from __future__ import annotations

import numpy as np

_AXES = {"X": 0, "Y": 1, "Z": 2}


def parse_axis(spec: str) -> np.ndarray:
    """Unit vector of a signed lab axis such as ``"+Y"``, ``"-x"`` or ``"Z"``.

    Parameters
    ----------
    spec : str
        Optional sign (``+``/``-``) followed by ``X``, ``Y`` or ``Z`` (any case).

    Returns
    -------
    ndarray, shape (3,)
        The axis as a unit vector in lab coordinates.

    Raises
    ------
    ValueError
        If ``spec`` is not of that form.
    """
    text = str(spec).strip().upper()
    sign = -1.0 if text.startswith("-") else 1.0
    letter = text.lstrip("+-")
    if letter not in _AXES or len(text) - len(letter) > 1:
        raise ValueError(f"axis {spec!r} is not a signed lab axis like '+Z', '-X' or 'Y'")
    out = np.zeros(3)
    out[_AXES[letter]] = sign
    return out


def rotation_to_contract(up_lab: np.ndarray, forward_lab: np.ndarray) -> np.ndarray:
    """Rotation from lab to contract coordinates given the lab's up and forward directions.

    Parameters
    ----------
    up_lab : array_like, shape (3,)
        The upward vertical in lab coordinates (any length).
    forward_lab : array_like, shape (3,)
        The subject's forward direction in lab coordinates; its vertical part
        is removed, only the horizontal heading is used.

    Returns
    -------
    ndarray, shape (3, 3)
        Proper rotation (det = +1) whose rows are the contract's x (forward),
        y (left = z x x) and z (up) in lab coordinates: ``v_contract = R @ v_lab``.

    Raises
    ------
    ValueError
        If ``forward_lab`` is (nearly) vertical or either vector is zero.
    """
    z = np.asarray(up_lab, float)
    if not np.all(np.isfinite(z)) or np.linalg.norm(z) == 0:
        raise ValueError("up direction must be a finite non-zero vector")
    z = z / np.linalg.norm(z)
    f = np.asarray(forward_lab, float)
    x = f - np.dot(f, z) * z
    if not np.all(np.isfinite(x)) or np.linalg.norm(x) < 1e-6 * max(float(np.linalg.norm(f)), 1e-300):
        raise ValueError(f"forward direction {f.tolist()} is vertical; it must have a horizontal part")
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    return np.vstack([x, y, z])


def detect_forward(rear_m: list[np.ndarray], front_m: list[np.ndarray], up_lab: np.ndarray) -> np.ndarray:
    """Horizontal direction the subject faces, from rear->front marker pairs.

    Each pair is e.g. heel->toe or PSIS->ASIS. The horizontal unit vectors
    of each pair are averaged over its finite frames, then the pairs are
    averaged with equal weight (so an occluded frame does not tilt the
    balance), which cancels the toe-out of left and right feet when both are
    given.

    Parameters
    ----------
    rear_m, front_m : list of ndarray, each shape (N, 3)
        Positions (lab coordinates, any length unit) of the rear and front
        marker of each pair; NaN frames are ignored.
    up_lab : array_like, shape (3,)
        Upward vertical in lab coordinates.

    Returns
    -------
    ndarray, shape (3,)
        Unit horizontal forward direction in lab coordinates.

    Raises
    ------
    ValueError
        If no pair has a finite horizontal vector, or the pairs disagree so
        much that their mean direction is undefined.
    """
    z = np.asarray(up_lab, float) / np.linalg.norm(up_lab)
    pair_means = []
    for rear, front in zip(rear_m, front_m):
        d = np.asarray(front, float) - np.asarray(rear, float)
        d = d - np.outer(d @ z, z)
        n = np.linalg.norm(d, axis=1)
        ok = np.isfinite(n) & (n > 0)
        if ok.any():
            pair_means.append((d[ok] / n[ok, None]).mean(axis=0))
    if not pair_means:
        raise ValueError("cannot detect the forward direction: no frame has both markers of a rear->front pair")
    mean = np.mean(pair_means, axis=0)
    if np.linalg.norm(mean) < 0.5:
        raise ValueError(
            "cannot detect the forward direction: rear->front marker pairs point in inconsistent "
            f"directions (mean resultant length {np.linalg.norm(mean):.2f} < 0.5); give it explicitly"
        )
    return mean / np.linalg.norm(mean)


def detect_up_axis(lower_m: np.ndarray, upper_m: np.ndarray) -> np.ndarray:
    """Signed lab axis along which an upper marker sits above a lower one.

    Used when a file does not say which axis is vertical: the head (or
    shoulder) marker is far above the toe marker along the vertical axis.

    Parameters
    ----------
    lower_m, upper_m : ndarray, shape (N, 3)
        Lab positions of a low marker (toe) and a high marker (head).

    Returns
    -------
    ndarray, shape (3,)
        The signed lab axis (unit vector) with the largest median upper-lower
        component.

    Raises
    ------
    ValueError
        If no frame has both markers.
    """
    d = np.asarray(upper_m, float) - np.asarray(lower_m, float)
    d = d[np.all(np.isfinite(d), axis=1)]
    if d.shape[0] == 0:
        raise ValueError("cannot detect the vertical axis: no frame has both the toe and the head marker")
    med = np.median(d, axis=0)
    k = int(np.argmax(np.abs(med)))
    out = np.zeros(3)
    out[k] = np.sign(med[k])
    return out


def to_contract(vectors: np.ndarray, rotation: np.ndarray, origin_lab: np.ndarray | None = None) -> np.ndarray:
    """Express lab vectors or positions in the contract frame.

    Parameters
    ----------
    vectors : ndarray, shape (..., 3)
        Lab coordinates (any unit; NaN propagates).
    rotation : ndarray, shape (3, 3)
        From :func:`rotation_to_contract`.
    origin_lab : ndarray, shape (3,), optional
        For positions: the contract origin in lab coordinates, subtracted
        before rotating. Leave None for free vectors (forces, moments).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    v = np.asarray(vectors, float)
    if origin_lab is not None:
        v = v - np.asarray(origin_lab, float)
    return v @ np.asarray(rotation, float).T
