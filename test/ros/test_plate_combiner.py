"""Two force plates live: the replay node plays a two-plate MCAP (built from a bundled recording,
test/two_plates.py), the plate_combiner node (its own process, config/plates.yaml) sums them,
the stance_detector node detects stances on the sum, over real DDS; the combined wrench gives the summed
plate's stances and coefficients within 1e-6 relative, and a plate that stops is reported on /diagnostics, not summed as zero."""

import os
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from hop_impedance_msgs.msg import StanceEvent  # noqa: E402

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.child_env import child_env  # noqa: E402
from hop_impedance.impedance.recording_fits import fit_recording  # noqa: E402
from hop_impedance.io.mcap_io import McapWriter  # noqa: E402
from hop_impedance.io.recording_io import SUBJECT_TYPE, WRENCH_TYPE, load_recording  # noqa: E402
from hop_impedance.nodes.common import stamp_ns  # noqa: E402
from hop_impedance.nodes.qos import input_qos, result_qos  # noqa: E402
from hop_impedance.nodes.runner import child_command  # noqa: E402
from hop_impedance.recording import SUBJECT_TOPIC, ForcePlateSeries, Recording  # noqa: E402
from test.two_plates import LEFT_TOPIC, RIGHT_TOPIC, split_two_plates  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
RECORDING = ROOT / "recordings" / "sim_2p20hz_hard.mcap"
PLATES_YAML = ROOT / "config" / "plates.yaml"
#: Topics of this test process only (config/plates.yaml's layout, its topic names overridden), so another
#: pytest that happens to share the ROS domain cannot feed or read them.
PREFIX = f"/test_plates_{os.getpid()}"
TOPICS = {LEFT_TOPIC: PREFIX + LEFT_TOPIC, RIGHT_TOPIC: PREFIX + RIGHT_TOPIC}
OUTPUT = PREFIX + "/force_plate/wrench"
EVENTS = PREFIX + "/stance/events"
#: The fixed topics of the replay and the stance detector, moved under PREFIX too.
REMAPS = [a for old, new in (("/force_plate/wrench", OUTPUT), ("/stance/events", EVENTS), ("/subject", PREFIX + "/subject"),
                             ("/replay/end_of_stream", PREFIX + "/end"), ("/pipeline/progress", PREFIX + "/progress"))
          for a in ("-r", f"{old}:={new}")]


