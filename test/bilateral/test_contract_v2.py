"""Contract v2 (docs/contract_v2.md): both plates and both legs from the real OpenCap drop jump, MCAP round trip,
v1 compatibility."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hop_impedance.bilateral import PLATE_TOPICS, V2_MARKER_NAMES, BilateralRecording, load_bilateral, save_bilateral
from hop_impedance.importers import import_opensim
from hop_impedance.importers.bilateral_import import import_opensim_bilateral
from hop_impedance.io.mcap_io import summarize
from hop_impedance.io.recording_io import load_recording, save_recording
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
TRC, MOT = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
pytestmark = pytest.mark.skipif(not TRC.exists(), reason="shared data set opencap_dropjump not present")


@pytest.fixture(scope="module")
def bilateral() -> BilateralRecording:
    return import_opensim_bilateral(TRC, MOT, mass_kg=60.0)


def test_v1_view_is_the_v1_import_unchanged(bilateral):
    v1 = import_opensim(TRC, MOT, "opencap_right", mass_kg=60.0)
    np.testing.assert_array_equal(bilateral.recording.force.force_n, v1.force.force_n)
    np.testing.assert_array_equal(bilateral.recording.force.torque_nm, v1.force.torque_nm)
    np.testing.assert_array_equal(bilateral.recording.markers.positions_m, v1.markers.positions_m)
    assert bilateral.recording.subject == v1.subject


def test_plates_sum_to_the_summed_plate_and_go_to_the_nearest_foot(bilateral):
    """The MOT's plate 1 is under the right foot, plate 2 under the left (plate 3 is all zeros)."""
    assert bilateral.is_bilateral
    assert bilateral.summed_plate_mismatch_n() < 1e-9
    torque = sum(p.torque_nm for p in bilateral.plates.values())
    np.testing.assert_allclose(torque, bilateral.recording.force.torque_nm, atol=1e-9)
    assert any("ground_force_1 -> right foot" in w for w in bilateral.recording.warnings)
    assert any("ground_force_2 -> left foot" in w for w in bilateral.recording.warnings)
    # each plate's centre of pressure lies under its own foot: in front of that leg's heel, at most to its toe tips,
    # in x, at its ankle in y
    for side in ("left", "right"):
        p, mk = bilateral.plates[side], bilateral.markers(side)
        loaded = p.force_n[:, 2] > 300
        t = (p.stamp_ns[loaded] - mk.stamp_ns[0]) * 1e-9
        cop_x = -p.torque_nm[loaded, 1] / p.force_n[loaded, 2]
        cop_y = p.torque_nm[loaded, 0] / p.force_n[loaded, 2]
        mt = (mk.stamp_ns - mk.stamp_ns[0]) * 1e-9
        heel_x, toe_x = np.interp(t, mt, mk.marker("heel")[:, 0]), np.interp(t, mt, mk.marker("toe")[:, 0])
        ankle_y = np.interp(t, mt, mk.marker("ankle")[:, 1])
        assert np.median(np.abs(cop_y - ankle_y)) < 0.05
        # contract toe = 5th metatarsal head; the toe tips are ~8 cm further forward
        assert np.all((cop_x > heel_x + 0.05) & (cop_x < toe_x + 0.08))
    # the left and right legs are different markers, the head is shared
    assert np.nanmedian(bilateral.markers("left").marker("ankle")[:, 1] - bilateral.markers("right").marker("ankle")[:, 1]) > 0.2
    np.testing.assert_array_equal(bilateral.markers("left").marker("head"), bilateral.markers("right").marker("head"))


def test_mcap_round_trip_and_v1_reader(bilateral, tmp_path):
    path = tmp_path / "dj_v2.mcap"
    save_bilateral(path, bilateral)
    topics = {t.topic: t.count for t in summarize(path)}
    n = len(bilateral.recording.force)
    assert topics[FORCE_TOPIC] == n and topics[PLATE_TOPICS["left"]] == n and topics[PLATE_TOPICS["right"]] == n
    assert topics[MARKER_TOPIC] == len(bilateral.recording.markers)

    back = load_bilateral(path)
    assert back.is_bilateral
    for side in ("left", "right"):
        np.testing.assert_allclose(back.plates[side].force_n, bilateral.plates[side].force_n, atol=1e-9)
        np.testing.assert_allclose(back.plates[side].torque_nm, bilateral.plates[side].torque_nm, atol=1e-9)
        np.testing.assert_allclose(back.markers(side).positions_m, bilateral.markers(side).positions_m,
                                   atol=1e-12, equal_nan=True)
        np.testing.assert_array_equal(back.plates[side].stamp_ns, bilateral.recording.force.stamp_ns)

    v1 = load_recording(path)  # a v1 reader sees the v1 recording: summed plate, right leg under the v1 names
    np.testing.assert_allclose(v1.force.force_n, bilateral.recording.force.force_n, atol=1e-9)
    np.testing.assert_allclose(v1.markers.positions_m, bilateral.recording.markers.positions_m, atol=1e-12, equal_nan=True)
    assert len(V2_MARKER_NAMES) == 11


def test_v1_file_reads_as_lumped_only(bilateral, tmp_path):
    path = tmp_path / "dj_v1.mcap"
    save_recording(path, bilateral.recording)
    back = load_bilateral(path)
    assert not back.is_bilateral and back.plates == {} and back.left_markers is None
    with pytest.raises(ValueError, match="no /force_plate/left/wrench data"):
        back.leg("left")


def test_per_plate_stamps_that_differ_from_the_summed_plate_are_refused(bilateral, tmp_path):
    """A v2 file whose left-plate topic lost samples: the reader names the topic instead of misaligning the legs."""
    from dataclasses import replace

    from hop_impedance.recording import ForcePlateSeries

    left = bilateral.plates["left"]
    short = ForcePlateSeries(left.stamp_ns[:-5], left.force_n[:-5], left.torque_nm[:-5])
    path = tmp_path / "lost.mcap"
    save_bilateral(path, replace(bilateral, plates={**bilateral.plates, "left": short}))
    with pytest.raises(ValueError, match="/force_plate/left/wrench stamps differ from /force_plate/wrench"):
        load_bilateral(path)
