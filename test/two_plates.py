"""Test fixture: one summed-plate recording re-expressed as two plates, one per foot.

Built here with explicit physics, independently of ``biomech.plate_combining``:
the total wrench (force F and moment M about the contract origin O, lab axes)
is shared between the feet with an asymmetric, time-varying fraction s(t),
plus an equal and opposite couple D x F that a real pair of feet apart
produces without changing the total; each plate's moment is then moved from O
to the plate's own origin r_k (``M_k = M_k^O - (r_k - O) x F_k``) and both
vectors are rotated into the plate's own axes. The right plate is stamped
``SKEW_NS`` later than the left (same instants, separately stamped).
"""

from __future__ import annotations

import numpy as np

from hop_impedance.recording import FORCE_TOPIC, ForcePlateSeries

#: Lab-frame plate origins (m): distinct, neither at the contract origin.
LEFT_ORIGIN = np.array([0.05, 0.25, 0.0])
RIGHT_ORIGIN = np.array([-0.10, -0.30, 0.0])
#: The right plate is mounted turned round (its x and y axes point backwards and to the right).
RIGHT_YAW_DEG = 180.0
#: Stamp skew of the right plate against the left (ns).
SKEW_NS = 500_000
#: Half the distance between the feet's centres of pressure (m), for the couple.
FEET_APART_M = np.array([0.02, 0.20, 0.0])

LEFT_TOPIC = "/force_plate/left"
RIGHT_TOPIC = "/force_plate/right"


def left_share(t_s: np.ndarray) -> np.ndarray:
    """Fraction of the load on the left plate: asymmetric (mean 0.62) and varying in time."""
    return 0.62 + 0.1 * np.sin(2 * np.pi * 3.0 * t_s)


def _yaw_matrix(deg: float) -> np.ndarray:
    if deg == 180.0:
        return np.diag([-1.0, -1.0, 1.0])
    if deg == 0.0:
        return np.eye(3)
    raise ValueError("fixture only knows 0 and 180 deg")


def split_two_plates(force: ForcePlateSeries) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{topic: (stamps_ns, wrench (N, 6) in the plate's axes about its origin)}`` for left and right."""
    t = (force.stamp_ns - force.stamp_ns[0]) * 1e-9
    s = left_share(t)[:, None]
    f, m = force.force_n, force.torque_nm
    couple = s * (1 - s) * np.cross(FEET_APART_M, f)
    out = {}
    for topic, share, sign, origin, yaw, skew in (
        (LEFT_TOPIC, s, 1.0, LEFT_ORIGIN, 0.0, 0),
        (RIGHT_TOPIC, 1 - s, -1.0, RIGHT_ORIGIN, RIGHT_YAW_DEG, SKEW_NS),
    ):
        f_k = share * f
        m_k_about_o = share * m + sign * couple
        m_k = m_k_about_o - np.cross(origin, f_k)  # contract origin O = 0
        rot = _yaw_matrix(yaw)  # plate axes -> lab axes; lab -> plate is its transpose
        out[topic] = (force.stamp_ns + skew, np.hstack([f_k @ rot, m_k @ rot]))
    return out


def combiner_parameters() -> dict:
    """The plate_combiner node's parameters for this layout (as in config/plates.yaml)."""
    return {
        "plate_topics": [LEFT_TOPIC, RIGHT_TOPIC],
        "plate_names": ["left", "right"],
        "plate_origins_m": [*LEFT_ORIGIN.tolist(), *RIGHT_ORIGIN.tolist()],
        "plate_yaw_deg": [0.0, RIGHT_YAW_DEG],
        "output_topic": FORCE_TOPIC,
    }
