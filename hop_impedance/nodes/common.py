"""Shared pieces of the pipeline nodes: parameters, stamps, input bookkeeping, diagnostics, progress.

Topic names of the pipeline (inputs follow shared/contract/RECORDINGS.md):

=============================  ==========================================  =====================
topic                          type                                        publisher
=============================  ==========================================  =====================
``/stance/events``             ``hop_impedance_msgs/msg/StanceEvent``      stance_detector
``/stance/kinetics``           ``hop_impedance_msgs/msg/StanceKinetics``   inverse_dynamics
``/joint_kinetics``            ``hop_impedance_msgs/msg/JointKinetics``    inverse_dynamics
``/impedance/profile``         ``hop_impedance_msgs/msg/ImpedanceProfile`` impedance_estimator
``/impedance/stance_summary``  ``hop_impedance_msgs/msg/StanceSummary``    impedance_estimator
``/impedance/controller``      ``hop_impedance_msgs/msg/ControllerImpedance`` impedance_estimator
``/pipeline/progress``         ``hop_impedance_msgs/msg/Progress``         every input consumer
``/replay/end_of_stream``      ``std_msgs/msg/Header``                     replay
``/diagnostics``               ``diagnostic_msgs/msg/DiagnosticArray``     every node
=============================  ==========================================  =====================
"""

from __future__ import annotations

import array
import functools
import math
import struct
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Generic, TypeVar

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node

from hop_impedance.biomech.stages import NominalPeriod
from hop_impedance.recording import FORCE_TOPIC, MARKER_TOPIC, MARKER_TYPE, SUBJECT_TOPIC, SUBJECT_TYPE, WRENCH_TYPE

EVENTS_TOPIC = "/stance/events"
STANCE_KINETICS_TOPIC = "/stance/kinetics"
JOINT_KINETICS_TOPIC = "/joint_kinetics"
PROFILE_TOPIC = "/impedance/profile"
SUMMARY_TOPIC = "/impedance/stance_summary"
CONTROLLER_TOPIC = "/impedance/controller"
PROGRESS_TOPIC = "/pipeline/progress"
END_TOPIC = "/replay/end_of_stream"
DIAGNOSTICS_TOPIC = "/diagnostics"

#: Every topic of the pipeline and its type (``pkg/msg/Type``), inputs first.
TOPIC_TYPES: dict[str, str] = {
    FORCE_TOPIC: WRENCH_TYPE,
    MARKER_TOPIC: MARKER_TYPE,
    SUBJECT_TOPIC: SUBJECT_TYPE,
    EVENTS_TOPIC: "hop_impedance_msgs/msg/StanceEvent",
    STANCE_KINETICS_TOPIC: "hop_impedance_msgs/msg/StanceKinetics",
    JOINT_KINETICS_TOPIC: "hop_impedance_msgs/msg/JointKinetics",
    PROFILE_TOPIC: "hop_impedance_msgs/msg/ImpedanceProfile",
    SUMMARY_TOPIC: "hop_impedance_msgs/msg/StanceSummary",
    CONTROLLER_TOPIC: "hop_impedance_msgs/msg/ControllerImpedance",
    DIAGNOSTICS_TOPIC: "diagnostic_msgs/msg/DiagnosticArray",
}

#: Topics the pipeline produces (what the recorder writes next to the inputs).
OUTPUT_TOPICS: tuple[str, ...] = (
    EVENTS_TOPIC, STANCE_KINETICS_TOPIC, JOINT_KINETICS_TOPIC, PROFILE_TOPIC, SUMMARY_TOPIC,
    CONTROLLER_TOPIC, DIAGNOSTICS_TOPIC,
)


def declare(node: Node, name: str, default, description: str):
    """Declare a parameter with a description and return its value."""
    return node.declare_parameter(name, default, ParameterDescriptor(description=description)).value


