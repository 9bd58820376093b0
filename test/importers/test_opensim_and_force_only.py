"""OpenSim TRC/MOT and force-only imports on the real shared data sets."""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.stance_detection import detect_stances
from hop_impedance.importers import FORCE_ONLY_LIMITS, MissingMarkersError, import_force_only, import_opensim
from hop_impedance.importers.force_only_import import read_force_text
from hop_impedance.importers.marker_mapping import choose_mapping, load_marker_mapping, mapping_from_dict, resolve_labels
from hop_impedance.importers.opensim_import import read_mot, read_trc
from hop_impedance.recording import GRAVITY_M_S2

from .conftest import CMJ, OPENCAP

TRC = OPENCAP / "Subject4_DJ1_markers_trc.txt"
MOT = OPENCAP / "Subject4_DJ1_grf_mot.txt"
pytestmark = pytest.mark.skipif(not TRC.exists(), reason="shared data set opencap_dropjump not present")


@pytest.fixture(scope="module")
def dj1():
    return import_opensim(TRC, MOT, "opencap_right", mass_kg=60.0)


class TestReadTrc:
    def test_real_file(self):
        trc = read_trc(TRC)
        assert trc.rate_hz == 100 and trc.positions_m.shape == (269, 51, 3)
        assert "R_HJC" in trc.labels and "r_5meta" in trc.labels
        # Gaps ('nan' or empty cells) are NaN: count them in the raw text independently.
        raw = [ln.split("\t") for ln in TRC.read_text().splitlines()[5:] if ln.strip()]
        col = 2 + 3 * trc.labels.index("r_5meta")
        empty = sum(1 for r in raw if len(r) <= col or r[col].strip().lower() in ("", "nan"))
        assert empty > 0 and np.isnan(trc.positions_m[:, trc.labels.index("r_5meta"), 0]).sum() == empty

    def test_mm_units_and_rate_mismatch(self, tmp_path):
        head = "PathFileType\t4\t(X/Y/Z)\tx.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n{rate}\t100\t3\t1\tmm\n"
        body = "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n\n1\t0\t1000\t2000\t\n2\t0.01\t1000\t2000\t3000\n3\t0.02\t1\t2\t3\n"
        (tmp_path / "a.trc").write_text(head.format(rate=100) + body)
        trc = read_trc(tmp_path / "a.trc")
        np.testing.assert_allclose(trc.positions_m[1, 0], [1.0, 2.0, 3.0])
        assert np.isnan(trc.positions_m[0, 0, 2])
        (tmp_path / "b.trc").write_text(head.format(rate=120) + body)
        with pytest.raises(ValueError, match="inconsistent rates: header DataRate 120 Hz"):
            read_trc(tmp_path / "b.trc")


class TestMarkerMapping:
    def test_opencap_right_labels(self):
        labels = read_trc(TRC).labels
        idx = resolve_labels(labels, load_marker_mapping("opencap_right"))
        assert [labels[idx[m]] for m in ("toe", "heel", "ankle", "knee", "hip", "head")] == [
            "r_5meta", "r_calc", "r_ankle", "r_knee", "R_HJC", "R_Shoulder"
        ]
        assert choose_mapping(labels).name == "opencap_right"
        left = resolve_labels(labels, load_marker_mapping("opencap_left"))
        assert labels[left["hip"]] == "L_HJC"

    def test_missing_named_with_near_labels(self):
        labels = ("r_5meta", "r_calc", "r_ankle", "r_knee", "R_HJC_reg2", "C7")
        with pytest.raises(MissingMarkersError, match=r"hip \(tried R_HJC, RHJC, R_HJC_reg; closest in file: R_HJC_reg2\); head"):
            resolve_labels(labels, load_marker_mapping("opencap_right"))

    def test_yaml_must_name_all_six(self):
        with pytest.raises(ValueError, match="missing head"):
            mapping_from_dict({"markers": {m: m for m in ("toe", "heel", "ankle", "knee", "hip")}})

    def test_unknown_name(self):
        with pytest.raises(ValueError, match="unknown marker mapping 'vicon'; shipped ones: contract, opencap_left"):
            load_marker_mapping("vicon")


