"""C3D import through ezc3d: round trip of a simulated recording, two plates, clear errors."""

from __future__ import annotations

import ezc3d
import numpy as np
import pytest

from hop_impedance.importers import MissingMarkersError, import_c3d, write_c3d
from hop_impedance.importers.c3d_import import MOMENT_UNITS, c3d_session, unit_scale
from hop_impedance.recording import MARKER_NAMES

# ezc3d stores C3D data as float32: ~7 significant digits.
F32 = 1e-6


def _assert_same_signals(back, rec, force_atol=1e-3, marker_atol=1e-6):
    np.testing.assert_array_equal(back.force.stamp_ns, rec.force.stamp_ns)
    np.testing.assert_array_equal(back.markers.stamp_ns, rec.markers.stamp_ns)
    np.testing.assert_allclose(back.force.force_n, rec.force.force_n, atol=force_atol)
    np.testing.assert_allclose(back.force.torque_nm, rec.force.torque_nm, atol=force_atol)
    np.testing.assert_array_equal(np.isnan(back.markers.positions_m), np.isnan(rec.markers.positions_m))
    np.testing.assert_allclose(back.markers.positions_m, rec.markers.positions_m, atol=marker_atol)


class TestRoundTrip:
    @pytest.mark.parametrize("up, forward", [("+Z", "-Y"), ("+Y", "+X"), ("+Z", "+X")])
    def test_same_signals_with_stated_axes(self, hopping, tmp_path, up, forward):
        path = write_c3d(hopping, tmp_path / "s.c3d", lab_up=up, lab_forward=forward)
        back = import_c3d(path, "contract", forward=forward)
        _assert_same_signals(back, hopping)
        assert back.subject == hopping.subject  # mass and height from PROCESSING (height in mm)
        assert any("force on the plate" in w for w in back.warnings)  # Vicon-style action channels

    def test_heading_and_up_detected(self, hopping, tmp_path):
        # Lab z up (POINT:Y_SCREEN) and the subject facing lab -Y: nothing stated on import.
        path = write_c3d(hopping, tmp_path / "s.c3d", lab_up="+Z", lab_forward="-Y")
        back = import_c3d(path, "contract")
        # Heading from heel->toe with 0.5 mm marker noise: within 0.05 degrees,
        # so 2 m from the origin positions agree within 2 mm.
        _assert_same_signals(back, hopping, force_atol=2.0, marker_atol=2e-3)
        np.testing.assert_allclose(back.force.cop_x_m(), hopping.force.cop_x_m(), atol=1e-3)

    def test_up_detected_from_markers_without_y_screen(self, hopping, tmp_path):
        path = write_c3d(hopping, tmp_path / "s.c3d", lab_up="-X", lab_forward="+Z")
        c = ezc3d.c3d(str(path))
        del c["parameters"]["POINT"]["Y_SCREEN"]
        c.write(str(tmp_path / "noscreen.c3d"))
        back = import_c3d(tmp_path / "noscreen.c3d", "contract", forward="+Z")
        _assert_same_signals(back, hopping)
        assert any("detected from the toe->head" in w for w in back.warnings)

    def test_lab_labels_through_plugin_gait_mapping(self, hopping, tmp_path):
        labels = ("Anna:RTOE", "Anna:RHEE", "Anna:RANK", "Anna:RKNE", "Anna:RGT", "Anna:RFHD")
        path = write_c3d(hopping, tmp_path / "s.c3d", labels=labels)
        back = import_c3d(path, forward="+Y")  # mapping chosen automatically
        # Plug-in Gait's toe and heel markers sit on the shoe: the map lowers
        # them to the sole by their height in flat stance (5th percentile of z).
        expected = hopping.markers.positions_m.copy()
        for name in ("toe", "heel"):
            k = MARKER_NAMES.index(name)
            expected[:, k, 2] -= np.nanpercentile(expected[:, k, 2], 5)
        np.testing.assert_allclose(back.markers.positions_m, expected, atol=1e-6)
        assert any("toe <- Anna:RTOE" in w for w in back.warnings)
        assert any("toe lowered by 19." in w for w in back.warnings)  # base 20 mm minus noise


