"""``stance_detector``: touchdown / take-off events from the force plate.

Subscribes ``/force_plate/wrench``, feeds the vertical force to
:class:`hop_impedance.biomech.stages.StanceDetectorStage` (the same state
machine as the batch analysis) and publishes ``StanceEvent`` on
``/stance/events`` (reliable). Samples are reordered over
``reorder_window_s`` of stamp time before detection; samples arriving later
than that are counted (``late_dropped``) and skipped.

One detector: ``inverse_dynamics`` runs the same stage on the same samples
with the same parameters (:func:`declare_detector_options`: every field of
:class:`DetectorOptions`, default from the dataclass, set once for both nodes
under ``/**`` in ``config/pipeline.yaml``) and the same body weight (from
``/subject``, transient-local; force samples wait here until it is in, as in
``inverse_dynamics``), so the published events are the stances it analyses
(test/ros/test_one_detector.py).

Parameters (``config/pipeline.yaml``): ``reliable_inputs``,
``reorder_window_s``, ``process_period_s``, ``diagnostics_period_s``, the
detector fields (``touchdown_n``, ``takeoff_n``, ``touchdown_bw``, ...).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from hop_impedance_msgs.msg import StanceEvent, SubjectInfo
from rclpy.node import Node
from std_msgs.msg import Header

from hop_impedance.biomech.stages import StanceDetectorStage, pending_stance
from hop_impedance.biomech.stance_detection import DetectorOptions
from hop_impedance.nodes.common import (
    END_TOPIC,
    EVENTS_TOPIC,
    Diagnostics,
    InputTracker,
    ProgressReporter,
    ReorderBuffer,
    declare,
    declare_stream_parameters,
    raw_wrench_subscription,
    seconds_to_ns,
    set_stamp,
    stamp_ns,
    wrench_from_cdr,
)
from hop_impedance.nodes.qos import input_qos, latched_qos, result_qos
from hop_impedance.recording import FORCE_TOPIC, GRAVITY_M_S2, SUBJECT_TOPIC


class StanceDetectorNode(Node):
    """Publishes contact events; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("stance_detector", **kwargs)
        reliable, reorder_s, period, diag = declare_stream_parameters(self, "the detector")
        self.detector_options = declare_detector_options(self)
        self.stage: StanceDetectorStage | None = None  # once /subject gives the body weight
        self.waiting: list[tuple[np.ndarray, np.ndarray]] = []  # released samples before that
        self.t0_ns: int | None = None
        self.buffer: ReorderBuffer[float] = ReorderBuffer(int(reorder_s * 1e9))
        self.tracker = InputTracker(FORCE_TOPIC)
        self.events_out = 0
        self.touchdowns = 0
        self._recent_t = np.zeros(0)
        self._recent_fz = np.zeros(0)
        self.pub = self.create_publisher(StanceEvent, EVENTS_TOPIC, result_qos())
        raw_wrench_subscription(self, FORCE_TOPIC, self._on_wrench, input_qos(reliable))
        self.create_subscription(Header, END_TOPIC, self._on_end, latched_qos())
        self.create_subscription(SubjectInfo, SUBJECT_TOPIC, self._on_subject, latched_qos())
        self.progress = ProgressReporter(self, {FORCE_TOPIC: self.tracker})
        self.diagnostics = Diagnostics(self, diag, self._diag_values)
        self.end_timeout_s = declare(self, "end_timeout_s", 3.0, "after end-of-stream, wait this long (s) for missing data")
        self._end: tuple[int, float] | None = None
        self.create_timer(period, self._tick)

    def _on_wrench(self, cdr: bytes) -> None:
        """Raw ``WrenchStamped`` (parsed by :func:`common.wrench_from_cdr`)."""
        ns, (_, _, fz, _, _, _) = wrench_from_cdr(cdr)
        self.tracker.note(ns)
        self.buffer.add(ns, fz)

    def _on_subject(self, msg: SubjectInfo) -> None:
        if self.stage is None:
            self.stage = StanceDetectorStage(self.detector_options, float(msg.body_mass) * GRAVITY_M_S2)
            for t, fz in self.waiting:
                self._detect(t, fz)
            self.waiting = []

    def _tick(self) -> None:
        self.process()
        self._check_end()

    def process(self, everything: bool = False) -> None:
        """Run the detector on released samples and publish the events."""
        items = self.buffer.release(everything)
        if not items:
            return
        ns = np.fromiter((i[0] for i in items), np.int64, len(items))
        fz = np.fromiter((i[1] for i in items), float, len(items))
        if self.t0_ns is None:
            self.t0_ns = int(ns[0])
        t = (ns - self.t0_ns) * 1e-9
        if self.stage is None:
            self.waiting.append((t, fz))
            if t[-1] - self.waiting[0][0][0] > SUBJECT_WAIT_S:  # no /subject: detect with the absolute floors
                self.get_logger().warning(f"no {SUBJECT_TOPIC} after {SUBJECT_WAIT_S:.0f} s of force data: "
                                          "stance thresholds without the body weight (absolute floors)")
                self.stage = StanceDetectorStage(self.detector_options)
                waiting, self.waiting = self.waiting, []
                for tw, fw in waiting:
                    self._detect(tw, fw)
        else:
            self._detect(t, fz)
        self.progress.processed_ns[FORCE_TOPIC] = int(ns[-1])
        self.diagnostics.sample_ns = int(ns[-1])

    def _detect(self, t: np.ndarray, fz: np.ndarray) -> None:
        keep = self._recent_t > t[-1] - 3.0
        self._recent_t = np.concatenate([self._recent_t[keep], t])
        self._recent_fz = np.concatenate([self._recent_fz[keep], fz])
        assert self.stage is not None  # the callers create it first
        for ev in self.stage.push((t, fz)):
            self._publish(ev)

    def _on_end(self, msg: Header) -> None:
        """End of a replayed stream: finish once data up to its stamp are in (or after ``end_timeout_s``)."""
        self._end = (stamp_ns(msg.stamp), time.monotonic() + self.end_timeout_s)

    def _check_end(self) -> None:
        if self._end is None or self.progress.finished:
            return
        end_ns, deadline = self._end
        newest = max((t.newest_ns or 0) for t in [self.tracker])
        if newest >= end_ns or time.monotonic() > deadline:
            self._finish()

    def _finish(self) -> None:
        """End of a replayed stream: flush once every sample up to its last stamp is in."""
        self.process(everything=True)
        if self.stage is None and self.waiting:
            self.stage = StanceDetectorStage(self.detector_options)
            waiting, self.waiting = self.waiting, []
            for tw, fw in waiting:
                self._detect(tw, fw)
        if self.stage is not None:
            for ev in self.stage.flush():
                self._publish(ev)
        self.diagnostics.publish()  # the final counts, at once
        self.progress.finished = True
        self.progress.publish()

    def _publish(self, ev) -> None:
        """One StanceEvent; a take-off carries its stance's contact time, peak force and flight before.

        Provisional and withdrawn take-offs (the controller feed's early
        announcement, see stance_detection) are not events of this topic:
        it publishes the confirmed ones.
        """
        if ev.kind not in ("touchdown", "takeoff"):
            return
        # events come from the stage, which gets data after process() set t0_ns
        assert self.stage is not None and self.t0_ns is not None
        msg = StanceEvent(threshold_n=float(self.stage.detector.levels_n[1]), complete=True,
                          flight_time_before_s=math.nan)
        stances = list(self.stage.stances)
        pending = pending_stance(self.stage.detector)
        if pending is not None:
            stances.append(pending)  # a confirmed take-off waits there until the next touchdown
        if ev.kind == "touchdown":
            msg.event_type = StanceEvent.TOUCHDOWN
            msg.stance_index = len(stances)
            if stances:
                msg.flight_time_before_s = ev.time_s - stances[-1].takeoff_s
        else:
            msg.event_type = StanceEvent.TAKEOFF
            k = len(stances) - 1
            s = stances[k]
            msg.stance_index = k
            msg.complete = bool(s.complete)
            msg.contact_time_s = float(s.takeoff_s - s.touchdown_s)
            if k > 0:
                msg.flight_time_before_s = s.touchdown_s - stances[k - 1].takeoff_s
            sel = (self._recent_t >= s.touchdown_s) & (self._recent_t <= s.takeoff_s)
            if np.any(sel):
                msg.peak_grf_n = float(np.max(self._recent_fz[sel]) - ev.baseline_n)
        event_ns = seconds_to_ns(self.t0_ns, ev.time_s)
        set_stamp(msg.event_stamp, event_ns)
        set_stamp(msg.header.stamp, event_ns)
        msg.header.frame_id = "force_plate"
        self.pub.publish(msg)
        self.events_out += 1

    def _diag_values(self) -> dict:
        t = self.tracker
        return {"force_received": t.received, "force_rate_hz": t.rate_hz, "force_lost": t.lost,
                "force_out_of_order": t.late, "force_late_dropped": self.buffer.dropped, "events_published": self.events_out}


