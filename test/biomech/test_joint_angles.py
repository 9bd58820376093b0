"""Sign conventions of the seed's Eq. 2 as chosen in ``hop_impedance/biomech/joint_angles.py``.

Known postures drawn by hand (sagittal x forward, z up, metres): upright standing gives knee and hip angles
of exactly pi, and each joint angle grows with that joint's flexion (ankle dorsiflexion, knee flexion, hip
flexion) and with nothing else.
"""

import numpy as np
import pytest

from hop_impedance.biomech.joint_angles import SEGMENT_ENDPOINTS, joint_angles, segment_angle

UPRIGHT = {"toe": (0.15, 0.0), "ankle": (0.0, 0.08), "knee": (0.0, 0.50), "hip": (0.0, 0.90), "head": (0.0, 1.60)}


def _rho(points: dict, alpha_rad: float = 0.3) -> np.ndarray:
    q = np.array([[segment_angle(np.array([points[d]]), np.array([points[p]]))[0]
                   for d, p in SEGMENT_ENDPOINTS.values()]])
    return joint_angles(q, alpha_rad)[0]


def test_upright_standing():
    q_shank = segment_angle(np.array([UPRIGHT["ankle"]]), np.array([UPRIGHT["knee"]]))[0]
    assert q_shank == pytest.approx(np.pi / 2, abs=1e-15)
    rho = _rho(UPRIGHT)
    assert rho[1] == pytest.approx(np.pi, abs=1e-15) and rho[2] == pytest.approx(np.pi, abs=1e-15)
    # ankle: foot angle (toe->ankle) minus the vertical shank plus alpha
    assert rho[0] == pytest.approx(np.arctan2(0.08, -0.15) - np.pi / 2 + 0.3, abs=1e-15)


def test_each_angle_grows_with_its_own_flexion():
    up = _rho(UPRIGHT)
    crouch = dict(UPRIGHT, knee=(0.10, 0.48), hip=(0.0, 0.86), head=(0.0, 1.56))  # shank forward, thigh back
    d = _rho(crouch) - up
    shank_tilt, thigh_tilt = np.pi / 2 - np.arctan2(0.40, 0.10), np.arctan2(0.38, -0.10) - np.pi / 2
    assert d[0] == pytest.approx(shank_tilt, abs=1e-12) and d[0] > 0  # shank forward over a flat foot: dorsiflexion
    assert d[1] == pytest.approx(shank_tilt + thigh_tilt, abs=1e-12) and d[1] > 0  # knee flexion
    assert d[2] == pytest.approx(thigh_tilt, abs=1e-12) and d[2] > 0  # knee ahead of the hip, trunk upright: hip flexion
    lean = dict(UPRIGHT, head=(0.30, 1.55))  # trunk leans forward over a vertical thigh: hip flexion only
    d = _rho(lean) - up
    assert d[0] == 0.0 and d[1] == 0.0
    assert d[2] == pytest.approx(np.pi / 2 - np.arctan2(0.65, 0.30), abs=1e-12) and d[2] > 0
    tiptoe = dict(UPRIGHT, toe=(0.15, 0.0), ankle=(0.05, 0.16))  # heel raised, leg vertical: plantarflexion
    tiptoe.update(knee=(0.05, 0.58), hip=(0.05, 0.98), head=(0.05, 1.68))
    d = _rho(tiptoe) - up
    assert d[0] < -0.3 and d[1] == pytest.approx(0.0, abs=1e-12) and d[2] == pytest.approx(0.0, abs=1e-12)
