"""Live per-leg inverse dynamics (issue 21): the node graph with ``inverse_dynamics`` and ``impedance_estimator``
given ``side`` left, on the real bilateral OpenCap drop jump written as contract v2 MCAP.

Real rclpy over loopback DDS (``run_pipeline``, one process): the replay plays the summed plate (the stance
detector's), the left plate, the markers (both legs) and ``/subject``. ``inverse_dynamics`` analyses the left
foot's plate with the left leg's markers and one leg's segments; its published stance must be the offline
per-leg analysis of that leg with the same (measured-marker) kinematics, ``analyze_legs(..., rigid=False)``,
and the controller feed must say ``side: left``.
"""

from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")

from hop_impedance.bilateral import PLATE_TOPICS, save_bilateral  # noqa: E402
from hop_impedance.biomech.per_leg import analyze_legs  # noqa: E402
from hop_impedance.importers.bilateral_import import import_opensim_bilateral  # noqa: E402
from hop_impedance.io.mcap_io import MessageStream  # noqa: E402
from hop_impedance.nodes.common import CONTROLLER_TOPIC, STANCE_KINETICS_TOPIC, stamp_ns  # noqa: E402
from hop_impedance.nodes.inverse_dynamics import stance_from_message  # noqa: E402
from hop_impedance.nodes.runner import PipelineConfig, run_pipeline  # noqa: E402
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC  # noqa: E402

OPENCAP = Path("/work/shared/data_candidates/opencap_dropjump")
TRC, MOT = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
pytestmark = pytest.mark.skipif(not TRC.exists(), reason="shared data set opencap_dropjump not present")


def test_live_left_leg_equals_the_offline_per_leg_analysis(tmp_path):
    bilateral = import_opensim_bilateral(TRC, MOT, mass_kg=60.0)
    path = tmp_path / "dj_v2.mcap"
    save_bilateral(path, bilateral)
    side = "left"
    report = run_pipeline(PipelineConfig(recording=str(path), out_dir=str(tmp_path / "out"), timeout_s=90.0, overrides={
        "replay": {"topics": [FORCE_TOPIC, PLATE_TOPICS[side], MARKER_TOPIC, SUBJECT_TOPIC]},
        "inverse_dynamics": {"side": side},
        "impedance_estimator": {"side": side},
    }))
    assert report.finished
    live = [stance_from_message(m.message) for m in MessageStream(report.output_mcap, topics=[STANCE_KINETICS_TOPIC])]
    offline = analyze_legs(bilateral, rigid=False)[side]
    accepted = [s for s in offline.stances if s.joints is not None]
    assert len(accepted) == 1
    off = accepted[0]
    start_s = bilateral.recording.start_ns * 1e-9
    match = [s for s in live if s.joints is not None and abs(s.touchdown_s - start_s - off.touchdown_s) < 1e-6]
    assert len(match) == 1, [(s.touchdown_s - start_s, s.rejection_reason) for s in live]
    on = match[0]
    assert on.joints.moment_nm.shape == off.joints.moment_nm.shape
    peak = np.max(np.abs(off.joints.moment_nm), axis=0)
    rel = np.max(np.abs(on.joints.moment_nm - off.joints.moment_nm), axis=0) / peak
    print(f"live {side} leg vs offline per-leg (rigid=False): max |difference| / peak {rel} "
          f"(peak {np.round(peak, 1)} N m, {len(off.joints.time_s)} samples)")
    assert np.all(rel < 1e-6)  # measured 1e-9 to 7e-9: the message carries float64 times, same arithmetic
    np.testing.assert_allclose(on.joints.angle_rad, off.joints.angle_rad, atol=1e-9)  # the left leg's markers
    assert np.all(np.isnan([s.hip_residual_rms_nm for s in live]))  # the HAT is not part of one leg
    assert on.peak_grf_n == pytest.approx(off.peak_grf_n, rel=1e-12) and on.peak_grf_n < 1100  # the left plate's, not the sum
    feeds = [m.message for m in MessageStream(report.output_mcap, topics=[CONTROLLER_TOPIC])]
    assert feeds and all(f.side == side for f in feeds)
    assert any(abs(stamp_ns(f.touchdown_stamp) * 1e-9 - on.touchdown_s) < 1e-6 for f in feeds)
