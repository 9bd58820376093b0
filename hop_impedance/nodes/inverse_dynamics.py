"""``inverse_dynamics``: synchronise force plate and markers, per-stance and per-frame joint kinetics.

Thin adapter around :class:`hop_impedance.biomech.stages.StanceAnalysisStage`:

- ``/subject`` (transient-local) gives mass, height; the stage then scales
  the body model itself from the complete marker frames stamped within
  ``calibration_s`` of the first one and not after the first announced
  take-off (:func:`hop_impedance.biomech.analysis.calibration_markers`, the
  rule ``analyze`` uses too), once its marker stream has passed that window,
  so the model does not depend on how the messages were batched, equals the
  offline one, and is ready when the first stance ends.
- Force (1 kHz) and markers (100 Hz) arrive at different rates, with jitter,
  loss and possibly out of order. Each stream goes through a reorder buffer
  (``reorder_window_s`` of stamp time); the stage itself waits until both
  streams cover a stance's window (markers one frame beyond), which is the
  synchronisation. Counted per topic: received, lost (stamp gaps), out of
  order, too late to use. ``sync_residual_s`` on /diagnostics is the newest
  force stamp minus the newest marker stamp.
- A stance with missing samples is published with a rejection reason
  (stages.missing_samples_reason), never analysed on incomplete data.
  Every force-stamp gap (in the stamp-sorted stream) is counted exactly
  once: on the next stance's ``force_samples_lost_before`` when it starts
  before that stance's touchdown (in a flight, or a whole stance that was
  never detected), on its ``force_samples_lost_in_stance`` when it starts
  inside it (the stance is then also rejected), or in
  ``force_lost_after_last_stance`` on /diagnostics at the end of a replayed
  stream; their sum is ``force_lost_sorted``.
- Output per stance: ``StanceKinetics`` on ``/stance/kinetics`` (whole
  stance, reliable) and, if ``publish_frames``, one ``JointKinetics`` per
  force frame of the stance on ``/joint_kinetics`` (published after the
  analysis of the stance, since the zero-lag filters need the whole window,
  and after its ``StanceKinetics``: from 40 ms after it, 50 frames per 2 ms
  timer tick, so they neither delay nor compete with the estimator's fit;
  all of them before ``finished`` at the end of a replayed stream).
- Stances are found by the same detector stage as ``stance_detector``'s, with
  the same parameters (:func:`stance_detector.declare_detector_options`) and
  body weight, so the analysed stances are the published ``/stance/events``.
- ``side`` (issue 21): ``lumped`` (default) analyses the summed plate with the
  v1 markers and both legs' segments; ``left`` / ``right`` analyses one leg of
  a contract v2 stream (docs/contract_v2.md): that foot's plate
  ``/force_plate/<side>/wrench``, that leg's markers (``_l`` names for the
  left), one leg's segments (:func:`hop_impedance.biomech.per_leg.leg_subject`),
  no HAT residual; the same stances and moments as ``analyze_legs(...,
  rigid=False)`` (the offline rigid-segment fit is not live).
- ``low_latency`` selects the stage's low-latency mode (window ends
  ``post_pad_s`` after the provisional take-off); a withdrawn take-off is
  published as a stance rejected with :data:`stages.WITHDRAWN`, so the
  estimator withdraws what it published for it.
"""

from __future__ import annotations

import math
import time

import numpy as np
from hop_impedance_msgs.msg import JointKinetics, MarkerArray, StanceKinetics, SubjectInfo
from rclpy.node import Node
from std_msgs.msg import Header

from hop_impedance.bilateral import PLATE_TOPICS, SIDES, leg_marker_names
from hop_impedance.biomech.analysis import AnalysisOptions, StanceResult
from hop_impedance.biomech.per_leg import leg_subject
from hop_impedance.biomech.stages import StanceAnalysisStage
from hop_impedance.nodes.common import (
    END_TOPIC,
    JOINT_KINETICS_TOPIC,
    STANCE_KINETICS_TOPIC,
    DeferredPublisher,
    Diagnostics,
    InputGuard,
    InputTracker,
    ProgressReporter,
    ReorderBuffer,
    declare,
    declare_stream_parameters,
    float64_sequence,
    percentile_ms,
    raw_wrench_subscription,
    seconds_to_ns,
    set_stamp,
    stamp_ns,
    wrench_from_cdr,
)
from hop_impedance.nodes.qos import history_qos, input_qos, latched_qos, result_qos
from hop_impedance.nodes.stance_detector import declare_detector_options
from hop_impedance.recording import FORCE_TOPIC, MARKER_NAMES, MARKER_TOPIC, SUBJECT_TOPIC, Subject


