"""The model that grows effect by effect: joint law, ground law and sensor model.

Joint law (per joint, pooled over stances, moments extensor positive)
---------------------------------------------------------------------
With ``dr = rho - rho0`` and ``dw = omega - omega0`` (touchdown values),
``S = int (omega - omega0) omega dt`` and ``t`` time since touchdown:

    M = a(t) * E + D + P,
    E = k0 dr [+ k1 dr^2/2 + k2 dr^3/3]  (angle_dependent_stiffness)  [+ k3 S] (rate_dependent_stiffness)
    D = b0 dw + b1 dw^2/2                                              (joint_damping)
    P = A sin^2(pi (t - onset) / duration) on [onset, onset + duration]  (active_push_off)
    a(t) = 1 - (1 - a_min) exp(-t / tau)                                (time_dependent_activation)

the seed's Eq. 3 integrated (Eqs. 4-5) with ``m0 = 0`` (baseline: zero moment
at touchdown), seed 001's activation and the simulator's push-off shape. For
fixed ``tau``, ``onset`` and ``duration`` the moment is linear in the
coefficients (``a(t) E`` is written as ``E - exp(-t/tau) * sum_k c_k E_k``
with one free ``c_k = (1 - a_min) k_k`` per elastic term), so each fit is
one least-squares solve; the three timing parameters are chosen on a grid.

Ground and sensors
------------------
- ``surface_compliance``: toe displacement ``-c Fz^p`` (Fz in N), i.e. the
  seed 001 law ``Fz = k |y|^n`` with ``n = 1/p``, ``k = c^(-1/p)``; its
  viscous term is fitted afterwards for forward simulation only.
- ``force_plate_offset``: raw plate Fz = true Fz + ``offset_n``.
- ``stream_latency``: markers show the body ``latency_s`` late.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from hop_impedance.simulation.impedance_laws import ImpedanceLaw

#: Effect names, exactly as the issue spells them.
EFFECT_NAMES: tuple[str, ...] = (
    "angle_dependent_stiffness",
    "rate_dependent_stiffness",
    "joint_damping",
    "surface_compliance",
    "time_dependent_activation",
    "stream_latency",
    "force_plate_offset",
    "active_push_off",
)
#: Effects that act on the joint law (fitted to the ID moments).
JOINT_EFFECTS = ("angle_dependent_stiffness", "rate_dependent_stiffness", "joint_damping",
                 "time_dependent_activation", "active_push_off")
#: Grids of the nonlinear timing parameters (s).
TAU_GRID_S = (0.01, 0.02, 0.03, 0.045, 0.06, 0.08, 0.11, 0.15)
ONSET_GRID_S = tuple(np.round(np.arange(0.04, 0.26, 0.02), 3))
DURATION_GRID_S = tuple(np.round(np.arange(0.08, 0.32, 0.03), 3))


@dataclass(frozen=True)
class ModelSpec:
    """Which effects are in the model, with their nonlinear hyper-parameters.

    Attributes
    ----------
    effects : tuple of str
        Names from :data:`EFFECT_NAMES`, in the order added.
    tau_s, onset_s, duration_s : float
        Activation time constant and push-off timing (s); used only with those effects.
    latency_s, offset_n : float
        Sensor model (s, N).
    compliance : tuple (c, p) or None
        Toe displacement law ``-c Fz^p`` (m, N).
    ground_damping_n_s_m : float
        Surface damping for forward simulation (N s/m).
    stiff_compliance : tuple (c, p, damping) or None
        Law of the stiffer surface when the recording mixes two surfaces
        (``compliance``/``ground_damping_n_s_m`` are then the softer one's).
    surface_split : float or None
        Stances whose :func:`~hop_impedance.discovery.identify.compliance_index`
        is below this value stand on the stiffer surface.
    """

    effects: tuple[str, ...] = ()
    tau_s: float = 0.04
    onset_s: float = 0.1
    duration_s: float = 0.15
    latency_s: float = 0.0
    offset_n: float = 0.0
    compliance: tuple[float, float] | None = None
    ground_damping_n_s_m: float = 0.0
    stiff_compliance: tuple[float, float, float] | None = None
    surface_split: float | None = None

    def with_effect(self, name: str, **params) -> "ModelSpec":
        """Copy with ``name`` appended and parameters replaced."""
        return replace(self, effects=self.effects + (name,), **params)

    def has(self, name: str) -> bool:
        """Is the effect in the model?"""
        return name in self.effects


def elastic_terms(spec: ModelSpec) -> tuple[str, ...]:
    """Names of the elastic regressors of the joint law."""
    names = ("k0",)
    if spec.has("angle_dependent_stiffness"):
        names += ("k1", "k2")
    if spec.has("rate_dependent_stiffness"):
        names += ("k3",)
    return names


def feature_names(spec: ModelSpec) -> tuple[str, ...]:
    """Regressor names of the joint law, in column order."""
    el = elastic_terms(spec)
    names = el
    if spec.has("time_dependent_activation"):
        names += tuple("act_" + e for e in el)
    if spec.has("joint_damping"):
        names += ("b0", "b1")
    if spec.has("active_push_off"):
        names += ("push",)
    return names


def push_profile(t_s: np.ndarray, onset_s: float, duration_s: float) -> np.ndarray:
    """sin^2 pulse on ``[onset, onset + duration]`` (dimensionless), shape of ``t_s``."""
    phase = (np.asarray(t_s, float) - onset_s) / duration_s
    return np.where((phase >= 0) & (phase <= 1), np.sin(np.pi * np.clip(phase, 0, 1)) ** 2, 0.0)


def features(spec: ModelSpec, t_s, dr, dw, s_int) -> np.ndarray:
    """Regressor matrix of one joint, shape (N, len(feature_names(spec))).

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Time since touchdown (s).
    dr, dw, s_int : ndarray, shape (N,)
        ``rho - rho0`` (rad), ``omega - omega0`` (rad/s), ``S`` (rad^2/s).
    """
    t_s, dr, dw, s_int = (np.asarray(a, float) for a in (t_s, dr, dw, s_int))
    cols = {"k0": dr, "k1": dr**2 / 2, "k2": dr**3 / 3, "k3": s_int, "b0": dw, "b1": dw**2 / 2}
    el = [cols[e] for e in elastic_terms(spec)]
    out = list(el)
    if spec.has("time_dependent_activation"):
        decay = np.exp(-np.maximum(t_s, 0.0) / spec.tau_s)
        out += [-decay * e for e in el]
    if spec.has("joint_damping"):
        out += [cols["b0"], cols["b1"]]
    if spec.has("active_push_off"):
        out.append(push_profile(t_s, spec.onset_s, spec.duration_s))
    return np.stack(out, axis=-1)


def stance_features(spec: ModelSpec, t_s, rho, omega) -> list[np.ndarray]:
    """Per joint regressors of one measured stance (``S`` by trapezoidal integration).

    Parameters
    ----------
    t_s : ndarray, shape (N,)
    rho, omega : ndarray, shape (N, 3)

    Returns
    -------
    list of 3 ndarrays, each (N, n_features)
    """
    from scipy.integrate import cumulative_trapezoid

    dr = rho - rho[0]
    dw = omega - omega[0]
    s_int = cumulative_trapezoid(dw * omega, t_s, axis=0, initial=0.0)
    return [features(spec, t_s, dr[:, j], dw[:, j], s_int[:, j]) for j in range(3)]


@dataclass(frozen=True)
class FittedLaw(ImpedanceLaw):
    """The identified joint law as a simulator torque law (same regressors as the fit).

    Attributes
    ----------
    spec : ModelSpec
    coefficients : ndarray, shape (3, n_features)
        Per joint (ankle, knee, hip), in :func:`feature_names` order (SI).
    touchdown_moment_nm : ndarray, shape (3,)
        ``M_td`` of the stance simulated (N m; nuisance, see ``identify.touchdown_moments``).
    """

    spec: ModelSpec
    coefficients: np.ndarray = field(default_factory=lambda: np.zeros((3, 1)))
    touchdown_moment_nm: np.ndarray = field(default_factory=lambda: np.zeros(3))

    n_states = 3

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102
        dr = np.asarray(rho, float) - ref.rho0_rad
        dw = np.asarray(omega, float) - ref.omega0_rad_s
        s = np.asarray(states, float)
        t = np.broadcast_to(np.asarray(t_s, float), dr.shape[:-1])
        return np.stack([self.touchdown_moment_nm[j] + features(self.spec, t, dr[..., j], dw[..., j], s[..., j])
                         @ self.coefficients[j] for j in range(3)], axis=-1)

    def state_rates(self, t_s, rho, omega, states, ref):  # noqa: D102
        w = np.asarray(omega, float)
        return (w - ref.omega0_rad_s) * w

    def to_dict(self) -> dict:  # noqa: D102
        names = feature_names(self.spec)
        return {"type": "discovery", "terms": list(names), "coefficients": self.coefficients.tolist()}
