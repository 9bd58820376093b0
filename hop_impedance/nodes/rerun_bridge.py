"""``rerun_bridge``: stream the pipeline's topics to Rerun, live.

A thin adapter: each message becomes arrays, and the arrays go through the
same logging functions as the offline ``hop-impedance view``
(:mod:`hop_impedance.viz.views`), so live and offline show the same entities
and blueprint.

Subscriptions (names from :mod:`hop_impedance.nodes.common`):
``/force_plate/wrench`` (GRF series and arrow), ``/mocap/markers`` (stick
figure), ``/subject`` (body weight), ``/stance/events`` (stance marks),
``/joint_kinetics`` (angles, velocities, moments, powers),
``/impedance/profile`` and ``/impedance/stance_summary`` (per-stance fits,
table, trends).

Cost control: high-rate messages are only appended to lists in the
callbacks; a timer (``flush_period_s``) sends each list as one columnar
``send_columns`` call per entity. Per-stance views are logged once per
stance. ``bench/bench_rerun.py`` measures what this costs.

Time: the ``time`` timeline is header stamps minus ``start_ns`` (parameter;
0 = the first force or marker stamp received), as offline where it is the
recording's first message.

Parameters
----------
viewer_url : str
    gRPC address of a running viewer (e.g. ``rerun+http://127.0.0.1:9876/proxy``).
save_path : str
    Also (or only) write an .rrd file.
spawn : bool
    Spawn a viewer on loopback; default true when neither ``viewer_url`` nor
    ``save_path`` is given. Viewer analytics are disabled first.
flush_period_s : float
    Period of the columnar flush (s) [0.1].
start_ns : int
    Zero of the time axis (ns) [0 = first stamp seen].
reliable : bool
    Subscribe to the sensor topics reliably [true].
"""

from __future__ import annotations

import math

import numpy as np
from geometry_msgs.msg import WrenchStamped
from hop_impedance_msgs.msg import ImpedanceProfile, JointKinetics, MarkerArray, StanceEvent, StanceSummary, SubjectInfo
from rclpy.node import Node

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.nodes.common import EVENTS_TOPIC, JOINT_KINETICS_TOPIC, PROFILE_TOPIC, SUMMARY_TOPIC, declare, stamp_ns
from hop_impedance.nodes.qos import input_qos, latched_qos, result_qos
from hop_impedance.recording import FORCE_TOPIC, GRAVITY_M_S2, MARKER_NAMES, MARKER_TOPIC, SUBJECT_TOPIC
from hop_impedance.viz.blueprint import default_blueprint
from hop_impedance.viz.session import new_recording_stream, open_sinks
from hop_impedance.viz.stance_view import JointFitView, StanceView
from hop_impedance.viz.views import (
    DEFAULT_CHART_RANGES,
    cop_x_from_wrench,
    joint_charts,
    log_body,
    log_chart_frames,
    log_ground_reaction,
    log_joint_series,
    log_stance,
    log_stance_event,
    log_static_styles,
)