class TestDropJumpImport:
    def test_forces_are_the_plates_sum(self, dj1):
        mot = read_mot(MOT)
        vy = mot.column("ground_force_1_vy") + mot.column("ground_force_2_vy") + mot.column("ground_force_3_vy")
        np.testing.assert_allclose(dj1.force.force_n[:, 2], vy)
        # Braking at touchdown: the subject moves forward, the ground pushes back.
        first = int(np.argmax(dj1.force.force_n[:, 2] > 20))
        assert dj1.force.force_n[first, 0] < -100

    def test_frame_is_contract(self, dj1):
        m = dj1.markers
        landed = slice(160, 200)  # 1.6-2.0 s, both feet on the plates
        assert np.nanmedian(m.marker("toe")[landed, 2]) == pytest.approx(0.04, abs=0.02)  # on the ground (z up)
        assert np.nanmedian(m.marker("toe")[landed, 0] - m.marker("heel")[landed, 0]) > 0.12  # faces +x
        assert np.nanmedian(m.marker("head")[:, 2] - m.marker("hip")[:, 2]) > 0.4
        # y points to the subject's left: the left leg's ankle has the larger y.
        left = import_opensim(TRC, MOT, "opencap_left", mass_kg=60.0).markers
        assert np.median(left.marker("ankle")[landed, 1] - m.marker("ankle")[landed, 1]) > 0.2
        # Combined COP (both plates, contract formula) between the heel and ~toe tips while loaded:
        # the mapped 'toe' is the 5th metatarsal head, 5-10 cm behind the tips, and the left foot
        # stands ~4 cm further forward than the right.
        cop = dj1.force.cop_x_m(min_fz_n=200)
        ok = np.isfinite(cop)
        heel_x, toe_x = np.nanmin(m.marker("heel")[ok, 0]), np.nanmax(m.marker("toe")[ok, 0])
        assert ok.sum() > 50
        assert np.all((cop[ok] > heel_x) & (cop[ok] < toe_x + 0.15))

    def test_impulse_matches_pelvis_velocity_change(self, dj1):
        # Momentum balance over the first contact: int(Fz - mg) dt / m = change of vertical velocity,
        # which the pelvis markers (mid ASIS/PSIS, close to the COM) give independently.
        trc = read_trc(TRC)
        t = dj1.force.stamp_ns / 1e9
        stance = detect_stances(t, dj1.force.force_n[:, 2])[0]
        seg = (t >= stance.touchdown_s) & (t <= stance.takeoff_s)
        dv_force = np.trapezoid(dj1.force.force_n[seg, 2] - 60.0 * GRAVITY_M_S2, t[seg]) / 60.0
        pelvis = np.mean([trc.positions_m[:, trc.labels.index(n), 1] for n in ("r.ASIS", "L.ASIS", "r.PSIS", "L.PSIS")], axis=0)
        v = np.gradient(pelvis, trc.time_s)
        dv_markers = np.interp(stance.takeoff_s, trc.time_s, v) - np.interp(stance.touchdown_s, trc.time_s, v)
        assert dv_force == pytest.approx(dv_markers, rel=0.15)
        assert dv_markers > 4.0  # from falling (~-2.5 m/s) to rising (~+2 m/s)

    def test_contacts_match_source(self, dj1):
        t = dj1.force.stamp_ns / 1e9
        st = detect_stances(t, dj1.force.force_n[:, 2])
        # SOURCE.txt: vertical-force edges (> 20 N) at 1.42 / 2.17 / 2.57 s (100 Hz data).
        assert [round(s.touchdown_s, 1) for s in st] == [1.4, 2.6]
        assert st[0].takeoff_s == pytest.approx(2.17, abs=0.015)
        assert st[1].rejection_reason.startswith("incomplete")

    def test_height_estimated_and_said(self, dj1):
        assert 1.55 < dj1.subject.body_height_m < 1.75
        assert any("height" in w and "estimated" in w for w in dj1.warnings)

    def test_mass_required(self):
        with pytest.raises(ValueError, match="body mass unknown"):
            import_opensim(TRC, MOT)

    def test_static_trial_mass_auto(self):
        rec = import_opensim(None, OPENCAP / "Subject4_static1_grf_mot.txt", mass_kg="auto", height_m=1.65)
        # SOURCE.txt: 60.0 kg = mean vertical GRF of static1 / 9.81.
        assert rec.subject.body_mass_kg == pytest.approx(60.0, abs=0.3)
        assert rec.markers is None

    def test_wrong_mapping_names_the_markers(self):
        with pytest.raises(MissingMarkersError, match="plugin_gait_right.*toe \\(tried RMT5, RTOE\\)"):
            import_opensim(TRC, MOT, "plugin_gait_right", mass_kg=60)


