"""``mocap4r2_adapter``: mocap4r2 drivers' ``mocap4r2_msgs/msg/Markers`` -> the contract's ``MarkerArray``.

Labs running ROS 2 motion capture use the MOCAP4ROS2 drivers (Vicon,
OptiTrack, Qualisys, ...), which publish every frame's markers as
``mocap4r2_msgs/msg/Markers``. This node picks the contract's markers out of
each frame and publishes ``hop_impedance_msgs/msg/MarkerArray`` on
``/mocap/markers`` (names ``toe, heel, ankle, knee, hip, head`` in that order,
lab frame, m; a marker absent from the frame is NaN, the contract's
"occluded"). Same stamp as the input frame; ``frame_id = "lab"``.

Which marker is which (``config/mocap4r2_markers.yaml``), per marker:

- when its ``id_type`` is ``USE_NAME`` or ``USE_BOTH`` (the driver set the
  name) and the name is not empty, by name: ``marker_labels[i]`` is the
  label of contract marker ``marker_names[i]`` (exact match first, then
  ignoring case);
- otherwise (``USE_INDEX``, or an empty name, as older drivers that carried
  only an index send), by index: ``marker_indices[i]`` is the index of
  contract marker ``marker_names[i]``.

A contract marker seen twice in one frame keeps the first and counts a
duplicate; markers matching no contract marker are ignored (a full-body set
has dozens). Counted on ``/diagnostics``: frames in and out, frames with
each contract marker missing, duplicates.

Parameters
----------
input_topic : str
    The driver's Markers topic (``ros2 topic list -t`` shows it).
output_topic : str
    Default ``/mocap/markers``.
marker_names, marker_labels, marker_indices : lists
    Contract marker, its label, its index (same length; a label of ``""``
    or an index of -1 means "not identified that way").
origin_m : list of 3 float
    Subtracted from every position: the lab point that is the contract
    origin (give the plate_combiner the same ``origin_m``).
reliable_inputs : bool
    Default false: a best-effort subscription matches both reliable and
    best-effort drivers.
diagnostics_period_s : float
"""

from __future__ import annotations

import math

from geometry_msgs.msg import Point
from hop_impedance_msgs.msg import MarkerArray
from rclpy.node import Node

from hop_impedance.io.recording_io import LAB_FRAME_ID
from hop_impedance.nodes.common import Diagnostics, InputTracker, declare, stamp_ns
from hop_impedance.nodes.qos import input_qos
from hop_impedance.recording import MARKER_NAMES, MARKER_TOPIC

# mypy finds the repository's mocap4r2_msgs/ (the .msg definitions) as a namespace package before the generated one
from mocap4r2_msgs.msg import Marker, Markers  # type: ignore[attr-defined]


class MarkerIdentities:
    """Contract marker of a mocap4r2 marker, by name or by index (see the module docstring).

    Parameters
    ----------
    names, labels, indices : sequences of equal length
        Contract marker ``names[i]`` has lab label ``labels[i]`` (``""``:
        none) and driver index ``indices[i]`` (-1: none).
    """

    def __init__(self, names, labels, indices) -> None:
        names, labels, indices = list(names), list(labels), [int(i) for i in indices]
        if not (len(names) == len(labels) == len(indices)):
            raise ValueError(f"mocap4r2_adapter: marker_names ({len(names)}), marker_labels ({len(labels)}) and "
                             f"marker_indices ({len(indices)}) must have the same length")
        unknown = sorted(set(names) - set(MARKER_NAMES))
        if unknown:
            raise ValueError(f"mocap4r2_adapter: marker_names {unknown} are not contract markers {list(MARKER_NAMES)}")
        if len(set(names)) != len(names):
            raise ValueError("mocap4r2_adapter: a contract marker is listed twice in marker_names")
        missing = [n for n, lab, i in zip(names, labels, indices) if not lab and i < 0]
        if missing:
            raise ValueError(f"mocap4r2_adapter: {missing} have neither a label nor an index")
        slot = {n: MARKER_NAMES.index(n) for n in names}
        self.by_label = {lab: slot[n] for n, lab in zip(names, labels) if lab}
        self.by_label_folded = {lab.casefold(): s for lab, s in self.by_label.items()}
        self.by_index = {i: slot[n] for n, i in zip(names, indices) if i >= 0}

    def slot(self, marker) -> int | None:
        """Column in :data:`MARKER_NAMES` of a ``mocap4r2_msgs/Marker``, or None when it is none of ours."""
        if marker.id_type in (Marker.USE_NAME, Marker.USE_BOTH) and marker.marker_name:
            s = self.by_label.get(marker.marker_name)
            return s if s is not None else self.by_label_folded.get(marker.marker_name.casefold())
        return self.by_index.get(marker.marker_index)