def _write_two_plates(path: Path, parts: dict, right_until: int | None = None, n: int | None = None, subject=None) -> None:
    events = []
    for topic, (stamps, w) in parts.items():
        stop = right_until if (topic == RIGHT_TOPIC and right_until is not None) else n
        for i in range(len(stamps) if stop is None else stop):
            events.append((int(stamps[i]), topic, w[i]))
    events.sort(key=lambda e: (e[0], e[1]))
    with McapWriter(path) as writer:
        if subject is not None:
            t0 = events[0][0]
            writer.write(SUBJECT_TOPIC, SUBJECT_TYPE, {
                "header": {"stamp": {"sec": t0 // 1_000_000_000, "nanosec": t0 % 1_000_000_000}, "frame_id": "lab"},
                "subject_id": subject.subject_id, "body_mass": subject.body_mass_kg, "body_height": subject.body_height_m}, t0)
        for t, topic, w in events:
            stamp = {"sec": t // 1_000_000_000, "nanosec": t % 1_000_000_000}
            writer.write(TOPICS[topic], WRENCH_TYPE, {
                "header": {"stamp": stamp, "frame_id": topic.rsplit("/", 1)[-1]},
                "wrench": {"force": dict(zip("xyz", map(float, w[:3]))), "torque": dict(zip("xyz", map(float, w[3:])))},
            }, t)


def _wait_until(executor, condition, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)


def _readers(diags: list) -> int:
    """Readers matched to the combined output, from the plate_combiner's newest diagnostics."""
    for d in reversed(diags):
        for st in d.status:
            if st.name == "/plate_combiner":
                return int(next((kv.value for kv in st.values if kv.key == "readers"), "0"))
    return 0


def _run(mcap: Path, want: int, log_dir: Path, timeout_s: float = 60.0, settle_s: float = 1.0, detector: bool = False):
    """Start plate_combiner (stance_detector after it, if asked) and replay as processes; collect the
    combined wrench, the plate_combiner's /diagnostics and the stance events."""
    wrenches, diags, events = [], [], []
    context = rclpy.Context()
    rclpy.init(context=context)
    children = []
    try:
        node = rclpy.create_node("test_plate_listener", context=context)
        node.create_subscription(WrenchStamped, OUTPUT, wrenches.append, input_qos(True))
        node.create_subscription(DiagnosticArray, "/diagnostics", diags.append, 50)
        node.create_subscription(StanceEvent, EVENTS, events.append, result_qos())
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        starts = [
            ("plate_combiner", {"diagnostics_period_s": 0.2, "plate_topics": list(TOPICS.values()), "output_topic": OUTPUT},
             str(PLATES_YAML)),
            # end_timeout_s under the 3 s default: the end stamp is the right plate's, which the combined stream never reaches
            *([("stance_detector", {"end_timeout_s": 1.5}, str(ROOT / "config" / "pipeline.yaml"))] if detector else []),
            # rate 2 (not 0): without consumers a rate-0 replay waits for acknowledgements block by block
            ("replay", {"recording": str(mcap), "rate": 2.0, "topics": [*TOPICS.values(), SUBJECT_TOPIC]}, None),
        ]
        for name, params, pfile in starts:
            log = open(log_dir / f"{name}.log", "w")  # noqa: SIM115
            children.append(subprocess.Popen(child_command(name, params, pfile) + REMAPS, env=child_env(), stdout=log,
                                             stderr=subprocess.STDOUT))
            log.close()
            if name == "plate_combiner":  # the replay waits for its readers; the combiner's reader is us
                _wait_until(executor, lambda: node.count_publishers(OUTPUT) > 0 and diags, 20.0)
            elif name == "stance_detector":  # matched at the combiner itself (its diagnostics), not only seen by us
                _wait_until(executor, lambda: node.count_publishers(EVENTS) > 0 and _readers(diags) > 1, 20.0)
        replay = children[-1]
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and (len(wrenches) < want or replay.poll() is None):
            executor.spin_once(timeout_sec=0.05)
        assert replay.wait(timeout=10) == 0, (log_dir / "replay.log").read_text()
        end = time.monotonic() + settle_s  # the combiner's end-of-stream flush and final diagnostics
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    finally:
        for p in children:
            if p.poll() is None:
                p.send_signal(2)
        for p in children:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
        rclpy.shutdown(context=context)
    combiner = [s for d in diags for s in d.status if s.name == "/plate_combiner"]
    return wrenches, combiner, events


def _values(status) -> dict:
    return {kv.key: kv.value for kv in status[-1].values} if status else {}


def test_replayed_two_plates_combine_to_the_summed_plate(tmp_path):
    rec = load_recording(RECORDING)
    mcap = tmp_path / "two_plates.mcap"
    _write_two_plates(mcap, split_two_plates(rec.force), subject=rec.subject)
    wrenches, status, events = _run(mcap, len(rec.force), tmp_path, settle_s=2.5, detector=True)
    stamps = np.array([stamp_ns(w.header.stamp) for w in wrenches], np.int64)
    assert len(wrenches) == len(rec.force), (_values(status), np.setdiff1d(rec.force.stamp_ns, stamps))
    np.testing.assert_array_equal(stamps, rec.force.stamp_ns)
    assert {w.header.frame_id for w in wrenches} == {"force_plate"}
    force = np.array([[w.wrench.force.x, w.wrench.force.y, w.wrench.force.z] for w in wrenches])
    moment = np.array([[w.wrench.torque.x, w.wrench.torque.y, w.wrench.torque.z] for w in wrenches])
    a1 = analyze_recording(rec)
    a2 = analyze_recording(Recording(ForcePlateSeries(stamps, force, moment), rec.markers, rec.subject, "live two plates"))
    assert [t for s in a2.stances for t in (s.touchdown_s, s.takeoff_s)] == pytest.approx(
        [t for s in a1.stances for t in (s.touchdown_s, s.takeoff_s)], rel=1e-6)
    worst, n = 0.0, 0
    for f1, f2 in zip(fit_recording(a1), fit_recording(a2)):
        for joint, fit in f1.items():
            assert f2[joint].rejection_reason == fit.rejection_reason
            for term, v in fit.coefficients.items():
                w2 = f2[joint].coefficients[term]
                worst = max(worst, 0.0 if v == w2 else abs(w2 - v) / abs(v))
                n += 1
    print(f"over DDS: {len(wrenches)} combined samples, {n} coefficients, max relative difference {worst:.2e}")
    # The stance_detector node on the combined stream: every touchdown and take-off of the offline analysis
    # of the summed plate, the last one included (end-of-stream through the combiner).
    live = sorted((stamp_ns(e.event_stamp), e.event_type) for e in events)
    offline = sorted([(rec.start_ns + round(s.touchdown_s * 1e9), StanceEvent.TOUCHDOWN) for s in a1.stances]
                     + [(rec.start_ns + round(s.takeoff_s * 1e9), StanceEvent.TAKEOFF) for s in a1.stances])
    assert [k for _, k in live] == [k for _, k in offline], (tmp_path / "stance_detector.log").read_text()[-2000:]
    assert np.abs(np.array([t for t, _ in live]) - [t for t, _ in offline]).max() <= 1000  # ns
    assert n >= 60 and worst <= 1e-6
    last = {kv.key: kv.value for kv in status[-1].values}
    assert status[-1].level == bytes([0]), status[-1].message
    assert last["left_missing"] == last["right_missing"] == "0" and last["right_skew_ms"] == "0.5"


def test_a_plate_that_stops_is_reported_on_diagnostics(tmp_path):
    rec = load_recording(RECORDING)
    mcap = tmp_path / "right_stops.mcap"
    _write_two_plates(mcap, split_two_plates(rec.force), right_until=700, n=1500)
    # end_timeout_s 1 s: the right plate never reaches the end
    wrenches, status, _ = _run(mcap, 700, tmp_path, timeout_s=30.0, settle_s=2.5)
    assert len(wrenches) == 700, _values(status)  # nothing after the right plate stopped: no half-weight wrench
    final = status[-1]
    assert final.level == bytes([2]) and "right" in final.message, final.message
    values = {kv.key: kv.value for kv in final.values}
    assert values["right_missing"] == "800" and values["published"] == "700"