def wrench_block(msgs: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """WrenchStamped messages -> (stamp_ns (N,), force_n (N, 3), torque_nm (N, 3))."""
    stamps = np.array([stamp_ns(m.header.stamp) for m in msgs], np.int64)
    force = np.array([[m.wrench.force.x, m.wrench.force.y, m.wrench.force.z] for m in msgs], float)
    torque = np.array([[m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z] for m in msgs], float)
    return stamps, force, torque


def marker_frame_xz(msg) -> np.ndarray:
    """MarkerArray -> contract markers ``[x, z]`` (6, 2) in :data:`MARKER_NAMES` order; absent = NaN."""
    out = np.full((len(MARKER_NAMES), 2), np.nan)
    for name, p in zip(msg.names, msg.positions):
        if name in MARKER_NAMES:
            out[MARKER_NAMES.index(name)] = (p.x, p.z)
    return out


def kinetics_block(msgs: list) -> dict[str, np.ndarray]:
    """JointKinetics messages -> ``stamp_ns`` (n,), ``stance`` (n,), and (n, 3) angle/velocity/moment/power."""
    return {
        "stamp_ns": np.array([stamp_ns(m.header.stamp) for m in msgs], np.int64),
        "stance": np.array([m.stance_index for m in msgs], np.int64),
        "angle_rad": np.array([m.angle_rad for m in msgs], float),
        "angular_velocity_rad_s": np.array([m.angular_velocity_rad_s for m in msgs], float),
        "moment_nm": np.array([m.moment_nm for m in msgs], float),
        "power_w": np.array([m.power_w for m in msgs], float),
    }


def joint_view_from_profile(msg) -> JointFitView:
    """ImpedanceProfile -> :class:`JointFitView` (constant model ``M0 + K_const (rho - rho0)``, as offline)."""
    if not msg.accepted:
        return JointFitView(rejection_reason=msg.rejection_reason or f"fit status {msg.solver_status}")
    angle = np.asarray(msg.angle_rad, float)
    measured = np.asarray(msg.moment_measured_nm, float)
    constant = measured[0] + msg.constant_stiffness_nm_per_rad * (angle - angle[0]) if angle.size else angle
    return JointFitView(
        rejection_reason=None,
        time_s=np.asarray(msg.time_s, float),
        angle_rad=angle,
        moment_nm=measured,
        moment_fit_nm=np.asarray(msg.moment_fit_nm, float),
        moment_constant_nm=constant,
        stiffness_nm_per_rad=np.asarray(msg.stiffness_nm_per_rad, float),
        coefficients=dict(zip(msg.terms, msg.coefficients)),
        std_errors=dict(zip(msg.terms, msg.std_errors)),
        p_values=dict(zip(msg.terms, msg.p_values)),
        r_squared=msg.r_squared,
        rmse_nm=msg.rmse_nm,
        sse_variable=msg.sse_variable,
        sse_constant=msg.sse_constant,
        overall_stiffness_nm_per_rad=msg.overall_stiffness_nm_per_rad,
    )


def stance_view_from_summary(msg, profiles: dict, start_ns: int) -> StanceView:
    """StanceSummary (+ its ImpedanceProfiles by joint) -> :class:`StanceView` on the bridge's time axis."""
    reason = msg.rejection_reason or None
    joints = {j: (joint_view_from_profile(profiles[j]) if j in profiles and not reason else JointFitView(reason or "no profile"))
              for j in JOINT_NAMES}
    freq = msg.hop_frequency_hz if math.isfinite(msg.hop_frequency_hz) and msg.hop_frequency_hz > 0 else None
    return StanceView(
        index=int(msg.stance_index),
        touchdown_s=(stamp_ns(msg.touchdown_stamp) - start_ns) * 1e-9,
        takeoff_s=(stamp_ns(msg.takeoff_stamp) - start_ns) * 1e-9,
        rejection_reason=reason,
        contact_time_s=msg.contact_time_s,
        peak_grf_bw=msg.peak_grf_bw,
        hop_frequency_hz=freq,
        joints=joints,
    )


class RerunBridge(Node):
    """Subscribe to the pipeline's topics and log them to Rerun (see the module docstring)."""

    def __init__(self, **kwargs) -> None:
        super().__init__("rerun_bridge", **kwargs)
        viewer_url = declare(self, "viewer_url", "", "gRPC address of a running Rerun viewer")
        save_path = declare(self, "save_path", "", "write an .rrd file")
        spawn = declare(self, "spawn", not viewer_url and not save_path, "spawn a viewer on loopback")
        period = declare(self, "flush_period_s", 0.1, "period of the columnar flush (s)")
        self.start_ns = int(declare(self, "start_ns", 0, "zero of the time axis (ns), 0 = first stamp"))
        reliable = declare(self, "reliable", True, "subscribe to sensor topics reliably")
        self.rec = new_recording_stream()
        open_sinks(self.rec, default_blueprint(), save=save_path or None, connect_url=viewer_url or None, spawn=spawn)
        log_static_styles(self.rec)
        self.charts = joint_charts(*DEFAULT_CHART_RANGES)
        log_chart_frames(self.rec, self.charts)
        self.body_weight_n: float | None = None
        self._wrench: list = []
        self._markers: list = []
        self._kinetics: list = []
        self._last_kinetics: tuple[int, int] | None = None  # (stance index, last stamp ns)
        self._profiles: dict[int, dict] = {}
        self._summaries: dict[int, StanceSummary] = {}
        self.stances_logged = 0
        self.create_subscription(WrenchStamped, FORCE_TOPIC, self._wrench.append, input_qos(reliable))
        self.create_subscription(MarkerArray, MARKER_TOPIC, self._markers.append, input_qos(reliable))
        self.create_subscription(SubjectInfo, SUBJECT_TOPIC, self._on_subject, latched_qos())
        self.create_subscription(StanceEvent, EVENTS_TOPIC, self.on_event, result_qos())
        self.create_subscription(JointKinetics, JOINT_KINETICS_TOPIC, self._kinetics.append, result_qos(2000))
        self.create_subscription(ImpedanceProfile, PROFILE_TOPIC, self.on_profile, result_qos())
        self.create_subscription(StanceSummary, SUMMARY_TOPIC, self.on_summary, result_qos())
        self.create_timer(period, self.flush)

    # -- callbacks ---------------------------------------------------------
    def _on_subject(self, msg) -> None:
        self.body_weight_n = msg.body_mass * GRAVITY_M_S2

    def _zero(self, ns: int) -> int:
        if not self.start_ns:
            self.start_ns = int(ns)
        return self.start_ns

    def on_event(self, msg) -> None:
        """Touchdown -> stance mark 1, take-off -> 0, at the event's own stamp."""
        t0 = self._zero(stamp_ns(msg.event_stamp))
        log_stance_event(self.rec, (stamp_ns(msg.event_stamp) - t0) * 1e-9, msg.event_type == StanceEvent.TOUCHDOWN)

    def on_profile(self, msg) -> None:
        """Keep the joint's profile until the stance's summary (and all three joints) are in."""
        self._profiles.setdefault(int(msg.stance_index), {})[msg.joint] = msg
        self._try_stance(int(msg.stance_index))

    def on_summary(self, msg) -> None:
        """Keep the summary; log the stance once its profiles are in (or it was rejected)."""
        self._summaries[int(msg.stance_index)] = msg
        self._try_stance(int(msg.stance_index))

    def _try_stance(self, k: int) -> None:
        summary = self._summaries.get(k)
        profiles = self._profiles.get(k, {})
        if summary is None or (not summary.rejection_reason and len(profiles) < len(JOINT_NAMES)):
            return
        t0 = self._zero(stamp_ns(summary.touchdown_stamp))
        self._end_kinetics(k, t0)
        log_stance(self.rec, stance_view_from_summary(summary, profiles, t0), self.charts)
        self._summaries.pop(k)
        self._profiles.pop(k, None)
        self.stances_logged += 1

    # -- columnar flush ----------------------------------------------------
    def flush(self) -> None:
        """Send everything buffered, one columnar call per entity."""
        if self._wrench and self.body_weight_n:
            msgs, self._wrench[:] = list(self._wrench), []
            ns, force, torque = wrench_block(msgs)
            t0 = self._zero(ns.min())
            log_ground_reaction(self.rec, (ns - t0) * 1e-9, force[:, [0, 2]], cop_x_from_wrench(force, torque),
                                self.body_weight_n)
        if self._markers:
            msgs, self._markers[:] = list(self._markers), []
            ns = np.array([stamp_ns(m.header.stamp) for m in msgs], np.int64)
            t0 = self._zero(ns.min())
            log_body(self.rec, (ns - t0) * 1e-9, np.stack([marker_frame_xz(m) for m in msgs]))
        if self._kinetics:
            msgs, self._kinetics[:] = list(self._kinetics), []
            self._log_kinetics(kinetics_block(msgs))

    def _log_kinetics(self, block: dict) -> None:
        """Log per stance; a NaN sample after each finished stance keeps flights blank."""
        t0 = self._zero(block["stamp_ns"].min())
        if self._last_kinetics and self._last_kinetics[0] != block["stance"][0]:
            self._break_line(self._last_kinetics[1], t0)
        cuts = np.flatnonzero(np.diff(block["stance"])) + 1
        parts = np.split(np.arange(len(block["stance"])), cuts)
        for i, part in enumerate(parts):
            log_joint_series(
                self.rec,
                (block["stamp_ns"][part] - t0) * 1e-9,
                block["angle_rad"][part],
                block["angular_velocity_rad_s"][part],
                block["moment_nm"][part],
                block["power_w"][part],
                end_of_stance=i < len(parts) - 1,
            )
        self._last_kinetics = (int(block["stance"][-1]), int(block["stamp_ns"][-1]))

    def _end_kinetics(self, k: int, t0: int) -> None:
        """Stance ``k`` is complete: log its buffered frames and the line break after them."""
        if self._kinetics:
            msgs, self._kinetics[:] = list(self._kinetics), []
            self._log_kinetics(kinetics_block(msgs))
        if self._last_kinetics and self._last_kinetics[0] == k:
            self._break_line(self._last_kinetics[1], t0)
            self._last_kinetics = None

    def _break_line(self, last_ns: int, t0: int) -> None:
        nan = np.full((1, 3), np.nan)
        log_joint_series(self.rec, np.array([(last_ns - t0) * 1e-9 + 1e-3]), nan, nan, nan, nan, end_of_stance=False)

    def close(self) -> None:
        """Flush what is buffered and close the Rerun sinks."""
        self.flush()
        self.rec.flush()
        self.rec.disconnect()

    def destroy_node(self) -> None:
        """Close the Rerun sinks, then destroy the node."""
        self.close()
        super().destroy_node()


def main(args=None) -> None:
    """``ros2 run``-style entry point."""
    from hop_impedance.nodes.common import spin_node

    spin_node(RerunBridge, args)


if __name__ == "__main__":
    main()