#: Force data (s) the detector waits for ``/subject`` before it detects without the body weight.
SUBJECT_WAIT_S = 30.0

_DETECTOR_PARAMETERS = {
    "touchdown_n": "touchdown level floor above the flight baseline (N)",
    "takeoff_n": "take-off level floor above the flight baseline (N)",
    "touchdown_bw": "touchdown level as a fraction of body weight",
    "takeoff_bw": "take-off level as a fraction of body weight",
    "noise_factor": "take-off level at least this many flight-noise SDs (touchdown twice)",
    "min_stance_s": "shorter stances are rejected (s)",
    "min_flight_s": "a dip below the take-off level must last this long to be a flight (s)",
    "provisional_s": "announce a take-off provisionally after this long below the level (s; withdrawn within min_flight_s)",
    "settle_s": "flight samples this close to take-off are left out of the baseline (s)",
    "max_stance_s": "a steady 'stance' far from body weight longer than this is a detector failure (s)",
    "steady_s": "window of the steadiness test (s)",
    "steady_sd_n": "floor of the steadiness SD limit (N)",
    "standing_tolerance_bw": "steady force within this many body weights of 1 BW is quiet standing",
    "start_flight_max_n": "a first sample below this (N) starts the recording in flight",
    "start_flight_max_bw": "... or below this fraction of body weight, if larger",
}


def declare_detector_options(node: Node) -> DetectorOptions:
    """Declare every :class:`DetectorOptions` field as a parameter (default from the dataclass) and return the options.

    The one place the nodes take their detection settings from; ``event_level_n``
    (None = the take-off level) is not a ROS parameter.
    """
    defaults = DetectorOptions()
    values = {}
    for f in dataclasses.fields(DetectorOptions):
        if f.name != "event_level_n":  # a new field without a description here is a KeyError, not a silent default
            values[f.name] = float(declare(node, f.name, float(getattr(defaults, f.name)), _DETECTOR_PARAMETERS[f.name]))
    return DetectorOptions(**values)


def main(args=None) -> None:
    """Run the node (``python -m hop_impedance.nodes.stance_detector --ros-args -p ...``)."""
    from hop_impedance.nodes.common import spin_node

    spin_node(StanceDetectorNode, args)


if __name__ == "__main__":
    main()
