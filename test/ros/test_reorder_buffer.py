"""The nodes' reorder buffer: in-order samples pass at once, a hole holds what follows it (issue 15 latency)."""

from hop_impedance.nodes.common import ReorderBuffer

MS = 1_000_000


def _fill(buf, stamps):
    for ns in stamps:
        buf.add(ns, ns)


def test_in_order_samples_wait_for_the_window_only_until_the_period_is_known():
    buf = ReorderBuffer(20 * MS)
    _fill(buf, [i * MS for i in range(30)])
    assert [x[0] for x in buf.release()] == [i * MS for i in range(10)]  # newest - 20 ms
    assert buf.period_ns is None
    _fill(buf, [i * MS for i in range(30, 80)])
    out = buf.release()
    assert buf.period_ns == MS  # 50 released steps of 1 ms
    # once the period is known, every contiguous sample is released, none waits for the window
    assert out[-1][0] == 79 * MS
    buf.add(80 * MS, None)
    assert [x[0] for x in buf.release()] == [80 * MS]


def test_a_hole_holds_the_samples_behind_it_until_filled_or_the_window_passes():
    buf = ReorderBuffer(20 * MS)
    _fill(buf, [i * MS for i in range(80)])
    assert buf.release()[-1][0] == 79 * MS and buf.period_ns == MS
    _fill(buf, [81 * MS, 82 * MS])  # 80 late
    assert buf.release() == []
    buf.add(80 * MS, None)
    assert [x[0] for x in buf.release()] == [80 * MS, 81 * MS, 82 * MS]  # sorted, at once
    _fill(buf, [84 * MS + i * MS for i in range(20)])  # 83 lost: waits until 20 ms of newer stamps
    assert buf.release() == []
    buf.add(104 * MS, None)
    assert [x[0] for x in buf.release()] == [84 * MS + i * MS for i in range(21)]
    assert not buf.add(83 * MS, None) and buf.dropped == 1  # too late now
