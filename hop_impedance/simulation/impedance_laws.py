"""Joint torque laws of the simulator, each a switchable part.

Every law maps time since touchdown, joint angles and velocities (and, for
path-dependent terms, extra ODE states) to joint moments, **extensor
positive** (a positive moment acts to decrease rho, see
:mod:`hop_impedance.biomech.joint_angles`). Joints are ordered ankle, knee, hip.

Laws
----
- :class:`Eq3Law`: the seed paper's Eq. 3 stiffness ``K`` and damping ``B``
  integrated as in Eqs. 4-5 (constant stiffness is the special case with only
  ``k0``), optionally with a time-based activation that scales its elastic part.
- :class:`PushOff`: an extensor moment pulse with its own time course late in stance.
- :class:`BiarticularSpring`: a passive knee-ankle (gastrocnemius-like) spring, conservative (off by default).
- :class:`CompositeLaw`: the sum of parts.

Integration of Eq. 3 (done here in closed form, independently of the fit code)
-------------------------------------------------------------------------------
With ``dr = rho - rho0`` and ``dw = omega - omega0`` (touchdown values):

    M_s = k0 dr + k1 dr^2/2 + k2 dr^3/3 + k3 S
    M_d = b0 dw + b1 dw^2/2 + b2 dw^3/3 + b3 (dr dw - S)
    M   = m0 + a(t) M_s + M_d,        dS/dt = (omega - omega0) omega,

because ``int k3 dw d(rho) = k3 int dw omega dt = k3 S`` and, by parts,
``int b3 dr d(omega) = b3 (dr dw - S)``. ``S`` is one extra ODE state per
joint (zero at touchdown). ``m0`` is the moment at touchdown (M_s0 + M_d0 of
Eq. 4), zero by default as measured at touchdown in hopping (seed 001).
``a(t) = 1`` unless a :class:`TimeActivation` is attached.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field, replace
from typing import TypeVar

import numpy as np

COEFFICIENT_NAMES: tuple[str, ...] = ("m0", "k0", "k1", "k2", "k3", "b0", "b1", "b2", "b3")


@dataclass(frozen=True)
class TouchdownReference:
    """rho0 and omega0 of Eq. 3: joint angles (rad) and velocities (rad/s) at touchdown, shape (3,)."""

    rho0_rad: np.ndarray
    omega0_rad_s: np.ndarray


_LawT = TypeVar("_LawT", bound="ImpedanceLaw")


class ImpedanceLaw(ABC):
    """A joint torque law. Arrays broadcast: ``t_s`` shape (...), joint arrays (..., 3)."""

    @property
    def n_states(self) -> int:
        """Number of extra ODE states the law integrates during stance (a subclass may set a class attribute)."""
        return 0

    @abstractmethod
    def moments_nm(
        self, t_s: np.ndarray, rho: np.ndarray, omega: np.ndarray, states: np.ndarray, ref: TouchdownReference
    ) -> np.ndarray:
        """Joint moments (N m), extensor positive, shape (..., 3).

        Parameters
        ----------
        t_s : ndarray, shape (...)
            Time since touchdown (s).
        rho, omega : ndarray, shape (..., 3)
            Joint angles (rad) and angular velocities (rad/s), flexion positive.
        states : ndarray, shape (..., n_states)
            The law's extra states.
        ref : TouchdownReference
        """

    def state_rates(
        self, t_s: np.ndarray, rho: np.ndarray, omega: np.ndarray, states: np.ndarray, ref: TouchdownReference
    ) -> np.ndarray:
        """Time derivative of the extra states, shape (..., n_states)."""
        return np.zeros(np.shape(rho)[:-1] + (0,))

    def elastic_energy_j(self, rho: np.ndarray, ref: TouchdownReference) -> np.ndarray:
        """Energy stored in the joints (J), shape (...); only for conservative laws."""
        raise NotImplementedError(f"{type(self).__name__} is not conservative")

    @abstractmethod
    def to_dict(self) -> dict:
        """Every parameter, JSON-ready."""


@dataclass(frozen=True)
class TimeActivation:
    """Activation fixed in time since touchdown and blind to the surface (seed 001).

    ``a(t) = a_min + (1 - a_min) (1 - exp(-t / tau))``: the elastic moment
    rises with time like the active state of a pre-programmed stimulation, so
    a joint that flexes *earlier* (e.g. on an unexpected hard surface) meets a
    lower stiffness.

    Attributes
    ----------
    a_min : float
        Activation at touchdown, 0 <= a_min <= 1.
    tau_s : float
        Time constant (s), > 0.
    """

    a_min: float
    tau_s: float

    def __post_init__(self) -> None:
        if not (0.0 <= self.a_min <= 1.0 and self.tau_s > 0):
            raise ValueError(f"activation needs 0 <= a_min <= 1 and tau_s > 0, got {self.a_min}, {self.tau_s}")

    def value(self, t_s: np.ndarray) -> np.ndarray:
        """a(t) (dimensionless); ``t_s`` is time since touchdown (s)."""
        t = np.maximum(np.asarray(t_s, float), 0.0)
        return self.a_min + (1.0 - self.a_min) * (1.0 - np.exp(-t / self.tau_s))


@dataclass(frozen=True)
class BellActivation:
    """Activation that peaks within the stance and is lower at its edges (issue 17's seed-like hopper).

    ``a(t) = a_min + (1 - a_min) sin^2(pi t / duration)`` for ``0 <= t <= duration``, ``a_min`` after: the
    elastic moment is that fraction of Eq. 3's. The shape is seed 000's bell-shaped stiffness in time with
    non-zero edges (its Fig. 5; the discovery model's ``activation_shape="bell"``): the extensors are
    pre-activated at touchdown (``a_min``, the seed's "initial joint stiffness ... pre-activation"), fully
    active around maximal flexion, and relax before take-off. Over a stance mirror-symmetric about
    ``duration / 2`` the loading and unloading works cancel (unlike :class:`TimeActivation`, whose rise makes
    the springs do net positive work), and the force peaks more than a spring's: the seed's peak GRF over its
    mean in stance is 1.75-2.17, a linear spring-mass's at most 2.

    Attributes
    ----------
    a_min : float
        Activation at touchdown and after ``duration_s``, 0 <= a_min <= 1.
    duration_s : float
        Length of the bell (s), > 0 (:func:`~hop_impedance.simulation.scenarios.hopping_config`: the passive
        stance's).
    """

    a_min: float
    duration_s: float

    def __post_init__(self) -> None:
        if not (0.0 <= self.a_min <= 1.0 and self.duration_s > 0):
            raise ValueError(f"bell activation needs 0 <= a_min <= 1 and duration_s > 0, got {self.a_min}, "
                             f"{self.duration_s}")

    def value(self, t_s: np.ndarray) -> np.ndarray:
        """a(t) (dimensionless); ``t_s`` is time since touchdown (s)."""
        phase = np.clip(np.asarray(t_s, float) / self.duration_s, 0.0, 1.0)
        return self.a_min + (1.0 - self.a_min) * np.sin(np.pi * phase) ** 2


def _as3(x: object) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(x, float), (3,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"impedance coefficients must be finite, got {arr}")
    return arr


@dataclass(frozen=True)
class Eq3Law(ImpedanceLaw):
    """The seed's Eq. 3 law, integrated (Eqs. 4-5); each coefficient shape (3,) (ankle, knee, hip).

    Units: m0 N m; k0 N m/rad; k1 N m/rad^2; k2 N m/rad^3; k3 N m s/rad^2;
    b0 N m s/rad; b1 N m s^2/rad^2; b2 N m s^3/rad^3; b3 N m s/rad^2.
    """

    m0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    k0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    k1: np.ndarray = field(default_factory=lambda: np.zeros(3))
    k2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    k3: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b1: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    b3: np.ndarray = field(default_factory=lambda: np.zeros(3))
    activation: TimeActivation | BellActivation | None = None

    n_states = 3

    def __post_init__(self) -> None:
        for name in COEFFICIENT_NAMES:
            object.__setattr__(self, name, _as3(getattr(self, name)))

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102 (see base class)
        dr = np.asarray(rho, float) - ref.rho0_rad
        dw = np.asarray(omega, float) - ref.omega0_rad_s
        s = np.asarray(states, float)
        elastic = self.k0 * dr + self.k1 * dr**2 / 2 + self.k2 * dr**3 / 3 + self.k3 * s
        if self.activation is not None:
            elastic = self.activation.value(t_s)[..., None] * elastic
        damping = self.b0 * dw + self.b1 * dw**2 / 2 + self.b2 * dw**3 / 3 + self.b3 * (dr * dw - s)
        return self.m0 + elastic + damping

    def state_rates(self, t_s, rho, omega, states, ref):  # noqa: D102
        w = np.asarray(omega, float)
        return (w - ref.omega0_rad_s) * w

    def stiffness_nm_rad(self, rho, omega, ref) -> np.ndarray:
        """K of Eq. 3 (N m/rad), shape (..., 3), without the activation factor."""
        dr = np.asarray(rho, float) - ref.rho0_rad
        dw = np.asarray(omega, float) - ref.omega0_rad_s
        return self.k0 + self.k1 * dr + self.k2 * dr**2 + self.k3 * dw

    def elastic_energy_j(self, rho, ref):  # noqa: D102
        if self.activation is not None or np.any(self.k3 != 0):
            raise NotImplementedError("Eq3Law with k3 or an activation is not conservative")
        dr = np.asarray(rho, float) - ref.rho0_rad
        e = self.m0 * dr + self.k0 * dr**2 / 2 + self.k1 * dr**3 / 6 + self.k2 * dr**4 / 12
        return e.sum(axis=-1)

    def to_dict(self) -> dict:  # noqa: D102
        out = {"type": "eq3", **{n: getattr(self, n).tolist() for n in COEFFICIENT_NAMES}}
        out["activation"] = None if self.activation is None else vars(self.activation).copy()
        return out


@dataclass(frozen=True)
class PreparedStiffening(ImpedanceLaw):
    """Eq. 3's ``k1`` term with its rise pre-programmed in time along an expected stance (seed 001; off by default:
    no hopper builds it, :mod:`hop_impedance.simulation.surface_surprise` does).

    Eq. 3's angle-dependent part ``k1 dr^2 / 2 = int k1 dr d(rho)`` lets the stiffness grow with flexion. Seed 000
    reads that growth as pre-programmed muscle action (its K(t) bell peaks "at mid-stance, when the jumper's joints
    are maximally flexed"), and seed 001 shows where it comes from: the active state q "rises as a result of
    stimulation STIM(t), which is fixed in time", and "force rise ... mainly depends on the rise in q". On the
    surface the hopper expected, time and flexion go together, so the two readings give the same moment. On an
    unexpected surface they part: here the stiffness's rise follows the expected stance's flexion *in time*,

        M = a(t) k1 S,    dS/dt = dr_exp(t) omega,    S(0) = 0,

    where ``dr_exp(t)`` is the expected stance's ``rho - rho0`` at time ``t`` since touchdown (held at its last value
    after that stance's end) and ``a(t)`` the law's activation. Along the expected stance ``S = dr^2 / 2`` exactly
    (Eq. 3's term); a joint that flexes *earlier* than expected meets the lower stiffness of the earlier time.

    Attributes
    ----------
    k1 : ndarray, shape (3,)
        N m/rad^2, Eq. 3's ``k1``.
    times_s : ndarray, shape (n,)
        Increasing times since touchdown of the expected stance (s).
    expected_dr_rad : ndarray, shape (n, 3)
        Its joint angles minus their touchdown values (rad) at ``times_s``.
    activation : TimeActivation, BellActivation or None
        The activation that scales the elastic moment (the Eq. 3 law's own).
    """

    k1: np.ndarray
    times_s: np.ndarray
    expected_dr_rad: np.ndarray
    activation: TimeActivation | BellActivation | None = None

    n_states = 3

    def __post_init__(self) -> None:
        object.__setattr__(self, "k1", _as3(self.k1))
        t = np.asarray(self.times_s, float)
        dr = np.asarray(self.expected_dr_rad, float)
        if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0) or dr.shape != (len(t), 3):
            raise ValueError(f"prepared stiffening needs increasing times (n,) and angle changes (n, 3), got "
                             f"{t.shape}, {dr.shape}")
        object.__setattr__(self, "times_s", t)
        object.__setattr__(self, "expected_dr_rad", dr)

    def expected_dr(self, t_s) -> np.ndarray:
        """``dr_exp(t)`` (rad), shape (..., 3)."""
        t = np.asarray(t_s, float)
        return np.stack([np.interp(t, self.times_s, self.expected_dr_rad[:, j]) for j in range(3)], axis=-1)

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102 (see base class)
        elastic = self.k1 * np.asarray(states, float)
        if self.activation is not None:
            elastic = self.activation.value(t_s)[..., None] * elastic
        return elastic

    def state_rates(self, t_s, rho, omega, states, ref):  # noqa: D102
        return self.expected_dr(t_s) * np.asarray(omega, float)

    def to_dict(self) -> dict:  # noqa: D102
        return {"type": "prepared_stiffening", "k1": self.k1.tolist(), "times_s": self.times_s.tolist(),
                "expected_dr_rad": self.expected_dr_rad.tolist(),
                "activation": None if self.activation is None else vars(self.activation).copy(),
                "law": "M = a(t) k1 S, dS/dt = dr_expected(t) omega (Eq. 3's k1 term along the expected stance)"}


def with_prepared_stiffening(law: ImpedanceLaw, times_s, expected_dr_rad) -> CompositeLaw:
    """``law`` with its Eq. 3 part's ``k1`` term pre-programmed along an expected stance (:class:`PreparedStiffening`).

    ``law`` is an :class:`Eq3Law` or a :class:`CompositeLaw` holding one; its ``k1`` moves into a
    :class:`PreparedStiffening` with the same activation, everything else is kept. Along the expected stance the
    moments are the same as ``law``'s.
    """
    parts = law.parts if isinstance(law, CompositeLaw) else (law,)
    eq3 = law_part(law, Eq3Law)
    if eq3 is None:
        raise ValueError("with_prepared_stiffening needs an Eq3Law part")
    without_k1 = replace(eq3, k1=np.zeros(3))
    prepared = PreparedStiffening(eq3.k1, times_s, expected_dr_rad, eq3.activation)
    new_parts = tuple(q for p in parts for q in ((without_k1, prepared) if p is eq3 else (p,)))
    return CompositeLaw(new_parts)


def constant_stiffness(k0_nm_rad, b0_nm_s_rad=0.0) -> Eq3Law:
    """Constant stiffness (and optional constant damping): ``M = k0 (rho - rho0) + b0 (omega - omega0)``."""
    return Eq3Law(k0=k0_nm_rad, b0=b0_nm_s_rad)


@dataclass(frozen=True)
class PushOff(ImpedanceLaw):
    """Active extensor moment late in stance, fixed in time since touchdown.

    ``M(t) = A sin^2(pi (t - onset) / duration)`` for ``onset <= t <= onset + duration``,
    zero otherwise; ``A`` per joint (N m, >= 0: extensor; a negative share is a flexor). It
    resupplies the energy that damping and the ground dissipate; the hopping controller sets
    ``A`` hop by hop.

    ``lag_fraction`` (per joint, in [0, 1), default 0: every joint together): a joint's push starts that
    fraction of ``duration`` later and ends with the others, ``sin^2`` over its own shorter window (issue 17,
    session 28: the knee's extensors finishing the push after the ankle's; off by default).
    """

    amplitude_nm: np.ndarray
    onset_s: float
    duration_s: float
    lag_fraction: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude_nm", _as3(self.amplitude_nm))
        object.__setattr__(self, "lag_fraction", _as3(self.lag_fraction))
        if not (self.onset_s >= 0 and self.duration_s > 0):
            raise ValueError(f"push-off needs onset_s >= 0 and duration_s > 0, got {self.onset_s}, {self.duration_s}")
        if not np.all((self.lag_fraction >= 0) & (self.lag_fraction < 1)):
            raise ValueError(f"push-off lag fractions must lie in [0, 1), got {self.lag_fraction.tolist()}")

    def profile(self, t_s: np.ndarray) -> np.ndarray:
        """Time course in [0, 1] of a joint without lag, shape of ``t_s``."""
        return _sin2_window(t_s, self.onset_s, self.duration_s)

    def joint_profiles(self, t_s: np.ndarray) -> np.ndarray:
        """Time course per joint in [0, 1], shape of ``t_s`` + (3,) (:attr:`lag_fraction`)."""
        lag = self.lag_fraction * self.duration_s
        t = np.asarray(t_s, float)[..., None]
        return _sin2_window(t, self.onset_s + lag, self.duration_s - lag)

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102
        shape = np.broadcast_shapes(np.shape(t_s), np.shape(rho)[:-1])
        if not self.lag_fraction.any():  # the 0-d path kept: numpy's ``** 2`` on a (3,) array differs from the same
            # on a 0-d one in the last bit (15 of 20,000 push-off phases), and the default's trials stay bit-equal
            # (bench/simulator_reference.py --check: 4 of 12 cases differ through joint_profiles alone; session 28)
            return np.broadcast_to(self.profile(t_s)[..., None] * self.amplitude_nm, shape + (3,))
        return np.broadcast_to(self.joint_profiles(t_s) * self.amplitude_nm, shape + (3,))

    def with_amplitude(self, amplitude_nm) -> PushOff:
        """Copy with another amplitude (N m, per joint)."""
        return PushOff(amplitude_nm, self.onset_s, self.duration_s, self.lag_fraction)

    def to_dict(self) -> dict:  # noqa: D102
        out = {"type": "push_off", "amplitude_nm": self.amplitude_nm.tolist(),
               "onset_s": self.onset_s, "duration_s": self.duration_s}
        if self.lag_fraction.any():  # only then: the truth files of the default stay as they were
            out["lag_fraction"] = self.lag_fraction.tolist()
        return out


def _sin2_window(t_s, onset_s, duration_s) -> np.ndarray:
    """``sin^2(pi (t - onset) / duration)`` inside ``[onset, onset + duration]``, 0 outside (broadcasting)."""
    phase = (np.asarray(t_s, float) - onset_s) / duration_s
    inside = (phase >= 0) & (phase <= 1)
    return np.where(inside, np.sin(np.pi * np.clip(phase, 0, 1)) ** 2, 0.0)


@dataclass(frozen=True)
class CompositeLaw(ImpedanceLaw):
    """Sum of laws; their extra states are concatenated in order."""

    parts: tuple[ImpedanceLaw, ...]

    @property
    def n_states(self) -> int:
        return sum(p.n_states for p in self.parts)

    def _slices(self):
        start = 0
        for p in self.parts:
            yield p, slice(start, start + p.n_states)
            start += p.n_states

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102
        states = np.asarray(states, float)
        total = np.zeros(np.broadcast_shapes(np.shape(t_s), np.shape(rho)[:-1]) + (3,))
        for p, sl in self._slices():
            total = total + p.moments_nm(t_s, rho, omega, states[..., sl], ref)
        return total

    def state_rates(self, t_s, rho, omega, states, ref):  # noqa: D102
        states = np.asarray(states, float)
        rates = [p.state_rates(t_s, rho, omega, states[..., sl], ref) for p, sl in self._slices()]
        return np.concatenate(rates, axis=-1) if rates else np.zeros(np.shape(rho)[:-1] + (0,))

    def elastic_energy_j(self, rho, ref):  # noqa: D102
        return sum(p.elastic_energy_j(rho, ref) for p in self.parts)

    def part(self, kind: type[_LawT]) -> _LawT | None:
        """First part of the given type, or None."""
        return next((p for p in self.parts if isinstance(p, kind)), None)

    def replace_part(self, old: ImpedanceLaw, new: ImpedanceLaw) -> CompositeLaw:
        """Copy with ``old`` (by identity) swapped for ``new``."""
        return CompositeLaw(tuple(new if p is old else p for p in self.parts))

    def to_dict(self) -> dict:  # noqa: D102
        return {"type": "composite", "parts": [p.to_dict() for p in self.parts]}


def law_part(law: ImpedanceLaw, kind: type[_LawT]) -> _LawT | None:
    """The first part of ``law`` of type ``kind`` (the law itself if it is one), or None."""
    if isinstance(law, kind):
        return law
    if isinstance(law, CompositeLaw):
        return law.part(kind)
    return None


@dataclass(frozen=True)
class BiarticularSpring(ImpedanceLaw):
    """A passive two-joint spring coupling knee and ankle, like the gastrocnemius (issue 17, session 26; off by
    default: ``hopping_config(biarticular=...)``).

    The gastrocnemius crosses the knee behind its axis and the ankle behind its axis: it is a knee flexor and an
    ankle plantarflexor, and it lengthens with ankle dorsiflexion and with knee extension. In this package's angles
    (every rho increases with flexion, ankle rho with dorsiflexion) its length changes from touchdown by
    ``x = r_a (rho_ankle - rho0_ankle) - r_k (rho_knee - rho0_knee)`` (times a length unit), and a linear spring on it
    stores

        E = k x^2 / 2,     M_j = dE/drho_j:   M_ankle = k r_a x,   M_knee = -k r_k x,   M_hip = 0

    (extensor positive: ``M = dE/drho`` as for Eq. 3's ``k0 dr``). Stretched (``x > 0``) it is an ankle
    plantarflexor and a knee flexor, the muscle's anatomy. It resists the leg's zig-zag direction, ankle and knee
    turning opposite ways (``(d_ankle, d_knee)`` along ``(r_a, -r_k)``: the knee flexing more while the ankle flexes
    less, session 25 (helper)'s soft direction at 1.53 Hz, or the reverse), and leaves free the co-flexion with
    ``d_knee / d_ankle = r_a / r_k``. Conservative (a potential; no states), about each stance's touchdown angles,
    acting in stance only like every law part. The net joint moments, and so whatever the analysis fits, include
    it; the truth file states it (``law`` and each stance's ``biarticular``, ``biarticular_moments_nm``).

    Attributes
    ----------
    stiffness_nm_rad : float
        k (N m/rad of ``x``), >= 0.
    ankle_arm, knee_arm : float
        r_a, r_k: the spring's moment arms at ankle and knee in a common length unit (dimensionless weights of the
        two joints' rotation; the gastrocnemius' are about 5 and 2-4 cm), >= 0.
    """

    stiffness_nm_rad: float
    ankle_arm: float = 1.0
    knee_arm: float = 1.0

    def __post_init__(self) -> None:
        values = (self.stiffness_nm_rad, self.ankle_arm, self.knee_arm)
        if not all(np.isfinite(v) and v >= 0 for v in values):
            raise ValueError(f"biarticular spring needs finite k, r_a, r_k >= 0, got {values}")

    @property
    def arms(self) -> np.ndarray:
        """dx/drho per joint (ankle, knee, hip): ``[r_a, -r_k, 0]``."""
        return np.array([self.ankle_arm, -self.knee_arm, 0.0])

    def stretch_rad(self, rho, ref: TouchdownReference) -> np.ndarray:
        """``x`` (rad), shape (...)."""
        return (np.asarray(rho, float) - ref.rho0_rad) @ self.arms

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102 (see base class)
        x = self.stretch_rad(rho, ref)
        shape = np.broadcast_shapes(np.shape(t_s), np.shape(rho)[:-1])
        return np.broadcast_to(self.stiffness_nm_rad * x[..., None] * self.arms, shape + (3,))

    def elastic_energy_j(self, rho, ref):  # noqa: D102
        return 0.5 * self.stiffness_nm_rad * self.stretch_rad(rho, ref) ** 2

    def to_dict(self) -> dict:  # noqa: D102
        return {"type": "biarticular", "stiffness_nm_rad": self.stiffness_nm_rad, "ankle_arm": self.ankle_arm,
                "knee_arm": self.knee_arm,
                "law": "x = r_a (rho_ankle - rho0) - r_k (rho_knee - rho0); M_ankle += k r_a x, M_knee += -k r_k x"}


@dataclass(frozen=True)
class TrunkBalance:
    """Trunk-balance moment at the hip: holds the HAT at its touchdown inclination (hands on the waist).

    The seed's subjects hop with the trunk upright; a passive hip spring cannot do that, because under
    2.5-3.5 body weights the trunk is an inverted pendulum on the hip stiffer than the Table 2 hip k0
    (31.9 kg x 3.5 g x 0.38 m ~ 410 N m/rad against 95-175 N m/rad), so it pitches by tenths of a radian.
    This postural (vestibular) moment acts on the trunk's absolute angle q4, not on the hip angle:

        M_balance = -k (q4 - q4_td) - b dq4/dt      (added to the hip moment, extensor positive)

    where q4_td is the trunk angle at touchdown (a positive hip moment raises q4, see
    :func:`hop_impedance.simulation.dynamics.joint_generalized_forces`). It is an active moment, not a
    conservative spring, even with ``b = 0``: acting at the hip it turns the thigh too, so its work is
    ``int -M omega_hip dt``, not a change of ``k (q4 - q4_td)^2 / 2``. The whole hip moment is the
    Eq. 3 hip law plus this term; the truth file states both.

    Attributes
    ----------
    stiffness_nm_rad : float
        k (N m/rad), >= 0.
    damping_nm_s_rad : float
        b (N m s/rad), >= 0.
    reference_rad : float or None
        A fixed trunk angle q4_ref (rad) used instead of each stance's touchdown q4 (issue 17's
        lossless trial: a reference that does not move with the foot placement); None (default):
        the touchdown q4.
    """

    stiffness_nm_rad: float
    damping_nm_s_rad: float = 0.0
    reference_rad: float | None = None

    def __post_init__(self) -> None:
        if not (self.stiffness_nm_rad >= 0 and self.damping_nm_s_rad >= 0):
            raise ValueError(f"trunk balance needs k >= 0 and b >= 0, got {self.stiffness_nm_rad}, "
                             f"{self.damping_nm_s_rad}")

    def hip_moment_nm(self, q4_rad, q4_rate_rad_s, q4_touchdown_rad: float):
        """Balance moment at the hip (N m, extensor positive), shape of ``q4_rad``."""
        ref = q4_touchdown_rad if self.reference_rad is None else self.reference_rad
        return (-self.stiffness_nm_rad * (np.asarray(q4_rad, float) - ref)
                - self.damping_nm_s_rad * np.asarray(q4_rate_rad_s, float))

    def to_dict(self) -> dict:
        """Parameters for the truth file."""
        if self.reference_rad is None:
            return {"type": "trunk_balance", "stiffness_nm_rad": self.stiffness_nm_rad,
                    "damping_nm_s_rad": self.damping_nm_s_rad,
                    "law": "M_hip += -k (q4 - q4_touchdown) - b dq4/dt (q4: HAT absolute angle)"}
        return {"type": "trunk_balance", "stiffness_nm_rad": self.stiffness_nm_rad,
                "damping_nm_s_rad": self.damping_nm_s_rad, "reference_rad": self.reference_rad,
                "law": "M_hip += -k (q4 - reference) - b dq4/dt (q4: HAT absolute angle)"}
