"""In-memory form of a contract recording (see ``shared/contract/RECORDINGS.md``).

Everything downstream of I/O works on these arrays, never on ROS messages, so
the same science runs on a live stream, a replayed MCAP file, an imported C3D
session or a simulated trial.

Frames and units follow the contract: lab frame x forward (anterior), y to the
subject's left, z up; SI units (m, s, N, N m, kg). Times are integer
nanoseconds (``*_ns``) as in ROS headers; ``header.stamp`` is the instant the
sample was measured.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The six markers of the contract, in the order used by every ``(N, 6, 3)`` array.
MARKER_NAMES: tuple[str, ...] = ("toe", "heel", "ankle", "knee", "hip", "head")

#: Contract topic names.
FORCE_TOPIC = "/force_plate/wrench"
MARKER_TOPIC = "/mocap/markers"
SUBJECT_TOPIC = "/subject"
#: Their message types (``pkg/msg/Type``), as the contract and the MCAP schemas name them.
WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
MARKER_TYPE = "hop_impedance_msgs/msg/MarkerArray"
SUBJECT_TYPE = "hop_impedance_msgs/msg/SubjectInfo"

GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class Subject:
    """Who hopped.

    Attributes
    ----------
    subject_id : str
    body_mass_kg : float
        Total body mass (kg); drives the anthropometric model.
    body_height_m : float
        Standing height (m).
    sex : str
        ``"female"`` or ``"male"``: selects the de Leva (1996) table. Not in the
        contract's SubjectInfo message; defaults to ``"female"`` because the seed
        paper's subjects were all women.
    """

    subject_id: str
    body_mass_kg: float
    body_height_m: float
    sex: str = "female"

    @property
    def body_weight_n(self) -> float:
        """Body weight (N) with g = 9.81 m/s^2."""
        return self.body_mass_kg * GRAVITY_M_S2


@dataclass
class ForcePlateSeries:
    """Force-plate wrench samples, plate frame = lab frame, origin at the plate's top centre.

    Attributes
    ----------
    stamp_ns : ndarray, shape (N,), int64
        Measurement instants (ns), as in ``header.stamp``.
    force_n : ndarray, shape (N, 3)
        Ground reaction force on the subject (N), x forward, y left, z up.
    torque_nm : ndarray, shape (N, 3)
        Moment about the plate origin (N m).
    """

    stamp_ns: np.ndarray
    force_n: np.ndarray
    torque_nm: np.ndarray

    def __len__(self) -> int:
        return int(self.stamp_ns.shape[0])

    def cop_x_m(self, min_fz_n: float = 20.0) -> np.ndarray:
        """Anterior centre of pressure (m), ``-torque.y / force.z``; NaN where Fz < ``min_fz_n``."""
        fz = self.force_n[:, 2]
        out = np.full(fz.shape, np.nan)
        ok = fz > min_fz_n
        out[ok] = -self.torque_nm[ok, 1] / fz[ok]
        return out


@dataclass
class MarkerSeries:
    """Marker positions in the lab frame.

    Attributes
    ----------
    stamp_ns : ndarray, shape (M,), int64
        Measurement instants (ns).
    names : tuple of str
        Marker names, one per column of ``positions_m``; after mapping to the
        contract these are :data:`MARKER_NAMES` in that order.
    positions_m : ndarray, shape (M, len(names), 3)
        Positions (m); an occluded marker is NaN in all three coordinates.
    """

    stamp_ns: np.ndarray
    names: tuple[str, ...]
    positions_m: np.ndarray

    def __len__(self) -> int:
        return int(self.stamp_ns.shape[0])

    def marker(self, name: str) -> np.ndarray:
        """Positions of one marker, shape (M, 3) (m)."""
        return self.positions_m[:, self.names.index(name), :]


@dataclass
class Recording:
    """One hopping session: force plate, markers and subject.

    ``markers`` is None for force-only recordings (stance detection still works);
    ``subject`` is None when the recording carried no ``/subject`` message.
    ``warnings`` collects one-line notes from loading (truncation, dropped or
    out-of-order messages) so the caller can show them.
    """

    force: ForcePlateSeries
    markers: MarkerSeries | None
    subject: Subject | None
    source: str = ""
    warnings: list[str] = field(default_factory=list)

    @property
    def start_ns(self) -> int:
        """First measurement instant over all streams (ns): the zero of ``*_s`` times."""
        starts = [int(self.force.stamp_ns[0])] if len(self.force) else []
        if self.markers is not None and len(self.markers):
            starts.append(int(self.markers.stamp_ns[0]))
        return min(starts) if starts else 0