def declare_stream_parameters(node: Node, work: str) -> tuple[bool, float, float, float]:
    """Declare the parameters every sensor-stream consumer shares and return their values.

    Returns ``(reliable_inputs, reorder_window_s, process_period_s,
    diagnostics_period_s)``; ``work`` names what runs every period (for the
    parameter's description), e.g. ``"the detector"``.
    """
    return (
        declare(node, "reliable_inputs", True,
                "match reliable publishers (replay, many mocap drivers); false = sensor-data best effort"),
        declare(node, "reorder_window_s", 0.02, "hold samples this long (stamp time, s) to sort out-of-order arrivals"),
        declare(node, "process_period_s", 0.005, f"run {work} on the buffered samples this often (s)"),
        declare(node, "diagnostics_period_s", 1.0, "publish /diagnostics this often (s); 0 = never"),
    )


def stamp_ns(stamp) -> int:
    """``builtin_interfaces/Time`` -> integer ns."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def header_stamp_ns(cdr: bytes) -> int:
    """``header.stamp`` (ns) of a CDR-serialised message that starts with ``std_msgs/Header``.

    Layout: 4-byte encapsulation (``00 01`` = little endian), then int32 sec,
    uint32 nanosec.
    """
    little = cdr[1] == 1
    sec, nsec = struct.unpack_from("<iI" if little else ">iI", cdr, 4)
    return sec * 1_000_000_000 + nsec


_WRENCH_LE, _WRENCH_BE = struct.Struct("<6d"), struct.Struct(">6d")


def wrench_from_cdr(cdr: bytes) -> tuple[int, tuple[float, float, float, float, float, float]]:
    """``geometry_msgs/WrenchStamped`` CDR bytes -> (stamp ns, (Fx, Fy, Fz, Mx, My, Mz)).

    The 1 kHz force topic is subscribed raw and parsed here: rclpy's
    ``deserialize_message`` builds five Python message objects per sample
    (~65 us measured on this machine, bench/bench_pipeline.py), this takes ~2 us.
    Layout (XCDR1, plain): 4-byte encapsulation (``00 01`` little endian),
    header stamp int32 sec + uint32 nanosec, frame_id as uint32 length
    (including the NUL) + bytes, padding to 8 bytes counted from the end of
    the encapsulation, then six float64: force x, y, z (N), torque x, y, z (N m),
    in the message's frame (contract: force plate frame).
    """
    little = cdr[1] == 1
    sec, nsec, n = struct.unpack_from("<iII" if little else ">iII", cdr, 4)
    pos = 16 + n
    pos += -(pos - 4) % 8
    values = (_WRENCH_LE if little else _WRENCH_BE).unpack_from(cdr, pos)
    return sec * 1_000_000_000 + nsec, values


@functools.cache
def check_wrench_layout() -> None:
    """Fail loudly if :func:`wrench_from_cdr` does not read this installation's ``WrenchStamped`` (issue 20).

    The hand-written parser assumes the message's layout; a changed message
    definition or serialiser would otherwise give wrong forces silently. Once
    per process, rclpy serialises a message with distinct values (a frame_id
    whose length moves the padding) and the parser must read them all back.
    """
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message

    msg = WrenchStamped()
    msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id = 1_700_000_123, 456_789, "plate"
    want = (1.5, -2.25, 3.125, -4.0625, 5.03125, -6.015625)
    (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z,
     msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = want
    got = wrench_from_cdr(serialize_message(msg))
    if got != (1_700_000_123_000_456_789, want):
        raise RuntimeError(f"geometry_msgs/WrenchStamped is not laid out as wrench_from_cdr reads it: wrote "
                           f"{(1_700_000_123_000_456_789, want)}, read {got}; update nodes/common.py")


def raw_wrench_subscription(node: Node, topic: str, callback, qos):
    """Subscribe to a ``WrenchStamped`` topic as raw CDR bytes for :func:`wrench_from_cdr`, its layout checked first."""
    from geometry_msgs.msg import WrenchStamped

    check_wrench_layout()
    return node.create_subscription(WrenchStamped, topic, callback, qos, raw=True)


def set_stamp(stamp, ns: int) -> None:
    """Write integer ns into a ``builtin_interfaces/Time`` (sec, nanosec)."""
    stamp.sec, stamp.nanosec = divmod(int(ns), 1_000_000_000)


def float64_sequence(values) -> array.array:
    """``values`` as the ``array.array('d')`` a ``float64[]`` message field stores.

    Assigning a numpy array makes the generated setter convert and check it element by element:
    setting a stance's five arrays costs 0.111 ms that way, 0.009 ms as ``array.array``;
    serialising either costs 0.01 ms (``bench/bench_path_costs.py``; the stance kinetics are on
    the take-off-to-controller path, issue 15).
    """
    return array.array("d", np.ascontiguousarray(values, dtype=np.float64).ravel().tobytes())


def seconds_to_ns(t0_ns: int, t_s: float) -> int:
    """Stage time (s since ``t0_ns``) -> stamp ns."""
    return int(t0_ns + round(t_s * 1e9))


@dataclass
class InputTracker:
    """Counts what arrived on one input topic: messages, losses, order, rate.

    Losses are inferred from the stamps: a step of more than 1.5 nominal
    periods between consecutive stamps counts ``round(step / period) - 1``
    lost messages (the nominal period is the median of the first 50 steps).
    A stamp older than the newest one already seen is *late* (out of order).
    """

    topic: str
    received: int = 0
    lost: int = 0
    late: int = 0
    newest_ns: int | None = None
    first_wall: float | None = None
    last_wall: float | None = None
    #: ``(stamp before the gap, stamp after it, samples lost)`` per gap, oldest first (ns).
    gaps: list[tuple[int, int, int]] = field(default_factory=list)
    _steps: list[int] = field(default_factory=list, repr=False)
    _period: float = field(default=0.0, repr=False)
    _taken: int = field(default=0, repr=False)

    def note(self, ns: int) -> bool:
        """Record a stamp (ns); returns False when it is late (older than the newest)."""
        now = time.monotonic()
        self.first_wall = self.first_wall or now
        self.last_wall = now
        self.received += 1
        if self.newest_ns is not None and ns <= self.newest_ns:
            self.late += 1
            return False
        if self.newest_ns is not None:
            step = ns - self.newest_ns
            if len(self._steps) < 50:  # the median is frozen after 50 steps (per-message cost)
                self._steps.append(step)
                self._period = float(np.median(self._steps))
            if step > 1.5 * self._period:
                n = int(round(step / self._period)) - 1
                self.lost += n
                self.gaps.append((self.newest_ns, ns, n))
        self.newest_ns = ns
        return True

    def take_lost_before(self, end_ns: int) -> int:
        """Samples lost in the gaps not taken yet that start before ``end_ns`` (ns); each gap is taken once."""
        n = 0
        while self._taken < len(self.gaps) and self.gaps[self._taken][0] < end_ns:
            n += self.gaps[self._taken][2]
            self._taken += 1
        return n

    @property
    def rate_hz(self) -> float:
        """Mean arrival rate (messages per wall-clock second)."""
        if self.first_wall is None or self.last_wall is None or self.last_wall <= self.first_wall:
            return 0.0
        return (self.received - 1) / (self.last_wall - self.first_wall)


_Item = TypeVar("_Item")


class ReorderBuffer(Generic[_Item]):
    """Holds stamped items for up to ``window_ns`` of stamp time so out-of-order arrivals are sorted.

    An item that continues the released stream without a hole (its stamp at
    most 1.5 nominal periods after the last released one) is released at
    once: in-order data never wait for the window, which is what a
    controller's latency needs (issue 15: the 20 ms window used to delay every
    take-off by 20 ms). Only behind a hole (a sample late or lost) do the
    items wait, until the hole is filled or ``window_ns`` of newer stamps have
    arrived. The nominal period is the median of the first
    :data:`~hop_impedance.biomech.stages.NOMINAL_PERIOD_STEPS` steps released through the window (before that,
    every item waits for the window), learnt by the stages' own
    :class:`~hop_impedance.biomech.stages.NominalPeriod` on the stamps in ns.

    ``add`` returns False (and counts ``dropped``) for an item older than (or
    as old as) the last released one: it arrived too late to be used in order,
    or is a duplicate of a released one.
    """

    def __init__(self, window_ns: int) -> None:
        self.window_ns = int(window_ns)
        self.items: list[tuple[int, _Item]] = []
        self.released_ns: int | None = None
        self.dropped = 0
        self.duplicates = 0
        self._period = NominalPeriod()

    @property
    def period_ns(self) -> int | None:
        """The nominal period (ns), or None until it is learnt."""
        return None if self._period.value is None else int(self._period.value)

    def add(self, ns: int, item: _Item) -> bool:
        if self.released_ns is not None and ns <= self.released_ns:
            self.dropped += 1
            return False
        self.items.append((ns, item))
        return True

    def release(self, everything: bool = False) -> list[tuple[int, _Item]]:
        """Items in stamp order, each stamp once: those older than newest - window (all with
        ``everything``), then every following one that continues the stream without a hole.

        A repeated stamp (a duplicated message) keeps its first arrival and counts
        in ``duplicates``, as the offline loader drops it
        (:func:`hop_impedance.input_checks.order_by_stamp`); the stages downstream
        need strictly increasing stamps.
        """
        if not self.items:
            return []
        self.items.sort(key=lambda x: x[0])
        limit = self.items[-1][0] if everything else self.items[-1][0] - self.window_ns
        n = 0
        while n < len(self.items) and self.items[n][0] <= limit:
            n += 1
        if self._period.value is None:
            self._period.update(np.array([x[0] for x in self.items[:n]], dtype=np.int64))
        period_ns = self.period_ns
        if period_ns is not None:
            last = self.items[n - 1][0] if n else self.released_ns
            max_step = period_ns * 3 // 2
            while n < len(self.items) and last is not None and self.items[n][0] - last <= max_step:
                last = self.items[n][0]
                n += 1
        out, self.items = self.items[:n], self.items[n:]
        if out:
            unique = [out[0]] + [b for a, b in zip(out, out[1:]) if b[0] != a[0]]
            self.duplicates += len(out) - len(unique)
            out = unique
            self.released_ns = out[-1][0]
        return out


class InputGuard:
    """The shared input checks (:class:`hop_impedance.input_checks.InputChecks`) inside a node.

    Declares the parameters ``subject_wait_s`` (2.0: stamp time after the first
    force sample to wait for ``/subject``), ``body_mass_kg`` and
    ``body_height_m`` (0 = none: without ``/subject`` the node then fails the
    ``subject_missing`` rule), and turns a failed rule into the node's state:
    :meth:`reason` for every stance, :meth:`level` for ``/diagnostics`` (ERROR
    naming the rule), :meth:`values` (``input_check``, ``input_note``), and one
    error line in the node's log. No check is re-implemented here.
    """

    def __init__(self, node: Node, cutoff_hz: float) -> None:
        from hop_impedance.input_checks import InputChecks
        from hop_impedance.recording import Subject

        self.node = node
        wait = declare(node, "subject_wait_s", 2.0,
                       f"wait this long (stamp time, s) for {SUBJECT_TOPIC} before using the parameters")
        mass = declare(node, "body_mass_kg", 0.0, f"body mass (kg) if no {SUBJECT_TOPIC} arrives in time; 0 = stop with an error")
        height = declare(node, "body_height_m", 0.0, f"body height (m) if no {SUBJECT_TOPIC} arrives in time")
        fallback = Subject("parameters", float(mass), float(height)) if mass or height else None
        self.checks = InputChecks(cutoff_hz, subject_wait_s=float(wait), fallback=fallback)
        self._notes_logged = 0
        self._failure_logged = False

    @property
    def failure(self):
        return self.checks.failure

    def subject(self, subject) -> None:
        self.checks.set_subject(subject)
        self._log()

    def force(self, items: Sequence[tuple[int, tuple[float, ...]]], fz_index: int) -> None:
        """Released force items ``(stamp ns, values)``; ``values[fz_index]`` is force.z (N)."""
        if items:
            self.checks.force(np.fromiter((i[0] for i in items), np.int64, len(items)),
                              np.fromiter((i[1][fz_index] for i in items), float, len(items)))
            self._log()

    def marker_frame(self, ns: int, names: list[str], positions) -> None:
        """One ``MarkerArray``: names checked, positions (m) in contract order checked for units."""
        columns = self.checks.marker_names(names)
        if columns is not None and len(positions) == len(names):
            xyz = np.array([(p.x, p.y, p.z) for p in positions], float)[columns]
            self.checks.markers(ns, xyz)
        self._log()

    def reason(self, existing: str | None) -> str | None:
        """A stance's rejection reason: the failed rule's, else ``existing``."""
        return self.checks.failure.reason if self.checks.failure is not None else existing

    def level(self) -> tuple[int, str] | None:
        """``(2, reason)`` (ERROR) once a rule failed, else None."""
        return (2, self.checks.failure.reason) if self.checks.failure is not None else None

    def values(self) -> dict:
        f = self.checks.failure
        return {"input_check": f.reason if f is not None else "ok", "input_note": "; ".join(self.checks.notes)}

    def _log(self) -> None:
        for note in self.checks.notes[self._notes_logged:]:
            self.node.get_logger().warning(note)
        self._notes_logged = len(self.checks.notes)
        if self.checks.failure is not None and not self._failure_logged:
            self.node.get_logger().error(f"{self.checks.failure.reason}; every stance is rejected")
            self._failure_logged = True


def percentile_ms(values: list[float], q: float) -> float:
    """q-th percentile of seconds, in ms (NaN when empty)."""
    return float(np.percentile(values, q) * 1e3) if values else float("nan")


class Diagnostics:
    """Publishes one ``DiagnosticStatus`` per node on ``/diagnostics`` every ``period_s``.

    ``values`` is a callable returning ``{key: value}``; ``level`` one
    returning ``(level, message)``. The header stamp is the newest input
    sample stamp the node processed (the sample clock), so a recorded
    session keeps diagnostics next to the data they describe.
    """

    def __init__(self, node: Node, period_s: float, values, level=None) -> None:
        from diagnostic_msgs.msg import DiagnosticArray

        self.node = node
        self.values = values
        self.level = level or (lambda: (0, "ok"))
        self.sample_ns = 0
        self.pub = node.create_publisher(DiagnosticArray, DIAGNOSTICS_TOPIC, 10)
        self.timer = node.create_timer(period_s, self.publish) if period_s > 0 else None

    def publish(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        arr = DiagnosticArray()
        set_stamp(arr.header.stamp, self.sample_ns)
        level, message = self.level()
        status = DiagnosticStatus(level=bytes([level]), name=self.node.get_fully_qualified_name(),
                                  message=message, hardware_id="hop_impedance")
        status.values = [KeyValue(key=k, value=_fmt(v)) for k, v in self.values().items()]
        arr.status = [status]
        self.pub.publish(arr)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


class ProgressReporter:
    """Publishes the node's consumed stamps on ``/pipeline/progress`` (flow control of the replay).

    Published at most every ``period_s`` when something changed, at least
    every ``heartbeat_s`` (so the replay can tell a busy consumer from a dead
    one), and at once on :meth:`publish` (e.g. after a flush).
    """

    def __init__(self, node: Node, trackers: dict[str, InputTracker], period_s: float = 0.01) -> None:
        from hop_impedance_msgs.msg import Progress

        from hop_impedance.nodes.qos import result_qos

        self.node = node
        self.trackers = trackers
        self.processed_ns: dict[str, int] = {}
        self.finished = False
        self.stances_out = 0
        self._last_sent: tuple | None = None
        self._last_wall = 0.0
        self.heartbeat_s = 0.5
        self.pub = node.create_publisher(Progress, PROGRESS_TOPIC, result_qos(50))
        self.timer = node.create_timer(period_s, self._tick)

    def _state(self) -> tuple:
        return (tuple(sorted(self.processed_ns.items())), self.finished, self.stances_out,
                tuple(t.received for t in self.trackers.values()))

    def _tick(self) -> None:
        if self._state() != self._last_sent or time.monotonic() - self._last_wall > self.heartbeat_s:
            self.publish()

    def publish(self) -> None:
        from builtin_interfaces.msg import Time
        from hop_impedance_msgs.msg import Progress

        msg = Progress(node=self.node.get_fully_qualified_name(), finished=self.finished, stances_out=self.stances_out)
        set_stamp(msg.header.stamp, time.time_ns())
        msg.topics = list(self.trackers)
        stamps = []
        for topic in self.trackers:
            t = Time()
            set_stamp(t, self.processed_ns.get(topic, 0))
            stamps.append(t)
        msg.last_stamps = stamps
        msg.received = [t.received for t in self.trackers.values()]
        self._last_sent = self._state()
        self._last_wall = time.monotonic()
        self.pub.publish(msg)


def wants_help(args=None) -> bool:
    """True when the command line asks for ``-h`` / ``--help`` (before any ``--ros-args``)."""
    import sys

    argv = list(sys.argv[1:] if args is None else args)
    if "--ros-args" in argv:
        argv = argv[:argv.index("--ros-args")]
    return "-h" in argv or "--help" in argv


def spin_node(node_factory, args=None) -> None:
    """``main()`` body shared by the nodes: init, build, spin, exit quietly on Ctrl-C / shutdown.

    ``--help`` prints the node module's docstring (its topics and
    parameters) without starting ROS; a bad parameter (ValueError while
    building the node) exits with its one-line message.
    Uses the EventsExecutor (measured several times faster than the
    Single/MultiThreadedExecutor on this rclpy; docs/pipeline.md).
    """
    import sys

    if wants_help(args):
        print(sys.modules[node_factory.__module__].__doc__)
        return
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.signals import SignalHandlerOptions

    stop = StopRequest()
    with rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO):
        stop.install()
        node = None
        try:
            try:
                node = node_factory()
            except ValueError as exc:
                raise SystemExit(f"error: {exc}") from None
            executor = make_executor()
            executor.add_node(node)
            warm_up_logging()
            freeze_startup_objects()
            spin_until_shutdown(executor, stop)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            if node is not None:
                node.destroy_node()  # nodes with files (rerun_bridge, recorder) close them here


class StopRequest:
    """SIGINT / SIGTERM as a flag the spin loop reads between callbacks, never an exception inside one.

    rclpy's own handlers (``SignalHandlerOptions.ALL``) shut the context down and then chain to Python's,
    which raises ``KeyboardInterrupt`` wherever the main thread happens to be: inside a callback it can
    land in the middle of an MCAP write or flush, and the ``mcap`` writer is not exception-safe there
    (``bench/mcap_interrupt_probe.py``: an exception raised at a random point of a write loop loses messages
    already written in 86 of 300 trials). That is how the recorder of a CI run under load (session 26's stop)
    exited cleanly yet left out the last stance's outputs it had acknowledged. With this handler the
    callback in progress finishes, the loop ends within its 0.1 s wait, and the node closes its files.
    A second signal raises ``KeyboardInterrupt`` at once (a person pressing Ctrl-C again wants out).
    """

    def __init__(self) -> None:
        self.requested = False

    def install(self) -> None:
        """Handle SIGINT and SIGTERM in this process (call from the main thread)."""
        import signal

        signal.signal(signal.SIGINT, self._on_signal)
        signal.signal(signal.SIGTERM, self._on_signal)

    def _on_signal(self, _signum, _frame) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True


def spin_until_shutdown(executor, stop: StopRequest | None = None) -> None:
    """``spin_once`` until rclpy shuts down or ``stop`` is requested (Ctrl-C / SIGTERM).

    ``EventsExecutor.spin()`` of this rclpy neither returns on SIGINT nor
    idles (measured: ~80 % of a core with no traffic); spin_once in a loop
    does both.
    """
    import rclpy

    context = executor.context
    while rclpy.ok(context=context) and not (stop is not None and stop.requested):
        executor.spin_once(timeout_sec=0.1)


def freeze_startup_objects() -> None:
    """Collect once and move every object alive now out of the garbage collector's reach (``gc.freeze``).

    A full (generation 2) collection scans every tracked object: with the 89,617 that
    rclpy, numpy, scipy and the nodes leave after their imports one costs 26.7 ms CPU on a
    quiet machine, 0.00 ms after the freeze (``bench/bench_path_costs.py``), enough to put
    any stance it lands on past the controller's 20 ms (issue 15). Start-up objects live as long as the
    process, so scanning them again finds nothing; later objects are still collected. Call
    this once the nodes are built and warmed up, before the data flows.
    """
    import gc

    gc.collect()
    gc.freeze()


def warm_up_logging() -> None:
    """Pay rclpy's one-time logging cost now, before the first stance, not inside a callback.

    An rclpy logger call resolves its caller with ``inspect.getframeinfo``,
    whose ``inspect.getmodule`` maps every module loaded so far to its
    ``realpath`` the first time (later calls only look at modules imported
    since). With the pipeline's ~1,250 modules that first call takes tens of
    milliseconds on a loaded machine, and in one process it landed in
    ``inverse_dynamics``' callback right after it published the first
    ``StanceKinetics`` (its "body model scaled" note), so the estimator's
    callback, the first stance's fit and its controller message waited for it
    (the first stance's take-off -> controller latency of
    bench/bench_pipeline.py, one process). Call this once the nodes are built
    (their imports done) and before spinning.
    """
    import inspect

    frame = inspect.currentframe()  # None only on Python implementations without stack frames
    if frame is not None:
        inspect.getframeinfo(frame)


class DeferredPublisher:
    """Publish a queue of messages in slices from a timer, ``delay_s`` after the callback that queued them.

    ``inverse_dynamics`` has ~300 per-frame ``JointKinetics`` per stance.
    Published in the callback that publishes the ``StanceKinetics`` (3-4 ms
    of message building and publishing), they held every other callback of a
    one-process executor, the estimator's included, until they were out; with
    separate processes they competed for the two cores with the estimator's
    fit. Queued here, they go out ``per_tick`` at a time every ``period_s``,
    starting ``delay_s`` after they were queued (the timer runs only while
    something is queued); :meth:`flush` publishes the rest at once (end of
    stream).
    """

    def __init__(self, node: Node, msg_type, topic: str, qos, delay_s: float = 0.04, period_s: float = 0.002,
                 per_tick: int = 50) -> None:
        self.publisher = node.create_publisher(msg_type, topic, qos)
        self.delay_s, self.per_tick = delay_s, per_tick
        self._queue: list[tuple[float, object]] = []  # (due monotonic s, message or builder), oldest first
        self._timer = node.create_timer(period_s, self._tick, autostart=False)

    @property
    def pending(self) -> int:
        return len(self._queue)

    def extend(self, build) -> None:
        """Queue the messages ``build()`` returns (built when they are due, not in the caller's callback)."""
        self._queue.append((time.monotonic() + self.delay_s, build))
        if self._timer.is_canceled():
            self._timer.reset()

    def _tick(self) -> None:
        self._publish(self.per_tick, time.monotonic())

    def flush(self) -> None:
        self._publish(None, math.inf)

    def _publish(self, budget: int | None, now: float) -> None:
        while self._queue and self._queue[0][0] <= now and (budget is None or budget > 0):
            due, head = self._queue[0]
            if callable(head):
                self._queue[:1] = [(due, m) for m in head()]  # the builder's messages, in order
                continue
            self._queue.pop(0)
            self.publisher.publish(head)
            budget = None if budget is None else budget - 1
        if not self._queue:
            self._timer.cancel()


def make_executor(kind: str = "events"):
    """``"events"`` (rclpy.experimental.EventsExecutor) or ``"single"`` (SingleThreadedExecutor)."""
    if kind == "events":
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    if kind == "single":
        from rclpy.executors import SingleThreadedExecutor

        return SingleThreadedExecutor()
    raise ValueError(f"executor must be 'events' or 'single', got {kind!r}")