@pytest.mark.skipif(not CMJ.exists(), reason="shared data set bmc_cmj_grf not present")
class TestForceOnly:
    @pytest.fixture(scope="class")
    @classmethod
    def jump(cls):
        return import_force_only(CMJ)

    def test_mass_and_limits(self, jump):
        # SOURCE.txt: quiet stance ~692 N => ~70.5 kg.
        assert jump.subject.body_mass_kg == pytest.approx(692 / GRAVITY_M_S2, rel=0.01)
        assert jump.markers is None and jump.warnings[0] == FORCE_ONLY_LIMITS
        assert "joint moments" in FORCE_ONLY_LIMITS and "impedance" in FORCE_ONLY_LIMITS
        assert np.all(jump.force.torque_nm == 0) and np.all(np.isnan(jump.force.cop_x_m()) | (jump.force.cop_x_m() == 0))

    def test_stances_and_jump_height(self, jump):
        t = jump.force.stamp_ns / 1e9
        fz = jump.force.force_n[:, 2]
        st = detect_stances(t, fz)
        # SOURCE.txt: steps on 1.32 s, take-off 5.09 s, landing 5.64 s, steps off ~9.42 s.
        assert [s.touchdown_s for s in st] == pytest.approx([1.32, 5.64], abs=0.01)
        assert [s.takeoff_s for s in st] == pytest.approx([5.09, 9.42], abs=0.01)
        flight = st[1].touchdown_s - st[0].takeoff_s
        h_flight = GRAVITY_M_S2 * flight**2 / 8
        # Impulse-momentum from quiet standing (v = 0) to take-off, independent of the flight time.
        m = jump.subject.body_mass_kg
        seg = (t > 2.5) & (t <= st[0].takeoff_s)
        v_to = np.trapezoid(fz[seg] - m * GRAVITY_M_S2, t[seg]) / m
        h_impulse = v_to**2 / (2 * GRAVITY_M_S2)
        assert h_flight == pytest.approx(0.371, abs=0.01)
        assert h_impulse == pytest.approx(h_flight, rel=0.10)

    def test_bad_inputs(self, tmp_path):
        (tmp_path / "one.txt").write_text("700\n701\n702\n")
        with pytest.raises(ValueError, match="give the sampling rate"):
            read_force_text(tmp_path / "one.txt")
        t, f = read_force_text(tmp_path / "one.txt", rate_hz=500)
        np.testing.assert_allclose(t, [0, 0.002, 0.004])
        (tmp_path / "nan.txt").write_text("t f\n0 1\n0.1 nan\n0.2 3\n")
        with pytest.raises(ValueError, match="1 row\\(s\\) hold NaN"):
            read_force_text(tmp_path / "nan.txt")
        (tmp_path / "jit.txt").write_text("0 1\n0.1 1\n0.25 1\n0.3 1\n")
        with pytest.raises(ValueError, match="inconsistent sampling rate"):
            read_force_text(tmp_path / "jit.txt")

    def test_plate_sign_is_fixed(self, tmp_path):
        rows = "\n".join(f"{k / 100:.2f} {-700.0 + (k % 3)}" for k in range(300))
        (tmp_path / "neg.txt").write_text(rows)
        rec = import_force_only(tmp_path / "neg.txt", height_m=1.7)
        assert rec.force.force_n[0, 2] == pytest.approx(700.0)
        assert rec.subject.body_mass_kg == pytest.approx(699 / GRAVITY_M_S2, rel=1e-3)
        assert any("negated" in w for w in rec.warnings)
