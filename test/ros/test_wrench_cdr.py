"""The raw 1 kHz force parser equals rclpy's own (de)serialisation for every frame_id padding case."""

import struct

import numpy as np
import pytest

pytest.importorskip("rclpy")
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402

from hop_impedance.nodes.common import wrench_from_cdr  # noqa: E402


@pytest.mark.parametrize("frame_id", ["", "f", "plate", "force_plate", "force_plate_0", "a" * 8])
def test_wrench_from_cdr_matches_rclpy_serialisation(frame_id):
    rng = np.random.default_rng(7)
    m = WrenchStamped()
    m.header.stamp.sec, m.header.stamp.nanosec = 1_700_000_123, 987_654_321
    m.header.frame_id = frame_id
    values = rng.normal(0, 500, 6)
    (m.wrench.force.x, m.wrench.force.y, m.wrench.force.z,
     m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z) = values.tolist()
    ns, parsed = wrench_from_cdr(serialize_message(m))
    assert ns == 1_700_000_123 * 1_000_000_000 + 987_654_321
    assert parsed == tuple(values.tolist())  # bit-exact


def test_wrench_from_cdr_big_endian():
    # hand-encoded big endian (encapsulation 00 00): stamp, "fp\0" (len 3) ends at 15 bytes after the
    # encapsulation, 1 byte pads to 16, then six doubles
    body = struct.pack(">iII", 5, 6, 3) + b"fp\x00" + b"\x00" + struct.pack(">6d", 1, 2, 3, 4, 5, 6)
    ns, parsed = wrench_from_cdr(b"\x00\x00\x00\x00" + body)
    assert ns == 5_000_000_006 and parsed == (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)


def test_layout_check_at_start_up(monkeypatch):
    """Issue 20: the nodes subscribe raw through ``raw_wrench_subscription``, which first checks the parser
    against rclpy's serialisation of this installation's message: it passes here, and a parser that has the
    layout wrong (no padding after frame_id) fails it loudly instead of reading wrong forces."""
    import struct

    from hop_impedance.nodes import common

    common.check_wrench_layout.__wrapped__()  # this installation: no error

    def unpadded(cdr: bytes):
        sec, nsec, n = struct.unpack_from("<iII", cdr, 4)
        return sec * 1_000_000_000 + nsec, struct.unpack_from("<6d", cdr, 16 + n)

    monkeypatch.setattr(common, "wrench_from_cdr", unpadded)
    with pytest.raises(RuntimeError, match="WrenchStamped is not laid out as wrench_from_cdr reads it"):
        common.check_wrench_layout.__wrapped__()
