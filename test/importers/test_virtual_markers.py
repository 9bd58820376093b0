"""Virtual markers: the published regressions against hand-derived numbers, rigid-motion invariance, maps."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.importers.marker_mapping import (
    MissingMarkersError,
    mapping_from_dict,
    resolve_labels,
    source_notes,
    with_virtual_markers,
)
from hop_impedance.importers.virtual_markers import hat_top_from_c7, hjc_davis1991, hjc_harrington2007

# A pelvis in its own frame (x anterior, y left, z up, origin mid-ASIS, metres):
# pelvis width PW = 250 mm, pelvis depth PD = 160 mm.
RASI = np.array([0.0, -0.125, 0.0])
LASI = np.array([0.0, 0.125, 0.0])
RPSI = np.array([-0.16, -0.045, 0.0])
LPSI = np.array([-0.16, 0.045, 0.0])

# Harrington et al. (2007) by hand, mm: x = -0.24*160 - 9.9 = -48.3,
# superior = -0.30*250 - 10.9 = -85.9, lateral = 0.33*250 + 7.3 = 89.8.
HARRINGTON_RIGHT = np.array([-0.0483, -0.0898, -0.0859])
# Davis et al. (1991) by hand for leg length 900 mm, marker radius 7 mm:
# C = 0.115*900 - 15.3 = 88.2, x_dis = 0.1288*900 - 48.56 = 67.36,
# x = C cos28.4 sin18 - (x_dis + 7) cos18 = -46.7455,
# y = -(125 - C sin28.4) = -83.0499, z = -C cos28.4 cos18 - (x_dis + 7) sin18 = -96.7662.
DAVIS_RIGHT = np.array([-0.0467455, -0.0830499, -0.0967662])


def _mirror(p):
    return p * np.array([1.0, -1.0, 1.0])


def _rigid(seed):
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    rot = q * np.sign(np.linalg.det(q))  # proper rotation
    return rot, rng.normal(0, 2.0, 3)


def _frames(*points, n=4):
    return [np.repeat(p[None], n, axis=0) for p in points]


class TestHipJointCentre:
    @pytest.mark.parametrize("side, sign", [("right", 1), ("left", -1)])
    def test_harrington_in_pelvis_frame(self, side, sign):
        hjc = hjc_harrington2007(*_frames(RASI, LASI, 0.5 * (RPSI + LPSI)), side)
        expected = HARRINGTON_RIGHT if sign > 0 else _mirror(HARRINGTON_RIGHT)
        np.testing.assert_allclose(hjc, np.repeat(expected[None], 4, axis=0), atol=1e-9)

    @pytest.mark.parametrize("side, sign", [("right", 1), ("left", -1)])
    def test_davis_in_pelvis_frame(self, side, sign):
        hjc = hjc_davis1991(*_frames(RASI, LASI, 0.5 * (RPSI + LPSI)), side, leg_length_m=0.9, marker_radius_m=0.007)
        expected = DAVIS_RIGHT if sign > 0 else _mirror(DAVIS_RIGHT)
        np.testing.assert_allclose(hjc, np.repeat(expected[None], 4, axis=0), atol=1e-7)

    def test_davis_given_distances_override_the_markers(self):
        # Measured inter-ASIS 0.30 m and ASIS-trochanter 0.08 m replace the marker
        # distance and the leg-length rule: y = -(150 - 41.950) mm, x = 23.9751 - 87 cos18 mm.
        hjc = hjc_davis1991(
            *_frames(RASI, LASI, 0.5 * (RPSI + LPSI), n=1), "right", 0.9, 0.007, asis_trochanter_m=0.08, inter_asis_m=0.30
        )
        np.testing.assert_allclose(hjc[0, :2], [(23.9751 - 87.0 * 0.9510565) * 1e-3, -(150.0 - 41.9500) * 1e-3], atol=1e-7)

    @pytest.mark.parametrize("seed", [0, 1, 2])
    def test_invariant_under_rigid_motion_of_the_lab(self, seed):
        rot, shift = _rigid(seed)
        moved = [p @ rot.T + shift for p in (RASI, LASI, RPSI, LPSI)]
        ra, la, rp, lp = _frames(*moved)
        mid = 0.5 * (rp + lp)
        np.testing.assert_allclose(hjc_harrington2007(ra, la, mid, "right")[0], HARRINGTON_RIGHT @ rot.T + shift, atol=1e-9)
        np.testing.assert_allclose(hjc_davis1991(ra, la, mid, "left", 0.9)[0], _mirror(DAVIS_RIGHT) @ rot.T + shift, atol=1e-7)

    def test_occluded_frame_is_nan_and_others_unchanged(self):
        ra, la, mid = _frames(RASI, LASI, 0.5 * (RPSI + LPSI))
        ra[2] = np.nan
        hjc = hjc_harrington2007(ra, la, mid, "right")
        assert np.isnan(hjc[2]).all()
        np.testing.assert_allclose(hjc[[0, 1, 3]], np.repeat(HARRINGTON_RIGHT[None], 3, axis=0), atol=1e-9)

    def test_implausible_leg_length_is_refused(self):
        with pytest.raises(ValueError, match="leg length 900 m is implausible"):
            hjc_davis1991(*_frames(RASI, LASI, RPSI), "right", leg_length_m=900.0)


def test_hat_top_from_c7_follows_de_leva():
    # Female de Leva: head 0.2437, trunk 0.6148 of stature; head marker 0.33 head
    # lengths below the vertex: C7 + 0.67 * 0.2437 / 0.6148 * (C7 - mid-hip).
    c7, hip = _frames(np.array([0.0, 0.0, 1.4]), np.array([0.0, 0.0, 0.9]), n=1)
    np.testing.assert_allclose(hat_top_from_c7(c7, hip)[0], [0.0, 0.0, 1.53279034], atol=1e-8)


PELVIS_MAP = {
    "name": "test_pelvis",
    "virtual_markers": {
        "RHJC_h": {"method": "harrington2007", "side": "right", "inputs": {"rasi": "RASI", "lasi": "LASI", "sacrum": "SACR"}},
        "HEAD": {"method": "mean", "inputs": {"points": ["RFHD", "RBHD"]}},
    },
    "markers": {"toe": "RTOE", "heel": "RHEE", "ankle": "RANK", "knee": "RKNE", "hip": ["RGT", "RHJC_h"], "head": "HEAD"},
}


class TestMaps:
    def _session(self):
        labels = ["RTOE", "RHEE", "RANK", "RKNE", "RASI", "LASI", "SACR", "RFHD", "RBHD"]
        pos = np.zeros((3, len(labels), 3))
        pos[:, 4], pos[:, 5], pos[:, 6] = RASI, LASI, 0.5 * (RPSI + LPSI)
        pos[:, 7], pos[:, 8] = [0.1, -0.08, 1.6], [-0.1, -0.06, 1.62]
        return labels, pos

    def test_virtual_markers_feed_the_contract_and_are_noted(self):
        mapping = mapping_from_dict(PELVIS_MAP)
        labels, pos = self._session()
        all_labels, all_pos, notes = with_virtual_markers(labels, pos, mapping)
        idx = resolve_labels(all_labels, mapping)
        np.testing.assert_allclose(all_pos[:, idx["hip"]], np.repeat(HARRINGTON_RIGHT[None], 3, axis=0), atol=1e-9)
        np.testing.assert_allclose(all_pos[:, idx["head"]], np.repeat([[0.0, -0.07, 1.61]], 3, axis=0), atol=1e-12)
        lines = source_notes(all_labels, mapping, notes)
        assert ("hip <- RHJC_h = hip joint centre, Harrington et al. 2007 (J Biomech 40:595), right, "
                "from RASI, LASI, SACR") in lines
        assert "toe <- RTOE" in lines

    def test_a_marked_trochanter_wins_over_the_regression(self):
        labels, pos = self._session()
        all_labels, _, _ = with_virtual_markers(labels + ["RGT"], np.concatenate([pos, pos[:, :1]], axis=1),
                                                mapping_from_dict(PELVIS_MAP))
        assert all_labels[resolve_labels(all_labels, mapping_from_dict(PELVIS_MAP))["hip"]] == "RGT"

    def test_missing_input_is_named(self):
        labels, _ = self._session()
        with pytest.raises(MissingMarkersError, match=r"RHJC_h needs sacrum \(SACR\)"):
            resolve_labels([x for x in labels if x != "SACR"], mapping_from_dict(PELVIS_MAP))

    @pytest.mark.parametrize(
        "entry, message",
        [
            ({"method": "bell1990", "inputs": {}}, "needs a 'method', one of harrington2007"),
            ({"method": "harrington2007", "side": "right", "inputs": {"rasi": "A", "lasi": "B"}}, "takes inputs"),
            ({"method": "harrington2007", "side": "up", "inputs": {"rasi": "A", "lasi": "B", "sacrum": "S"}}, "side must be"),
            ({"method": "davis1991", "side": "right", "inputs": {"rasi": "A", "lasi": "B", "sacrum": "S"}}, "needs leg_length_m"),
        ],
    )
    def test_malformed_definitions_are_refused(self, entry, message):
        doc = dict(PELVIS_MAP, virtual_markers={"X": entry})
        with pytest.raises(ValueError, match=message):
            mapping_from_dict(doc)


def test_an_unused_rule_that_cannot_be_built_does_not_stop_the_import():
    doc = dict(
        PELVIS_MAP,
        virtual_markers={
            "RHJC_d": {
                "method": "davis1991",
                "side": "right",
                "inputs": {"rasi": "RASI", "lasi": "LASI", "sacrum": "SACR"},
                "leg_length_parameter": "RLegLength",
            },
            "HEAD": PELVIS_MAP["virtual_markers"]["HEAD"],
        },
    )
    doc["markers"] = dict(PELVIS_MAP["markers"], hip=["RGT", "RHJC_d"])
    mapping = mapping_from_dict(doc)
    labels, pos = TestMaps()._session()
    with_trochanter = with_virtual_markers(labels + ["RGT"], np.concatenate([pos, pos[:, :1]], axis=1), mapping)
    assert "RHJC_d" not in with_trochanter[0]  # not needed: not built
    with pytest.raises(ValueError, match="RHJC_d' \\(davis1991\\): no leg length"):
        with_virtual_markers(labels, pos, mapping)  # needed, and the file has no RLegLength
