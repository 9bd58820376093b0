"""One detector (issue 15): a detection setting given once moves the published events and the analysed stances together.

The pipeline runs with a ROS parameter file that sets the take-off and
touchdown levels to 150 / 300 N (instead of ~16 / 32 N for this subject);
``analyze --detector`` gets the same two settings. Touchdowns of
``/stance/events``, of ``/stance/kinetics`` (the stances inverse dynamics
analysed) and of the offline analysis agree to 1 us, and all are later than
with the default levels by more than 0.3 ms (so the setting reached each of them).
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytest.importorskip("rclpy")

from hop_impedance_msgs.msg import StanceEvent  # noqa: E402

from hop_impedance.biomech.stance_detection import DetectorOptions  # noqa: E402
from hop_impedance.io.mcap_io import MessageStream  # noqa: E402
from hop_impedance.nodes.common import EVENTS_TOPIC, STANCE_KINETICS_TOPIC, stamp_ns  # noqa: E402
from hop_impedance.nodes.runner import PipelineConfig, run_pipeline  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
REC = str(REPO / "recordings" / "sim_2p20hz_hard.mcap")
SETTINGS = {"takeoff_n": 150.0, "touchdown_n": 300.0}


def _offline_touchdowns(tmp_path: Path, settings: dict) -> list[int]:
    out = tmp_path / f"analyze_{len(settings)}.json"
    extra = [a for k, v in settings.items() for a in ("--detector", f"{k}={v}")]
    subprocess.run([sys.executable, "-m", "hop_impedance.cli", "analyze", REC, "--no-fit", "--json", str(out), *extra],
                   check=True, capture_output=True)
    return [s["touchdown_stamp_ns"] for s in json.loads(out.read_text())["stances"] if s["complete"]]


def test_yaml_setting_moves_events_and_analysed_stances_together(tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump({"/**": {"ros__parameters": SETTINGS}}))
    report = run_pipeline(PipelineConfig(REC, str(tmp_path), rate=0.0, processes=False, timeout_s=90,
                                         params_file=str(params), publish_frames=False))
    assert report.finished
    events, kinetics = [], []
    for m in MessageStream(report.output_mcap, [EVENTS_TOPIC, STANCE_KINETICS_TOPIC]):
        if m.topic == EVENTS_TOPIC and m.message.event_type == StanceEvent.TOUCHDOWN:
            events.append(stamp_ns(m.message.event_stamp))
            assert m.message.threshold_n == pytest.approx(150.0)  # the level in use, from the file
        elif m.topic == STANCE_KINETICS_TOPIC and m.message.complete:
            kinetics.append(stamp_ns(m.message.touchdown_stamp))
    offline = _offline_touchdowns(tmp_path, SETTINGS)
    default = _offline_touchdowns(tmp_path, {})
    assert len(offline) == len(default) == 10
    assert events[: len(offline)] == pytest.approx(offline, abs=1000)
    assert sorted(kinetics) == pytest.approx(offline, abs=1000)
    assert min(a - b for a, b in zip(offline, default)) > 300_000  # measured 0.58 ms and more


def test_pipeline_yaml_detection_values_are_the_dataclass_defaults():
    """config/pipeline.yaml states the detection defaults for both nodes; they must be DetectorOptions' own."""
    cfg = yaml.safe_load((REPO / "config" / "pipeline.yaml").read_text())
    shared = cfg["/**"]["ros__parameters"]
    defaults = DetectorOptions()
    named = [k for k in shared if hasattr(defaults, k)]
    assert named and all(shared[k] == getattr(defaults, k) for k in named)
    for node in ("stance_detector", "inverse_dynamics"):  # set once, not per node
        assert not [k for k in cfg[node]["ros__parameters"] if hasattr(defaults, k)]
