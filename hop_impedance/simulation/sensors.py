"""Force-plate and marker sampling of a simulated trial, with switchable sensor effects.

Force plate (WrenchStamped semantics of the contract): the force on the
subject ``(Fx, 0, Fz)`` and the moment about the plate origin (centre of
its top surface) of that force applied at the contact point
``r = (x_toe, 0, z_toe)``: ``torque = r x F``, i.e. ``torque.y = z_toe Fx - x_toe Fz``.
A massless surface layer transmits the force along the same line of action,
so ``cop_x = -torque.y / force.z`` is where that line meets the plate
surface (the toe's x when the toe is at z = 0 or Fx = 0). The two feet are
lumped symmetrically about y = 0, so the contact point has y = 0.

Markers: the six contract markers from the simulated segment geometry (the toe
marker is the contact point, or a point of the foot behind it when the chain
touches the ground ahead of the marker), in the
sagittal x-z plane at a constant ``y = marker_y_m`` (right side, -0.1 m).

Effects, each off when its value is 0: Gaussian force noise (N, each axis),
torque noise (N m), a constant Fz offset (N), Gaussian marker noise (m, each
coordinate), occlusions (NaN spans of one marker), and a marker stream time
offset: a marker sample stamped ``t`` shows the body at ``t - marker_time_offset_s``
(positive = markers lag the force plate).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from hop_impedance.recording import MARKER_NAMES, ForcePlateSeries, MarkerSeries, Recording, Subject
from hop_impedance.simulation.dynamics import heel_position, joint_positions, toe_marker_position
from hop_impedance.simulation.hopping_trial import HoppingTrial

#: Default first stamp (ns): 2023-11-14T22:13:20Z, an ordinary ROS wall-clock stamp.
DEFAULT_START_NS = 1_700_000_000_000_000_000


@dataclass(frozen=True)
class SensorConfig:
    """Sampling rates and sensor effects (SI; 0 switches an effect off)."""

    force_rate_hz: float = 1000.0
    marker_rate_hz: float = 100.0
    force_noise_n: float = 2.0
    torque_noise_nm: float = 0.5
    force_offset_n: float = 0.0
    marker_noise_m: float = 0.001
    occlusions_per_s: float = 0.0
    occlusion_duration_s: float = 0.05
    marker_time_offset_s: float = 0.0
    marker_y_m: float = -0.1
    start_ns: int = DEFAULT_START_NS

    def __post_init__(self) -> None:
        if not (self.force_rate_hz > 0 and self.marker_rate_hz > 0):
            raise ValueError(f"sampling rates must be positive, got {self.force_rate_hz}, {self.marker_rate_hz} Hz")
        for name in ("force_noise_n", "torque_noise_nm", "marker_noise_m", "occlusions_per_s", "occlusion_duration_s"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")

    def to_dict(self) -> dict:
        """Plain parameters for the truth file."""
        return asdict(self)


def noise_free(sensors: SensorConfig) -> SensorConfig:
    """The same rates and stream offset without noise, offset or occlusions."""
    return SensorConfig(sensors.force_rate_hz, sensors.marker_rate_hz, 0.0, 0.0, 0.0, 0.0, 0.0,
                        sensors.occlusion_duration_s, sensors.marker_time_offset_s, sensors.marker_y_m,
                        sensors.start_ns)


def sample_times_s(t_end_s: float, rate_hz: float) -> np.ndarray:
    """Sample instants ``k / rate`` in [0, t_end] (s)."""
    return np.arange(int(np.floor(t_end_s * rate_hz + 1e-9)) + 1) / rate_hz


def stamps_ns(times_s: np.ndarray, start_ns: int) -> np.ndarray:
    """Integer nanosecond stamps of times since the recording start."""
    return start_ns + np.round(np.asarray(times_s) * 1e9).astype(np.int64)


def marker_positions_m(trial: HoppingTrial, times_s: np.ndarray, y_m: float) -> np.ndarray:
    """True contract markers at ``times_s``, shape (N, 6, 3) (m), order :data:`MARKER_NAMES`."""
    g = trial.sample(times_s)["g"]
    joints = joint_positions(trial.chain, g)  # toe, ankle, knee, hip, head
    heel = heel_position(trial.chain, g)
    toe = toe_marker_position(trial.chain, g)  # the contact point unless the chain touches ahead of it
    xz = np.stack([toe, heel, joints[:, 1], joints[:, 2], joints[:, 3], joints[:, 4]], axis=1)
    out = np.empty(xz.shape[:2] + (3,))
    out[..., 0], out[..., 1], out[..., 2] = xz[..., 0], y_m, xz[..., 1]
    return out


def force_plate_wrench(trial: HoppingTrial, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """True force (N) and moment about the plate origin (N m), each shape (N, 3)."""
    state = trial.sample(times_s)
    fx, fz = state["grf_n"][:, 0], state["grf_n"][:, 1]
    contact = state["stance_index"] >= 0
    x_c = np.where(contact, state["g"][:, 0], 0.0)
    z_c = np.where(contact, state["g"][:, 1], 0.0)
    force = np.stack([fx, np.zeros_like(fx), fz], axis=1)
    torque = np.stack([np.zeros_like(fx), z_c * fx - x_c * fz, np.zeros_like(fx)], axis=1)
    return force, torque


def _occlusion_spans(duration_s: float, sensors: SensorConfig, rng: np.random.Generator) -> list[tuple[int, float, float]]:
    n = rng.poisson(sensors.occlusions_per_s * duration_s) if sensors.occlusions_per_s > 0 else 0
    starts = rng.uniform(0.0, duration_s, n)
    markers = rng.integers(0, len(MARKER_NAMES), n)
    return [(int(m), float(s), float(s + sensors.occlusion_duration_s)) for m, s in zip(markers, starts)]


def sample_recording(
    trial: HoppingTrial, sensors: SensorConfig, subject: Subject, rng: np.random.Generator
) -> tuple[Recording, dict]:
    """Contract recording of a simulated trial.

    Returns
    -------
    recording : Recording
    sensor_truth : dict
        The occlusion spans actually drawn (marker name, start/end s) and the
        sample counts, for the truth file.
    """
    t_f = sample_times_s(trial.t_end_s, sensors.force_rate_hz)
    force, torque = force_plate_wrench(trial, t_f)
    if sensors.force_noise_n > 0:
        force = force + rng.normal(0.0, sensors.force_noise_n, force.shape)
    if sensors.torque_noise_nm > 0:
        torque = torque + rng.normal(0.0, sensors.torque_noise_nm, torque.shape)
    force[:, 2] += sensors.force_offset_n

    t_m = sample_times_s(trial.t_end_s, sensors.marker_rate_hz)
    shown = np.clip(t_m - sensors.marker_time_offset_s, 0.0, trial.t_end_s)
    pos = marker_positions_m(trial, shown, sensors.marker_y_m)
    if sensors.marker_noise_m > 0:
        pos = pos + rng.normal(0.0, sensors.marker_noise_m, pos.shape)
    spans = _occlusion_spans(trial.t_end_s, sensors, rng)
    for m, s0, s1 in spans:
        pos[(t_m >= s0) & (t_m <= s1), m, :] = np.nan

    rec = Recording(
        force=ForcePlateSeries(stamps_ns(t_f, sensors.start_ns), force, torque),
        markers=MarkerSeries(stamps_ns(t_m, sensors.start_ns), MARKER_NAMES, pos),
        subject=subject,
        source="hop_impedance.simulation",
    )
    truth = {
        "occlusions": [{"marker": MARKER_NAMES[m], "start_s": s0, "end_s": s1} for m, s0, s1 in spans],
        "n_force_samples": int(len(t_f)),
        "n_marker_samples": int(len(t_m)),
    }
    return rec, truth
