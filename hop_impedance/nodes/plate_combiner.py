"""``plate_combiner``: N force-plate wrench topics -> the contract's one ``/force_plate/wrench``.

Labs with one plate per foot publish one ``geometry_msgs/WrenchStamped`` per
plate (each in its own axes, moment about its own origin). This node is a thin
adapter around :class:`hop_impedance.biomech.plate_combining.PlateCombinerStage`:
each plate topic goes through a reorder buffer (``reorder_window_s`` of stamp
time), the stage pairs the plates' samples (skew locked from the first pair
within ``max_skew_s``, then ``jitter_s``), carries every moment to
``origin_m`` and the node publishes the sum on ``output_topic`` with
``frame_id = "force_plate"`` and the first plate's stamp.

A missing plate is never summed as zero: an instant some plate lacks is not
published (downstream counts it as lost samples) and is counted per plate
(``<plate>_missing`` on ``/diagnostics``); a plate that has sent nothing, or
lags the others by more than ``missing_after_s``, turns the node's diagnostic
status to ERROR naming it.

Parameters (``config/plates.yaml``)
-----------------------------------
plate_topics : list of str
    One ``WrenchStamped`` topic per plate; the first is the reference plate
    (its stamps are the output's).
plate_names : list of str
    A label per plate for diagnostics (default: the topics' last parts).
plate_origins_m : list of float
    x, y, z of each plate's origin (the point its moment is about) in the
    lab frame, 3 per plate (m).
plate_yaw_deg : list of float
    Rotation of each plate's axes about the vertical (deg), one per plate.
origin_m : list of 3 float
    Lab-frame point the combined moment is about: the contract frame's
    origin (the mocap4r2 adapter shifts the markers by the same point).
max_skew_s, jitter_s, missing_after_s : float
    Stamp skew accepted when locking a plate, per-sample tolerance after
    that, and how far (stamp time) the other plates may run ahead of a
    missing one before its instants are dropped (s).
output_topic : str
    Default ``/force_plate/wrench``.
reliable_inputs, reorder_window_s, process_period_s, diagnostics_period_s
    As every stream consumer (``nodes/common.py``).
"""

from __future__ import annotations

import time

from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node
from std_msgs.msg import Header

from hop_impedance.biomech.plate_combining import PlateCombinerStage, PlateLayout
from hop_impedance.io.recording_io import FORCE_FRAME_ID
from hop_impedance.nodes.common import (
    END_TOPIC,
    Diagnostics,
    InputTracker,
    ReorderBuffer,
    declare,
    declare_stream_parameters,
    raw_wrench_subscription,
    set_stamp,
    stamp_ns,
    wrench_from_cdr,
)
from hop_impedance.nodes.qos import input_qos, latched_qos
from hop_impedance.recording import FORCE_TOPIC


def plate_layouts(topics: list[str], names: list[str], origins: list[float], yaws: list[float]) -> list[PlateLayout]:
    """Parameters -> layouts; ValueError with a one-line message when the lists do not match."""
    p = len(topics)
    if p < 1 or any(not t for t in topics):
        raise ValueError("plate_combiner: 'plate_topics' must name at least one topic")
    names = list(names) if any(names) else [t.rstrip("/").rsplit("/", 1)[-1] for t in topics]
    if len(names) != p:
        raise ValueError(f"plate_combiner: {len(names)} plate_names for {p} plate_topics")
    if len(origins) != 3 * p:
        raise ValueError(f"plate_combiner: plate_origins_m needs 3 values per plate ({3 * p}), got {len(origins)}")
    yaws = list(yaws) if len(yaws) else [0.0] * p
    if len(yaws) != p:
        raise ValueError(f"plate_combiner: {len(yaws)} plate_yaw_deg for {p} plate_topics")
    xyz = [(float(origins[3 * i]), float(origins[3 * i + 1]), float(origins[3 * i + 2])) for i in range(p)]
    return [PlateLayout(n, xyz[i], float(y)) for i, (n, y) in enumerate(zip(names, yaws))]


