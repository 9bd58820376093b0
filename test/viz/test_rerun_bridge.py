"""The live bridge, fed the messages the pipeline publishes, logs what the offline view logs.

Messages are built with the pipeline's own builders (inverse_dynamics and
impedance_estimator) from the offline analysis of a bundled recording and
handed to the bridge's subscription callbacks in stamp order, with columnar
flushes in between as the timer would do. No DDS traffic: transport is the
pipeline's tests' business.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.viz import style as S

from .readback import column, load_store, scalars

rclpy = pytest.importorskip("rclpy")
msgs = pytest.importorskip("hop_impedance_msgs.msg")


def _sensor_messages(rec):
    from geometry_msgs.msg import Point, WrenchStamped

    def stamp(header, ns):
        header.stamp.sec, header.stamp.nanosec = divmod(int(ns), 1_000_000_000)

    subject = msgs.SubjectInfo(subject_id=rec.subject.subject_id, body_mass=rec.subject.body_mass_kg,
                               body_height=rec.subject.body_height_m)
    wrenches = []
    for ns, f, tq in zip(rec.force.stamp_ns, rec.force.force_n, rec.force.torque_nm):
        m = WrenchStamped()
        stamp(m.header, ns)
        m.wrench.force.x, m.wrench.force.y, m.wrench.force.z = map(float, f)
        m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z = map(float, tq)
        wrenches.append(m)
    frames = []
    for ns, pos in zip(rec.markers.stamp_ns, rec.markers.positions_m):
        m = msgs.MarkerArray(names=list(rec.markers.names),
                             positions=[Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in pos])
        stamp(m.header, ns)
        frames.append(m)
    return subject, wrenches, frames


@pytest.fixture(scope="module")
def bridge_rrd(tmp_path_factory, analysed):
    from rclpy.parameter import Parameter

    from hop_impedance.nodes.impedance_estimator import profile_message, summary_message
    from hop_impedance.nodes.inverse_dynamics import frame_messages, stance_message
    from hop_impedance.nodes.rerun_bridge import RerunBridge

    rec, analysis, fits = analysed
    out = tmp_path_factory.mktemp("bridge") / "live.rrd"
    subject, wrenches, frames = _sensor_messages(rec)
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        bridge = RerunBridge(
            context=context,
            parameter_overrides=[Parameter("save_path", value=str(out)), Parameter("start_ns", value=int(analysis.start_ns))],
        )
        bridge._on_subject(subject)
        for k in range(0, len(wrenches), 100):  # 0.1 s of force per timer tick
            bridge._wrench.extend(wrenches[k : k + 100])
            bridge._markers.extend(frames[k // 10 : k // 10 + 10])
            bridge.flush()
        for res, fit in zip(analysis.stances, fits):
            sk = stance_message(res, analysis.start_ns)
            ev = msgs.StanceEvent(event_type=msgs.StanceEvent.TOUCHDOWN, stance_index=res.index)
            ev.event_stamp = sk.touchdown_stamp if hasattr(sk, "touchdown_stamp") else sk.header.stamp
            bridge.on_event(ev)
            bridge._kinetics.extend(frame_messages(res, analysis.start_ns))
            bridge.flush()
            bridge.on_summary(summary_message(sk, fit))
            for joint in JOINT_NAMES:
                bridge.on_profile(profile_message(sk, joint, fit[joint], 0.0))
        logged = bridge.stances_logged
        bridge.destroy_node()
    finally:
        rclpy.shutdown(context=context)
    return out, logged


def test_bridge_logs_every_stance_once(bridge_rrd, analysed):
    out, logged = bridge_rrd
    n = len(analysed[1].stances)
    assert logged == n
    store = load_store(out)
    seq, tables = column(store, S.STANCE_TIMELINE, "/" + S.TABLE, "TextDocument:text")
    assert list(seq) == list(range(n))
    assert all(t[0].startswith(f"### Stance {k}:") for k, t in enumerate(tables))


def test_bridge_matches_the_offline_view(bridge_rrd, rrd):
    live, offline = load_store(bridge_rrd[0]), load_store(rrd[0])
    for entity in ("/" + S.GRF_BW, f"/{S.ANGLE}/knee", "/" + S.moment_path("ankle", "inverse_dynamics"), f"/{S.TREND}/k0/hip"):
        timeline = S.STANCE_TIMELINE if entity.startswith("/trend") else S.TIMELINE
        t_live, v_live = scalars(live, timeline, entity)
        t_off, v_off = scalars(offline, timeline, entity)
        assert len(v_live) == len(v_off), entity
        np.testing.assert_allclose(t_live, t_off, atol=2e-9, err_msg=entity)
        np.testing.assert_allclose(v_live, v_off, rtol=1e-9, atol=1e-9, equal_nan=True, err_msg=entity)
    _, m_live = column(live, S.TIMELINE, "/" + S.MARKERS, "Points2D:positions")
    _, m_off = column(offline, S.TIMELINE, "/" + S.MARKERS, "Points2D:positions")
    assert m_live == m_off
