"""QoS profiles used by every node, in one place.

- High-rate inputs (force plate, markers, per-frame kinetics): sensor-data style
  (best effort, volatile) by default, as live drivers publish; with the
  parameter ``reliable_inputs`` nodes match reliable publishers (many mocap
  drivers, and our replay, which must not lose samples). A deep history keeps a
  Python callback's short stalls from dropping messages (shared/notes: depth
  10 lost 13-38 of 5000 messages at 1 kHz, depth 1000 lost none).
- Results (stance events, profiles, summaries, controller feed): reliable, and
  transient-local for the controller feed so a controller that starts late
  gets the latest impedance at once.
- ``/subject``: reliable + transient-local, published once (contract).
- ``/stance/kinetics``: reliable + transient-local with the last
  :data:`STANCE_HISTORY` stances (:func:`history_qos`), so an estimator or a
  controller's own fitter started mid-session gets the recent stances at once;
  subscribers de-duplicate by touchdown stamp (a stance heard live and again
  from the history is fitted once).
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

INPUT_DEPTH = 2000


def input_qos(reliable: bool) -> QoSProfile:
    """QoS for high-rate sensor topics (reliable or best effort, deep KEEP_LAST history)."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=INPUT_DEPTH,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE,
    )


def result_qos(depth: int = 100) -> QoSProfile:
    """QoS for per-stance results."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE)


def latched_qos() -> QoSProfile:
    """Reliable, transient-local, depth 1: ``/subject`` and the controller feed."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=1,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )


#: Stances kept on ``/stance/kinetics`` for late joiners (about 10 s of hopping at 2 Hz).
STANCE_HISTORY = 20


def history_qos(depth: int = STANCE_HISTORY) -> QoSProfile:
    """Reliable, transient-local, the last ``depth`` messages: per-stance results a late joiner needs."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
