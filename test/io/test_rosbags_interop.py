"""Our MCAP reader and writer checked against an independent implementation (``rosbags``)."""

from pathlib import Path

import numpy as np
import pytest

from hop_impedance.io.message_definitions import msg_file_text
from hop_impedance.io.recording_io import load_recording, save_recording
from hop_impedance.recording import FORCE_TOPIC, MARKER_NAMES, MARKER_TOPIC, SUBJECT_TOPIC

rosbags = pytest.importorskip("rosbags", reason="rosbags is a test dependency (requirements/test.txt)")
from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from test.io.test_mcap_recordings import make_recording  # noqa: E402


def typestore_with_ours():
    store = get_typestore(Stores.ROS2_KILTED)
    types = {}
    for name in ("MarkerArray", "SubjectInfo"):
        full = f"hop_impedance_msgs/msg/{name}"
        types.update(get_types_from_msg(msg_file_text(full), full))
    store.register(types)
    return store


def _time(store, ns):
    Time = store.types["builtin_interfaces/msg/Time"]
    return Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9))


def write_with_rosbags(bag_dir: Path, rec) -> None:
    store = typestore_with_ours()
    T = store.types
    Header, Vector3, Wrench, WrenchStamped = (T[f"{p}"] for p in (
        "std_msgs/msg/Header", "geometry_msgs/msg/Vector3", "geometry_msgs/msg/Wrench", "geometry_msgs/msg/WrenchStamped"))
    Point, MarkerArray, SubjectInfo = (T[p] for p in (
        "geometry_msgs/msg/Point", "hop_impedance_msgs/msg/MarkerArray", "hop_impedance_msgs/msg/SubjectInfo"))
    with Writer(bag_dir, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c_sub = w.add_connection(SUBJECT_TOPIC, SubjectInfo.__msgtype__, typestore=store)
        c_f = w.add_connection(FORCE_TOPIC, WrenchStamped.__msgtype__, typestore=store)
        c_m = w.add_connection(MARKER_TOPIC, MarkerArray.__msgtype__, typestore=store)
        s = rec.subject
        t0 = rec.start_ns
        msg = SubjectInfo(header=Header(stamp=_time(store, t0), frame_id="lab"), subject_id=s.subject_id,
                          body_mass=s.body_mass_kg, body_height=s.body_height_m)
        w.write(c_sub, t0, store.serialize_cdr(msg, SubjectInfo.__msgtype__))
        f = rec.force
        for i, t in enumerate(f.stamp_ns):
            fx, fy, fz = map(float, f.force_n[i])
            tx, ty, tz = map(float, f.torque_nm[i])
            msg = WrenchStamped(header=Header(stamp=_time(store, t), frame_id="force_plate"),
                                wrench=Wrench(force=Vector3(x=fx, y=fy, z=fz), torque=Vector3(x=tx, y=ty, z=tz)))
            w.write(c_f, int(t), store.serialize_cdr(msg, WrenchStamped.__msgtype__))
        m = rec.markers
        for i, t in enumerate(m.stamp_ns):
            pts = [Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in m.positions_m[i]]
            msg = MarkerArray(header=Header(stamp=_time(store, t), frame_id="lab"), names=list(m.names), positions=pts)
            w.write(c_m, int(t), store.serialize_cdr(msg, MarkerArray.__msgtype__))


def test_we_read_a_rosbag2_mcap_written_by_rosbags(tmp_path):
    rec = make_recording(seconds=1.0, seed=3)
    bag = tmp_path / "bag"
    write_with_rosbags(bag, rec)
    back = load_recording(bag)  # the rosbag2 folder (metadata.yaml + .mcap)
    np.testing.assert_array_equal(back.force.stamp_ns, rec.force.stamp_ns)
    np.testing.assert_array_equal(back.force.force_n, rec.force.force_n)
    np.testing.assert_array_equal(back.force.torque_nm, rec.force.torque_nm)
    np.testing.assert_array_equal(back.markers.positions_m, rec.markers.positions_m)
    assert back.subject == rec.subject


def test_rosbags_reads_what_we_write(tmp_path):
    rec = make_recording(seconds=0.5, seed=4)
    path = tmp_path / "ours.mcap"
    save_recording(path, rec)
    store = typestore_with_ours()
    fz, names = [], None
    with AnyReader([path], default_typestore=store) as reader:
        topics = {c.topic for c in reader.connections}
        assert topics == {FORCE_TOPIC, MARKER_TOPIC, SUBJECT_TOPIC}
        for conn, _, raw in reader.messages(connections=reader.connections):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == FORCE_TOPIC:
                fz.append(msg.wrench.force.z)
            elif conn.topic == MARKER_TOPIC and names is None:
                names = list(msg.names)
            elif conn.topic == SUBJECT_TOPIC:
                assert msg.body_mass == pytest.approx(54.8)
    np.testing.assert_array_equal(np.array(fz), rec.force.force_n[:, 2])
    assert tuple(names) == MARKER_NAMES