class InverseDynamicsNode(Node):
    """Per-stance inverse dynamics from streamed force and markers; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("inverse_dynamics", **kwargs)
        reliable, reorder_s, period, diag = declare_stream_parameters(self, "the stage")
        self.publish_frames = declare(self, "publish_frames", True, "publish per-frame JointKinetics of each analysed stance")
        self.sex = declare(self, "sex", "female", "de Leva table: female or male (not in SubjectInfo)")
        self.side = declare(self, "side", "lumped", "lumped (summed plate, both legs) or left / right (one leg of a v2 stream)")
        if self.side not in ("lumped", *SIDES):
            raise ValueError(f"parameter side must be lumped, left or right, got {self.side!r}")
        self.force_topic = FORCE_TOPIC if self.side == "lumped" else PLATE_TOPICS[self.side]
        self.marker_names = MARKER_NAMES if self.side == "lumped" else leg_marker_names(self.side)
        low_latency = declare(self, "low_latency", False, "analyse at take-off + post_pad_s instead of at the next touchdown")
        post_pad = declare(self, "post_pad_s", 0.05, "low-latency mode: data used after take-off (s)")
        defaults = AnalysisOptions()
        self.calibration_s = declare(self, "calibration_s", defaults.calibration_s,
                                     "scale the body model from the complete marker frames within this many seconds of the first")
        cutoff = declare(self, "cutoff_hz", defaults.marker_cutoff_hz, "low-pass cut-off of markers and forces (Hz)")
        max_gap = declare(self, "max_gap_s", defaults.max_gap_s, "longest marker gap filled by interpolation (s)")
        # the stance detector's parameters and defaults, so both nodes find the same stances (one detector)
        self.options = AnalysisOptions(marker_cutoff_hz=cutoff, force_cutoff_hz=cutoff, max_gap_s=max_gap,
                                       detector=declare_detector_options(self), calibration_s=self.calibration_s)
        self.guard = InputGuard(self, cutoff)  # the input checks analyze runs (hop_impedance.input_checks)
        self.post_pad_s = post_pad if low_latency else None
        self.subject: Subject | None = None
        self.stage: StanceAnalysisStage | None = None
        self.t0_ns: int | None = None
        self._notes_logged = 0
        self.force_buf: ReorderBuffer[tuple[float, float, float]] = ReorderBuffer(int(reorder_s * 1e9))
        self.marker_buf: ReorderBuffer[np.ndarray] = ReorderBuffer(int(reorder_s * 1e9))
        # released, waiting for the body model
        self.pending_force: list[tuple[int, tuple[float, float, float]]] = []
        self.pending_markers: list[tuple[int, np.ndarray]] = []
        self.arrivals = np.zeros((0, 2), np.int64)  # (stamp ns, wall arrival ns) of recent force samples
        self._arrivals_new: list[tuple[int, int]] = []
        self.trackers = {self.force_topic: InputTracker(self.force_topic), MARKER_TOPIC: InputTracker(MARKER_TOPIC)}
        self.stances_out = 0
        self.rejected = 0
        # losses outside reported stances (a stance whose samples all vanished is never detected)
        self.sorted_force = InputTracker(self.force_topic)  # the released (stamp-sorted) force stream
        self.lost_between_stances = 0
        self.lost_after_last = 0
        self.analysis_s: list[float] = []
        self.takeoff_to_kinetics_s: list[float] = []  # first force sample at/after take-off -> StanceKinetics out
        self.pub_stance = self.create_publisher(StanceKinetics, STANCE_KINETICS_TOPIC, history_qos())  # late joiners
        # per-frame JointKinetics go out from later timer ticks, after the StanceKinetics (common.DeferredPublisher)
        self.pub_frames = DeferredPublisher(self, JointKinetics, JOINT_KINETICS_TOPIC, result_qos(2000))
        self.create_subscription(SubjectInfo, SUBJECT_TOPIC, self._on_subject, latched_qos())
        raw_wrench_subscription(self, self.force_topic, self._on_wrench, input_qos(reliable))
        self.create_subscription(MarkerArray, MARKER_TOPIC, self._on_markers, input_qos(reliable))
        self.create_subscription(Header, END_TOPIC, self._on_end, latched_qos())
        self.progress = ProgressReporter(self, self.trackers)
        self.diagnostics = Diagnostics(self, diag, self._diag_values, self._diag_level)
        self.end_timeout_s = declare(self, "end_timeout_s", 3.0, "after end-of-stream, wait this long (s) for missing data")
        self._end: tuple[int, float] | None = None
        self.create_timer(period, self._tick)

    # -- callbacks: message -> arrays ------------------------------------------

    def _on_subject(self, msg: SubjectInfo) -> None:
        self.subject = Subject(msg.subject_id, float(msg.body_mass), float(msg.body_height), self.sex)
        self.guard.subject(self.subject)

    def _on_wrench(self, cdr: bytes) -> None:
        """Raw ``WrenchStamped`` (parsed by :func:`common.wrench_from_cdr`, ~30x cheaper than deserialising)."""
        ns, (fx, _, fz, _, my, _) = wrench_from_cdr(cdr)
        self.trackers[self.force_topic].note(ns)
        if self.force_buf.add(ns, (fx, fz, -my)):  # sagittal [Fx, Fz, Mo] (force_plate.sagittal_wrench)
            self._arrivals_new.append((ns, time.time_ns()))

    def _on_markers(self, msg: MarkerArray) -> None:
        ns = stamp_ns(msg.header.stamp)
        self.trackers[MARKER_TOPIC].note(ns)
        names = list(msg.names)
        self.guard.marker_frame(ns, names, msg.positions)
        xz = np.full((len(MARKER_NAMES), 2), np.nan)
        for i, name in enumerate(self.marker_names):
            if name in names:
                p = msg.positions[names.index(name)]
                xz[i] = (p.x, p.z)
        self.marker_buf.add(ns, xz)

    def _on_end(self, msg: Header) -> None:
        """End of a replayed stream: finish once data up to its stamp are in (or after ``end_timeout_s``)."""
        self._end = (stamp_ns(msg.stamp), time.monotonic() + self.end_timeout_s)

    def _check_end(self) -> None:
        if self._end is None or self.progress.finished:
            return
        end_ns, deadline = self._end
        newest = max((t.newest_ns or 0) for t in list(self.trackers.values()))
        if newest >= end_ns or time.monotonic() > deadline:
            self._finish()

    def _finish(self) -> None:
        """End of a replayed stream: analyse what remains (the last stance) and report finished."""
        self.process(everything=True)
        if self.stage is None and (self.subject is not None or self.guard.failure is not None):
            self._start_stage()
            if self.stage is not None:  # the data held while waiting for the model
                for res in self.stage.push(self._force_arrays(self.pending_force), self._marker_arrays(self.pending_markers)):
                    self._publish(res)
                self.pending_force, self.pending_markers = [], []
        if self.stage is not None:
            for res in self.stage.flush():
                self._publish(res)
            self._log_notes(self.stage)
        self.lost_after_last = self.sorted_force.take_lost_before(2**63 - 1)
        if self.sorted_force.lost:
            self.get_logger().warning(
                f"{self.sorted_force.lost} force samples lost: {self.lost_between_stances} before reported stances, "
                f"{self.lost_after_last} after the last one; stances with losses inside were rejected")
        self.pub_frames.flush()  # every frame out before the node reports finished
        self.diagnostics.publish()  # the final counts, at once
        self.progress.finished = True
        self.progress.stances_out = self.stances_out
        self.progress.publish()

    # -- processing ------------------------------------------------------------

    def _tick(self) -> None:
        self.process()
        self._check_end()

    def process(self, everything: bool = False) -> None:
        """Release reordered samples, calibrate once, push to the stage, publish finished stances."""
        forces = self.force_buf.release(everything)
        markers = self.marker_buf.release(everything)
        for ns, _ in forces:
            self.sorted_force.note(ns)
        self.guard.force(forces, 1)
        if self.subject is None and self.guard.checks.subject is not None:  # no /subject in time: the parameters
            s = self.guard.checks.subject
            self.subject = Subject(s.subject_id, s.body_mass_kg, s.body_height_m, self.sex)
        if self._arrivals_new:
            self.arrivals = np.concatenate([self.arrivals[-5000:], np.array(self._arrivals_new, np.int64)])
            self._arrivals_new = []
        if not forces and not markers:
            return
        if self.t0_ns is None:
            self.t0_ns = min(x[0][0] for x in (forces, markers) if x)
        if self.stage is None:
            self.pending_force += forces
            self.pending_markers += markers
            self._start_stage()
            if self.stage is None:
                self._bound_pending()
                self._note_processed(forces, markers)
                return
            forces, markers = self.pending_force, self.pending_markers
            self.pending_force, self.pending_markers = [], []
        t_start = time.perf_counter()
        results = self.stage.push(self._force_arrays(forces), self._marker_arrays(markers))
        if results:
            self.analysis_s.append(time.perf_counter() - t_start)
        for res in results:
            self._publish(res)
        self._log_notes(self.stage)
        self._note_processed(forces, markers)

    def _log_notes(self, stage: StanceAnalysisStage) -> None:
        """The stage's notes (body model scaled, force-only), each logged once."""
        for note in stage.notes[self._notes_logged:]:
            (self.get_logger().info if note.startswith("body model scaled") else self.get_logger().warning)(note)
        self._notes_logged = len(stage.notes)

    def _note_processed(self, forces, markers) -> None:
        for topic, items in ((self.force_topic, forces), (MARKER_TOPIC, markers)):
            if items:
                self.progress.processed_ns[topic] = int(items[-1][0])
        self.progress.stances_out = self.stances_out
        if forces:
            self.diagnostics.sample_ns = int(forces[-1][0])

    def _start_stage(self) -> None:
        """Start the stage once the subject is known; it scales the body model from the markers itself.

        A failed input check: no model (every stance still gets a row with its reason).
        """
        if self.guard.failure is not None:
            mass = self.subject.body_mass_kg if self.subject is not None else math.nan
            self.stage = StanceAnalysisStage(None, mass, self.options, self.post_pad_s)
        elif self.subject is not None:
            model_subject = self.subject if self.side == "lumped" else leg_subject(self.subject)  # one leg's segments
            self.stage = StanceAnalysisStage(None, self.subject.body_mass_kg, self.options, self.post_pad_s,
                                             subject=model_subject)

    def _bound_pending(self, max_s: float = 30.0) -> None:
        """Without a subject, keep at most ``max_s`` of data (older samples are counted as lost)."""
        if self.pending_force and (self.pending_force[-1][0] - self.pending_force[0][0]) * 1e-9 > max_s:
            self.get_logger().warning(f"no {SUBJECT_TOPIC} yet: keeping only the last {max_s:.0f} s of data")
            cut = self.pending_force[-1][0] - int(max_s * 1e9)
            self.pending_force = [x for x in self.pending_force if x[0] >= cut]
            self.pending_markers = [x for x in self.pending_markers if x[0] >= cut]

    def _force_arrays(self, items):
        if not items:
            return None
        ns = np.fromiter((i[0] for i in items), np.int64, len(items))
        return (ns - self.t0_ns) * 1e-9, np.array([i[1] for i in items], float)

    def _marker_arrays(self, items):
        if not items:
            return None
        ns = np.fromiter((i[0] for i in items), np.int64, len(items))
        return (ns - self.t0_ns) * 1e-9, np.stack([i[1] for i in items])

    # -- arrays -> messages ----------------------------------------------------

    def _takeoff_arrival_ns(self, takeoff_ns: int) -> int:
        """Wall-clock arrival of the first force sample at or after take-off (0 if unknown)."""
        idx = np.searchsorted(self.arrivals[:, 0], takeoff_ns) if len(self.arrivals) else 0
        return int(self.arrivals[idx, 1]) if idx < len(self.arrivals) else 0

    def _publish(self, res: StanceResult) -> None:
        assert self.t0_ns is not None  # process() sets it before the stage can give a stance
        if self.guard.failure is not None:
            res.rejection_reason, res.joints = self.guard.reason(res.rejection_reason), None
        if self.side != "lumped":
            res.hip_residual_rms_nm = math.nan  # the HAT is not part of one leg: no top-down check
        msg = stance_message(res, self.t0_ns)
        msg.takeoff_received_ns = self._takeoff_arrival_ns(stamp_ns(msg.takeoff_stamp))
        msg.force_samples_lost_before = self.sorted_force.take_lost_before(stamp_ns(msg.touchdown_stamp))
        msg.force_samples_lost_in_stance = self.sorted_force.take_lost_before(stamp_ns(msg.takeoff_stamp))
        self.lost_between_stances += msg.force_samples_lost_before
        self.pub_stance.publish(msg)
        if msg.takeoff_received_ns:
            self.takeoff_to_kinetics_s.append((time.time_ns() - msg.takeoff_received_ns) * 1e-9)
        self.stances_out += 1
        self.rejected += res.rejection_reason is not None
        if self.publish_frames and res.joints is not None:
            # built and published from later ticks, so the estimator's callback (one process) and this node's
            # next samples do not wait behind ~300 messages (3-4 ms); the stance kinetics are already out
            t0_ns = self.t0_ns
            self.pub_frames.extend(lambda: frame_messages(res, t0_ns))

    def _diag_values(self) -> dict:
        out: dict[str, object] = {}
        for topic, t in self.trackers.items():
            name = "force" if topic == self.force_topic else "markers"
            out |= {f"{name}_received": t.received, f"{name}_rate_hz": t.rate_hz, f"{name}_lost": t.lost,
                    f"{name}_out_of_order": t.late}
        out["force_late_dropped"] = self.force_buf.dropped
        out["markers_late_dropped"] = self.marker_buf.dropped
        f, m = (self.trackers[k].newest_ns for k in (self.force_topic, MARKER_TOPIC))
        out["sync_residual_s"] = (f - m) * 1e-9 if f is not None and m is not None else math.nan
        out["force_lost_between_stances"] = self.lost_between_stances
        out["force_lost_after_last_stance"] = self.lost_after_last
        out["force_lost_sorted"] = self.sorted_force.lost
        out["stances_published"] = self.stances_out
        out["stances_rejected"] = self.rejected
        out["analysis_p50_ms"] = percentile_ms(self.analysis_s, 50)
        out["analysis_p99_ms"] = percentile_ms(self.analysis_s, 99)
        out["takeoff_to_kinetics_p50_ms"] = percentile_ms(self.takeoff_to_kinetics_s, 50)
        out["takeoff_to_kinetics_p99_ms"] = percentile_ms(self.takeoff_to_kinetics_s, 99)
        out["body_model"] = ("waiting for the subject" if self.stage is None else "calibrating" if self.stage.calibrating
                             else "ready" if self.stage.model is not None else "none (force-only)")
        out["force_duplicates_dropped"] = self.force_buf.duplicates
        out["markers_duplicates_dropped"] = self.marker_buf.duplicates
        out |= self.guard.values()
        return out

    def _diag_level(self) -> tuple[int, str]:
        level = self.guard.level()
        if level is not None:
            return level
        lost = sum(t.lost for t in self.trackers.values()) + self.force_buf.dropped + self.marker_buf.dropped
        return (1, f"{lost} input messages lost or too late") if lost else (0, "ok")