def _two_plate_c3d(path, fz=(400.0, 600.0), cop_local_mm=((30.0, 10.0), (-20.0, -5.0))):
    """Two type-2 plates, z-up lab, plate frames = lab frame, pure vertical loads (reaction sign)."""
    c = ezc3d.c3d()
    n_frames, ratio = 5, 4
    p = c["parameters"]
    p["POINT"]["RATE"]["value"] = [100.0]
    p["POINT"]["LABELS"]["value"] = list(MARKER_NAMES)
    p["POINT"]["UNITS"]["value"] = ["mm"]
    base = np.array([[1100, 250, 20], [900, 250, 30], [960, 250, 90], [1000, 250, 500], [980, 250, 920], [950, 250, 1620]], float)
    pts = np.ones((4, 6, n_frames))
    pts[:3] = base.T[:, :, None]
    c["data"]["points"] = pts
    p["ANALOG"]["RATE"]["value"] = [400.0]
    p["ANALOG"]["LABELS"]["value"] = [f"{a}{k}" for k in (1, 2) for a in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
    p["ANALOG"]["UNITS"]["value"] = (["N"] * 3 + ["Nmm"] * 3) * 2
    analogs = np.zeros((1, 12, n_frames * ratio))
    centres = np.array([[1000.0, 150.0, 0.0], [1000.0, 650.0, 0.0]])
    corners = []
    for k in range(2):
        x, y = cop_local_mm[k]
        analogs[0, 6 * k + 2] = fz[k]
        analogs[0, 6 * k + 3] = y * fz[k]  # Mx = y Fz
        analogs[0, 6 * k + 4] = -x * fz[k]  # My = -x Fz
        c0 = centres[k]
        corners.append(np.column_stack([c0 + [300, 200, 0], c0 + [-300, 200, 0], c0 + [-300, -200, 0], c0 + [300, -200, 0]]))
    c["data"]["analogs"] = analogs
    fp = p["FORCE_PLATFORM"]
    fp["USED"]["value"] = np.array([2])
    fp["TYPE"]["value"] = np.array([2, 2])
    fp["CORNERS"]["value"] = np.stack(corners, axis=2)
    fp["ORIGIN"]["value"] = np.zeros((3, 2))
    fp["CHANNEL"]["value"] = np.arange(1, 13).reshape(2, 6).T
    c.add_parameter("POINT", "Y_SCREEN", ["+Z"])
    c.write(str(path))
    return centres / 1000.0


class TestTwoPlates:
    def test_forces_sum_and_cop_combines(self, tmp_path):
        centres = _two_plate_c3d(tmp_path / "two.c3d")
        rec = import_c3d(tmp_path / "two.c3d", "contract", forward="+X", mass_kg=70, height_m=1.7)
        np.testing.assert_allclose(rec.force.force_n[:, 2], 1000.0, rtol=F32)
        # Origin = first plate's centre; plate 2 sits at the same x, COPs at +30 mm and -20 mm.
        expected = (0.030 * 400 + (centres[1, 0] - centres[0, 0] - 0.020) * 600) / 1000
        np.testing.assert_allclose(rec.force.cop_x_m(), expected, atol=1e-6)
        # Markers are shifted by the same origin: the toe at lab x = 1.1 m is 0.1 m ahead of plate 1.
        np.testing.assert_allclose(rec.markers.marker("toe")[:, 0], 0.1, atol=1e-6)

    def test_one_plate_selected(self, tmp_path):
        _two_plate_c3d(tmp_path / "two.c3d")
        rec = import_c3d(tmp_path / "two.c3d", "contract", forward="+X", mass_kg=70, height_m=1.7, plates=[1])
        np.testing.assert_allclose(rec.force.force_n[:, 2], 600.0, rtol=F32)
        with pytest.raises(ValueError, match="do not exist"):
            import_c3d(tmp_path / "two.c3d", "contract", forward="+X", mass_kg=70, height_m=1.7, plates=[2])


class TestErrors:
    def test_missing_markers_are_named(self, hopping, tmp_path):
        labels = ("RTOE", "RHEE", "RANK", "RKNE", "LASI", "LFHD")
        path = write_c3d(hopping, tmp_path / "s.c3d", labels=labels)
        # The hip's regression names what it lacks (one ASIS, the PSIS pair or the sacrum).
        with pytest.raises(
            MissingMarkersError,
            match=r"missing markers: hip \(tried RGT, RHJC, RFEP, RHJC_davis; RHJC_davis needs rasi \(RASI\), "
            r"rpsi \(RPSI\) \+ lpsi \(LPSI\) or sacrum \(SACR\)\); head",
        ):
            import_c3d(path, "plugin_gait_right")

    def test_no_force_plate(self, hopping, tmp_path):
        path = write_c3d(hopping, tmp_path / "s.c3d")
        c = ezc3d.c3d(str(path))
        c["parameters"]["FORCE_PLATFORM"]["USED"]["value"] = np.array([0])
        c["parameters"]["FORCE_PLATFORM"]["TYPE"]["value"] = np.array([], dtype=int)
        c.write(str(tmp_path / "noplate.c3d"))
        with pytest.raises(ValueError, match="no force plate found"):
            c3d_session(tmp_path / "noplate.c3d")

    def test_mass_unknown(self, hopping, tmp_path):
        path = write_c3d(hopping, tmp_path / "s.c3d")
        c = ezc3d.c3d(str(path))
        del c["parameters"]["PROCESSING"]
        c.write(str(tmp_path / "nomass.c3d"))
        with pytest.raises(ValueError, match="body mass unknown.*--mass-kg"):
            import_c3d(tmp_path / "nomass.c3d", "contract")
        # quiet standing is absent in a hopping trial: auto estimation says so
        with pytest.raises(ValueError, match="no 1 s of quiet standing"):
            import_c3d(tmp_path / "nomass.c3d", "contract", mass_kg="auto")

    def test_not_a_c3d(self, tmp_path):
        bad = tmp_path / "bad.c3d"
        bad.write_bytes(b"this is not a c3d file" * 30)
        with pytest.raises(ValueError, match="ezc3d cannot read it"):
            c3d_session(bad)

    def test_unknown_unit(self):
        assert unit_scale("N.mm", MOMENT_UNITS, "moment") == 1e-3
        with pytest.raises(ValueError, match="unknown moment unit 'lbf.in'"):
            unit_scale("lbf.in", MOMENT_UNITS, "moment")