class Mocap4r2AdapterNode(Node):
    """Republishes mocap4r2 marker frames as contract MarkerArrays; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("mocap4r2_adapter", **kwargs)
        self.input_topic = declare(self, "input_topic", "/markers", "mocap4r2_msgs/msg/Markers topic of the driver")
        self.output_topic = declare(self, "output_topic", MARKER_TOPIC, "contract MarkerArray topic")
        names = declare(self, "marker_names", list(MARKER_NAMES), "contract marker of each entry")
        labels = declare(self, "marker_labels", list(MARKER_NAMES),
                         "lab label of each entry, used when the driver sets names ('' = none)")
        indices = declare(self, "marker_indices", list(range(len(MARKER_NAMES))),
                          "driver index of each entry, used otherwise (-1 = none)")
        origin = list(declare(self, "origin_m", [0.0, 0.0, 0.0],
                              "lab point subtracted from every position: the contract origin (m)"))
        reliable = declare(self, "reliable_inputs", False, "true: reliable subscription; false (default) matches every driver")
        diag = declare(self, "diagnostics_period_s", 1.0, "publish /diagnostics this often (s); 0 = never")
        if len(origin) != 3:
            raise ValueError(f"mocap4r2_adapter: origin_m needs 3 values, got {len(origin)}")
        self.identities = MarkerIdentities(names, labels, indices)
        self.origin = origin
        self.tracker = InputTracker(self.input_topic)
        self.frames_out = 0
        self.missing = [0] * len(MARKER_NAMES)
        self.duplicates = 0
        self.pub = self.create_publisher(MarkerArray, self.output_topic, input_qos(True))
        self.create_subscription(Markers, self.input_topic, self._on_markers, input_qos(reliable))
        self.diagnostics = Diagnostics(self, diag, self._diag_values, self._diag_level)

    def _on_markers(self, frame: Markers) -> None:
        self.tracker.note(stamp_ns(frame.header.stamp))
        nan = math.nan
        positions: list[Point | None] = [None] * len(MARKER_NAMES)
        ox, oy, oz = self.origin
        for m in frame.markers:
            s = self.identities.slot(m)
            if s is None:
                continue
            if positions[s] is not None:
                self.duplicates += 1
                continue
            t = m.translation
            positions[s] = Point(x=t.x - ox, y=t.y - oy, z=t.z - oz)
        for s, p in enumerate(positions):
            if p is None:
                self.missing[s] += 1
                positions[s] = Point(x=nan, y=nan, z=nan)
        out = MarkerArray(names=list(MARKER_NAMES), positions=positions)
        out.header.stamp = frame.header.stamp
        out.header.frame_id = LAB_FRAME_ID
        self.pub.publish(out)
        self.frames_out += 1
        self.diagnostics.sample_ns = self.tracker.newest_ns or 0

    def _diag_level(self) -> tuple[int, str]:
        if self.tracker.received == 0:
            return 1, f"no frame on {self.input_topic} yet"
        never = [n for n, k in zip(MARKER_NAMES, self.missing) if k == self.frames_out]
        if never:
            return 2, "never identified: " + ", ".join(never) + " (check marker_labels / marker_indices)"
        return 0, "ok"

    def _diag_values(self) -> dict:
        t = self.tracker
        out = {"frames_received": t.received, "frames_published": self.frames_out, "frames_lost": t.lost,
               "frames_out_of_order": t.late, "duplicate_markers": self.duplicates, "rate_hz": t.rate_hz}
        out.update({f"{n}_missing_frames": k for n, k in zip(MARKER_NAMES, self.missing)})
        return out


def main(args=None) -> None:
    """Run the node (``mocap4r2_adapter --ros-args --params-file config/mocap4r2_markers.yaml``)."""
    from hop_impedance.nodes.common import spin_node

    spin_node(Mocap4r2AdapterNode, args)


if __name__ == "__main__":
    main()