def _nan(x) -> float:
    return math.nan if x is None else float(x)


def stance_message(res: StanceResult, t0_ns: int) -> StanceKinetics:
    """A :class:`StanceResult` as a ``StanceKinetics`` message (arrays row-major (n, 3))."""
    msg = StanceKinetics(stance_index=int(res.index), complete=bool(res.complete),
                         rejection_reason=res.rejection_reason or "")
    td_ns, to_ns = seconds_to_ns(t0_ns, res.touchdown_s), seconds_to_ns(t0_ns, res.takeoff_s)
    set_stamp(msg.touchdown_stamp, td_ns)
    set_stamp(msg.takeoff_stamp, to_ns)
    set_stamp(msg.header.stamp, to_ns)
    msg.header.frame_id = "lab"
    msg.contact_time_s = float(res.contact_time_s)
    msg.flight_time_before_s = _nan(res.flight_before_s)
    msg.peak_grf_n = _nan(res.peak_grf_n)
    msg.peak_grf_bw = _nan(res.peak_grf_bw)
    msg.hop_frequency_hz = _nan(res.hop_frequency_hz)
    msg.leg_stiffness_n_per_m = _nan(res.leg_stiffness_n_per_m)
    msg.hip_excursion_m = _nan(res.hip_excursion_m)
    msg.data_after_takeoff_s = float(res.data_after_takeoff_s or 0.0)  # 0: whole record (short windows are > 0)
    if res.joints is not None:
        j = res.joints
        msg.time_s = float64_sequence(j.time_s)
        msg.angle_rad = float64_sequence(j.angle_rad)
        msg.angular_velocity_rad_s = float64_sequence(j.angular_velocity_rad_s)
        msg.moment_nm = float64_sequence(j.moment_nm)
        msg.power_w = float64_sequence(j.power_w)
    return msg