class PlateCombinerNode(Node):
    """Sums plate wrench topics into the contract's one wrench; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("plate_combiner", **kwargs)
        reliable, reorder_s, period, diag = declare_stream_parameters(self, "the combiner")
        topics = list(declare(self, "plate_topics", ["/force_plate/left", "/force_plate/right"],
                              "one WrenchStamped topic per plate; the first is the reference"))
        names = list(declare(self, "plate_names", [""], "label per plate for diagnostics (default: topic's last part)"))
        origins = list(declare(self, "plate_origins_m", [0.0] * 6,
                               "x, y, z of each plate's origin in the lab frame, 3 per plate (m)"))
        yaws = list(declare(self, "plate_yaw_deg", [0.0, 0.0], "rotation of each plate's axes about the vertical (deg)"))
        origin = list(declare(self, "origin_m", [0.0, 0.0, 0.0],
                              "lab point the combined moment is about: the contract frame's origin (m)"))
        max_skew = declare(self, "max_skew_s", 0.0006, "largest stamp skew between plates accepted when locking (s)")
        jitter = declare(self, "jitter_s", 0.0002, "per-sample stamp tolerance after the skew is locked (s)")
        wait = declare(self, "missing_after_s", 0.5, "drop an instant a plate lacks once the others run this far ahead (s)")
        self.output_topic = declare(self, "output_topic", FORCE_TOPIC, "combined wrench topic")
        self.end_timeout_s = declare(self, "end_timeout_s", 1.0, "after end-of-stream, wait this long (s) for missing data; "
                                     "shorter than the consumers' (3 s) so the last samples reach them first")
        if len(origin) != 3:
            raise ValueError(f"plate_combiner: origin_m needs 3 values, got {len(origin)}")
        self.layouts = plate_layouts(topics, names, origins, yaws)
        self.topics = topics
        self.stage = PlateCombinerStage(self.layouts, origin, int(max_skew * 1e9), int(jitter * 1e9), int(wait * 1e9))
        self.buffers: list[ReorderBuffer[tuple[float, ...]]] = [ReorderBuffer(int(reorder_s * 1e9)) for _ in topics]
        self.trackers = [InputTracker(t) for t in topics]
        self.published = 0
        self.pub = self.create_publisher(WrenchStamped, self.output_topic, input_qos(reliable))
        for k, topic in enumerate(topics):
            raw_wrench_subscription(self, topic, self._callback(k), input_qos(reliable))
        self.create_subscription(Header, END_TOPIC, self._on_end, latched_qos())
        self.diagnostics = Diagnostics(self, diag, self._diag_values, self._diag_level)
        self._end: tuple[int, float] | None = None
        self._finished = False
        self.create_timer(period, self._tick)

    def _callback(self, k: int):
        def on_wrench(cdr: bytes) -> None:
            ns, values = wrench_from_cdr(cdr)
            self.trackers[k].note(ns)
            self.buffers[k].add(ns, values)
        return on_wrench

    def _tick(self) -> None:
        self.process()
        self._check_end()

    def process(self, everything: bool = False) -> None:
        """Push released samples of every plate into the stage and publish what it completes.

        A plate whose newest stamp is a reorder window behind the newest of all
        has stopped (or lags): its buffered tail is released at once, so the
        stage pairs it before it gives up on that plate's later instants.
        """
        newest = max((t.newest_ns or 0) for t in self.trackers)
        for k, buf in enumerate(self.buffers):
            own = self.trackers[k].newest_ns
            items = buf.release(everything or (own is not None and newest - own > buf.window_ns))
            if items:
                self._publish(*self.stage.push(k, [i[0] for i in items], [i[1] for i in items]))
        if everything:
            self._publish(*self.stage.flush())

    def _publish(self, stamps, force, moment) -> None:
        for ns, f, m in zip(stamps.tolist(), force.tolist(), moment.tolist()):
            msg = WrenchStamped()
            set_stamp(msg.header.stamp, ns)
            msg.header.frame_id = FORCE_FRAME_ID
            w = msg.wrench
            w.force.x, w.force.y, w.force.z = f
            w.torque.x, w.torque.y, w.torque.z = m
            self.pub.publish(msg)
            self.diagnostics.sample_ns = ns
        self.published += len(stamps)

    def _on_end(self, msg: Header) -> None:
        """End of a replayed stream: flush once every plate has data up to its stamp (or after ``end_timeout_s``).

        The end stamp is the newest of every played topic, so a plate stamped
        earlier by its skew counts as complete within ``max_skew_s`` of it.
        """
        self._end = (stamp_ns(msg.stamp), time.monotonic() + self.end_timeout_s)

    def _check_end(self) -> None:
        if self._end is None or self._finished:
            return
        end_ns, deadline = self._end
        if all((t.newest_ns or 0) + self.stage.max_skew_ns >= end_ns for t in self.trackers) or time.monotonic() > deadline:
            self.process(everything=True)
            self._finished = True
            self.diagnostics.publish()

    def _diag_level(self) -> tuple[int, str]:
        silent = self.stage.silent_plates()
        if all(n is None for n in self.stage.newest_ns):
            return 1, "no plate has sent anything yet"
        if silent:
            return 2, "plate(s) missing: " + ", ".join(silent) + " (their instants are not published)"
        if any(self.stage.missing):
            return 1, f"{self.stage.dropped} instants dropped for a missing plate sample"
        return 0, "ok"

    def _diag_values(self) -> dict:
        # readers: subscriptions matched to the combined output at this node's own participant (a downstream
        # node that is not yet matched misses the start of the stream; tests wait for it before replaying)
        out: dict[str, object] = {"published": self.published, "instants_dropped": self.stage.dropped,
                                  "readers": self.pub.get_subscription_count()}
        for lay, t, buf, missing, skew in zip(self.layouts, self.trackers, self.buffers, self.stage.missing, self.stage.skew_ns):
            out[f"{lay.name}_received"] = t.received
            out[f"{lay.name}_rate_hz"] = t.rate_hz
            out[f"{lay.name}_lost"] = t.lost
            out[f"{lay.name}_late_dropped"] = buf.dropped
            out[f"{lay.name}_missing"] = missing
            out[f"{lay.name}_skew_ms"] = float("nan") if skew is None else skew * 1e-6
        return out


def main(args=None) -> None:
    """Run the node (``plate_combiner --ros-args --params-file config/plates.yaml``)."""
    from hop_impedance.nodes.common import spin_node

    spin_node(PlateCombinerNode, args)


if __name__ == "__main__":
    main()
