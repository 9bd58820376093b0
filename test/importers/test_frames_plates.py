"""Axis mapping (frames.py) and multi-plate wrench combination (plates.py)."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.importers.frames import detect_forward, detect_up_axis, parse_axis, rotation_to_contract, to_contract
from hop_impedance.importers.plates import orient_reaction, total_wrench
from hop_impedance.recording import ForcePlateSeries


class TestParseAxis:
    def test_signed_axes(self):
        np.testing.assert_array_equal(parse_axis("+Y"), [0, 1, 0])
        np.testing.assert_array_equal(parse_axis("-z"), [0, 0, -1])
        np.testing.assert_array_equal(parse_axis("X"), [1, 0, 0])

    @pytest.mark.parametrize("bad", ["W", "+-X", "", "XY"])
    def test_rejects(self, bad):
        with pytest.raises(ValueError, match="signed lab axis"):
            parse_axis(bad)


class TestRotationToContract:
    def test_opensim_y_up_x_forward(self):
        # OpenSim: X forward, Y up, Z to the subject's right -> contract y (left) = -Z.
        rot = rotation_to_contract(parse_axis("+Y"), parse_axis("+X"))
        np.testing.assert_allclose(rot @ [1, 0, 0], [1, 0, 0])
        np.testing.assert_allclose(rot @ [0, 1, 0], [0, 0, 1])
        np.testing.assert_allclose(rot @ [0, 0, 1], [0, -1, 0])

    def test_proper_rotation_for_any_heading(self):
        rng = np.random.default_rng(0)
        for _ in range(20):
            rot = rotation_to_contract(rng.normal(size=3), rng.normal(size=3))
            np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
            assert np.linalg.det(rot) == pytest.approx(1.0)

    def test_vertical_forward_is_refused(self):
        with pytest.raises(ValueError, match="vertical"):
            rotation_to_contract([0, 0, 1], [0, 0, 2])

    def test_positions_are_shifted_then_rotated(self):
        rot = rotation_to_contract(parse_axis("+Z"), parse_axis("-Y"))
        out = to_contract(np.array([[1.0, 2.0, 0.5]]), rot, origin_lab=np.array([1.0, 3.0, 0.0]))
        # lab (0, -1, 0.5) relative to origin: 1 m along -Y = 1 m forward.
        np.testing.assert_allclose(out, [[1.0, 0.0, 0.5]], atol=1e-12)


class TestDetectForward:
    def test_toe_out_of_both_feet_cancels(self):
        # Feet turned out by +-12 degrees around the true heading 30 degrees from lab X (z up).
        heading = np.radians(30)
        rear, front = [], []
        for out in (+12, -12):
            a = heading + np.radians(out)
            heel = np.zeros((50, 3))
            toe = heel + 0.2 * np.array([np.cos(a), np.sin(a), 0.03])
            rear.append(heel)
            front.append(toe)
        front[0][5] = np.nan  # an occluded frame is ignored
        fwd = detect_forward(rear, front, [0, 0, 1])
        np.testing.assert_allclose(fwd, [np.cos(heading), np.sin(heading), 0], atol=1e-12)

    def test_inconsistent_pairs(self):
        heel = np.zeros((10, 3))
        with pytest.raises(ValueError, match="inconsistent"):
            detect_forward([heel, heel], [heel + [1, 0, 0], heel - [1, 0, 0]], [0, 0, 1])

    def test_no_frames(self):
        nan = np.full((4, 3), np.nan)
        with pytest.raises(ValueError, match="no frame"):
            detect_forward([nan], [nan], [0, 0, 1])


def test_detect_up_axis_from_toe_and_head():
    toe = np.zeros((10, 3))
    head = toe + [0.1, -1.6, 0.05]
    np.testing.assert_array_equal(detect_up_axis(toe, head), [0, -1, 0])


class TestTotalWrench:
    def test_two_feet_cop_is_force_weighted(self):
        # Plate wrenches given as force at the COP plus a free vertical torque (OpenSim MOT style).
        f = np.array([[[10.0, 2.0, 400.0]], [[-5.0, -1.0, 600.0]]])
        cop = np.array([[[0.12, 0.10, 0.0]], [[0.02, -0.10, 0.0]]])
        free = np.array([[[0.0, 0.0, 1.5]], [[0.0, 0.0, -0.5]]])
        force, moment = total_wrench(f, free, cop, np.zeros(3))
        series = ForcePlateSeries(np.array([0]), force, moment)
        assert series.cop_x_m()[0] == pytest.approx((0.12 * 400 + 0.02 * 600) / 1000)
        np.testing.assert_allclose(force[0], [5.0, 1.0, 1000.0])
        # Independent component formula: My = sum(z Fx - x Fz), Mz = sum(x Fy - y Fx + free).
        assert moment[0, 1] == pytest.approx(-(0.12 * 400 + 0.02 * 600))
        assert moment[0, 2] == pytest.approx(0.12 * 2 - 0.10 * 10 + 1.5 + 0.02 * -1 - (-0.10) * -5 - 0.5)

    def test_moment_about_other_origin(self):
        # M_O = M_P + (P - O) x F, with fixed plate centres.
        f = np.array([[[0.0, 0.0, 700.0]]])
        m = np.array([[[3.0, -14.0, 0.0]]])  # COP at (+0.02, +0.00429) about the plate centre
        centre = np.array([[0.5, 0.3, 0.0]])
        force, moment = total_wrench(f, m, centre, np.zeros(3))
        cop = ForcePlateSeries(np.array([0]), force, moment).cop_x_m()[0]
        assert cop == pytest.approx(0.5 + 14.0 / 700.0)

    def test_unloaded_plate_with_nan_cop_contributes_nothing(self):
        f = np.array([[[0.0, 0.0, 0.0]], [[0.0, 0.0, 500.0]]])
        cop = np.array([[[np.nan, np.nan, np.nan]], [[0.1, 0.0, 0.0]]])
        force, moment = total_wrench(f, np.zeros_like(f), cop, np.zeros(3))
        assert np.all(np.isfinite(moment))
        assert moment[0, 1] == pytest.approx(-50.0)


class TestOrientReaction:
    def test_action_is_negated(self):
        f = np.array([[0.0, 0.0, -700.0], [1.0, 0.0, -650.0]])
        m = np.ones((2, 3))
        g, n, flipped = orient_reaction(f, m)
        assert flipped and g[0, 2] == 700.0 and n[0, 0] == -1.0

    def test_reaction_is_kept(self):
        f = np.array([[0.0, 0.0, 700.0]])
        assert orient_reaction(f, f)[2] is False

    def test_nobody_on_the_plate(self):
        with pytest.raises(ValueError, match="nobody stood"):
            orient_reaction(np.zeros((5, 3)), np.zeros((5, 3)))