def stance_from_message(msg: StanceKinetics) -> StanceResult:
    """Inverse of :func:`stance_message` for what the impedance fit needs (times relative to touchdown)."""
    from hop_impedance.biomech.analysis import JointSeries

    td = stamp_ns(msg.touchdown_stamp) * 1e-9
    res = StanceResult(
        int(msg.stance_index), td, stamp_ns(msg.takeoff_stamp) * 1e-9, bool(msg.complete),
        msg.rejection_reason or None, float(msg.contact_time_s), msg.peak_grf_n, msg.peak_grf_bw,
        None if math.isnan(msg.flight_time_before_s) else msg.flight_time_before_s, None,
        None if math.isnan(msg.hop_frequency_hz) else msg.hop_frequency_hz,
        leg_stiffness_n_per_m=msg.leg_stiffness_n_per_m, hip_excursion_m=msg.hip_excursion_m,
        data_after_takeoff_s=msg.data_after_takeoff_s if msg.data_after_takeoff_s > 0 else None,
    )
    n = len(msg.time_s)
    if n:
        res.joints = JointSeries(
            np.asarray(msg.time_s, float),
            *(np.asarray(a, float).reshape(n, 3)
              for a in (msg.angle_rad, msg.angular_velocity_rad_s, msg.moment_nm, msg.power_w)),
        )
    return res


def frame_messages(res: StanceResult, t0_ns: int) -> list[JointKinetics]:
    """One ``JointKinetics`` per force frame of an analysed stance."""
    j = res.joints
    assert j is not None, "frame_messages needs an analysed stance (joint data)"  # callers check res.joints
    out = []
    for i in range(len(j.time_s)):
        msg = JointKinetics(stance_index=int(res.index), time_since_touchdown_s=float(j.time_s[i]))
        set_stamp(msg.header.stamp, seconds_to_ns(t0_ns, res.touchdown_s + float(j.time_s[i])))
        msg.header.frame_id = "lab"
        msg.angle_rad = j.angle_rad[i].tolist()
        msg.angular_velocity_rad_s = j.angular_velocity_rad_s[i].tolist()
        msg.moment_nm = j.moment_nm[i].tolist()
        msg.power_w = j.power_w[i].tolist()
        msg.grf_z_n = math.nan
        msg.cop_x_m = math.nan
        out.append(msg)
    return out


def main(args=None) -> None:
    """Run the node (``python -m hop_impedance.nodes.inverse_dynamics --ros-args -p ...``)."""
    from hop_impedance.nodes.common import spin_node

    spin_node(InverseDynamicsNode, args)


if __name__ == "__main__":
    main()
