"""The model that grows effect by effect: joint law, ground law and sensor model.

Joint law (per joint, pooled over stances, moments extensor positive)
---------------------------------------------------------------------
With ``dr = rho - rho0`` and ``dw = omega - omega0`` (touchdown values),
``S = int (omega - omega0) omega dt``, ``S_speed = int (|omega| - |omega0|) omega dt`` and ``t`` time since
touchdown:

    M = a(t) * E + D + P,
    E = k0 dr [+ k1 dr^2/2 (+ k2 dr^3/3: Eq. 3, ANGLE_TERMS)]  (angle_dependent_stiffness; Eq. 10 by default)
          [+ k3 S] or [+ k3 S_speed] (rate_form)                         (rate_dependent_stiffness)
    D = b0 dw + b1 dw^2/2                                              (joint_damping)
    P = A sin^2(pi (t - onset) / duration) on [onset, onset + duration]  (active_push_off)
    a(t) = 1 - (1 - a_min) exp(-t / tau)          (time_dependent_activation, seed 001: "exp")
    a(t) = a0 + (1 - a0) sin^2(pi t / Ta), t < Ta; a0 after  (seed 000's bell: "bell", Ta = tau_s)

the seed's Eq. 3 integrated (Eqs. 4-5) with ``m0 = 0`` (baseline: zero moment
at touchdown), seed 001's activation and the simulator's push-off shape.

Choice (issue 16): a rate-dependent stiffness ``dM = K dphi`` (Eq. 3) has two readings of "rate": the
signed velocity ``K = k0 + k3 (omega - omega0)`` (integrated: ``k3 S``) and the speed
``K = k0 + k3 (|omega| - |omega0|)`` (``k3 S_speed``, ``rate_form="speed"``; lossless and time-reversible,
since the stiffness then does not know whether the joint flexes or extends; the outside generator's form).
They differ once the joint extends (omega < 0, second half of stance). The candidate identifies the signed
form only: holding both regressors in the candidate (one more coefficient per joint) made it name a false
rate-dependent stiffness on the outside angle recording and on a null of the second generator, and the
outside rate law simulated through our model does not beat the baseline anyway (docs/discovery.md); the speed
form represents that truth law hop by hop (``bench/discovery_truth_gap.py``, tests). Pooled over stances it does
not: the generator simulates ``K = kc + k3 |omega|`` with one ``kc`` (its truth's ``law_simulated``), so its
touchdown-referenced per-hop ``kc_td = kc + k3 |omega0|`` moves with each hop's ``omega0``, which one pooled ``k0``
of ``S_speed`` cannot follow; ``rate_form="abs_speed"`` (``K = k0 + k3 |omega|``, regressor
``S_speed + |omega0| dr = int |omega| omega dt``; session 28, an option) holds it with pooled coefficients.
Likewise the activation's time course has two published shapes: seed 001's rise from ``a_min`` (``exp``) and
seed 000's bell-shaped stiffness with its maximum near mid-stance and non-zero edge values (``bell``), and two
readings of how it acts: on the elastic moment (``secant``, ``a(t) E``, as our simulator) or on the stiffness
in Eq. 3 (``tangent``, ``dM = a(t) K dphi``, integrated ``int a(t) dE``: the outside generator's form,
checked on its stance truth: 0.4 N m RMS against 32 N m for the secant reading); all four are on the candidate's grid. For
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
from functools import cached_property

import numpy as np

from hop_impedance.simulation.impedance_laws import ImpedanceLaw, TouchdownReference

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
#: A candidate of two effects named together (``forward_selection.ENERGY_PAIRS``, session 19) joins their names with
#: this, e.g. ``surface_compliance+active_push_off``; the document's ``effects_found`` lists the two.
PAIR_SEPARATOR = "+"


def members(effect: str) -> tuple[str, ...]:
    """The effects a candidate's name stands for: one, or a pair's two (:data:`PAIR_SEPARATOR`)."""
    return tuple(effect.split(PAIR_SEPARATOR))


#: Effects that act on the joint law (fitted to the ID moments).
JOINT_EFFECTS = ("angle_dependent_stiffness", "rate_dependent_stiffness", "joint_damping",
                 "time_dependent_activation", "active_push_off")
#: Grids of the nonlinear timing parameters (s).
TAU_GRID_S = (0.01, 0.02, 0.03, 0.045, 0.06, 0.08, 0.11, 0.15)
#: Bell activation periods ``Ta`` (s): the bell spans part of or the whole stance.
BELL_GRID_S = (0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5)
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
        Activation time constant (``exp``) or period ``Ta`` (``bell``) and push-off timing (s); used only
        with those effects.
    activation_shape : str
        ``"exp"`` (seed 001) or ``"bell"`` (seed 000), see the module docstring.
    activation_form : str
        ``"secant"`` (``a(t)`` scales the elastic moment) or ``"tangent"`` (``dM = a(t) K dphi``).
    rate_form : str
        ``"signed"`` (``k3 S``, identified), ``"speed"`` (``k3 S_speed``) or ``"abs_speed"``
        (``k3 (S_speed + |omega0| dr)``, ``K = k0 + k3 |omega|``), see the module docstring.
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
    body_fraction : float
        Nuisance, not an effect: share of the analysis table's thigh mass moved to the HAT
        (:mod:`hop_impedance.discovery.body_nuisance`); trials are measured with that body.
    """

    effects: tuple[str, ...] = ()
    tau_s: float = 0.04
    activation_shape: str = "exp"
    activation_form: str = "secant"
    rate_form: str = "signed"
    onset_s: float = 0.1
    duration_s: float = 0.15
    latency_s: float = 0.0
    offset_n: float = 0.0
    compliance: tuple[float, float] | None = None
    ground_damping_n_s_m: float = 0.0
    stiff_compliance: tuple[float, float, float] | None = None
    surface_split: float | None = None
    body_fraction: float = 0.0

    def with_effect(self, name: str, **params) -> ModelSpec:
        """Copy with ``name`` appended and parameters replaced."""
        return replace(self, effects=self.effects + (name,), **params)

    def has(self, name: str) -> bool:
        """Is the effect in the model?"""
        return name in self.effects


#: Terms the angle-dependent stiffness adds to ``k0``: seed 000's reduced Eq. 10 ``K = k0 + k1 (rho - rho0)``, the
#: default since session 30, or its Eq. 3 ``k1``, ``k2`` (``("k1", "k2")``, the default of sessions 1-29). Why the
#: reduced law: it is the model seed 000's F-tests reduce Eq. 3 to and the one a controller is given, and on the second
#: generator's touchdown-referenced angle law (K from 0.33 of its mid-stance value at the ankle) the pooled fit on the
#: stances' cores with ``k2`` extrapolates K at touchdown badly (seed 1: ankle 269 - 235 d + 264 d^2 against the
#: truth's 86 + 215 d; k0 + k1 alone: 160 + 109 d), and at the hip, whose 0.07-0.2 rad of flexion leave the ID
#: moment's body errors (8-24 N m RMS) to dominate, k1/k2 came out at +-1e4..2e5 and the simulation blew up.
#: Measured before the switch (docs/discovery.md, "Session 29 (lead)" and "Session 30"): outside 5/8 exact and 0/6
#: false (Eq. 3's names file for file), our simulator's sweep 3/10 (as Eq. 3), its 60 nulls 0/60 and the second
#: generator's 0/60, that generator's angle law 3/9 (Eq. 3: 2/9).
ANGLE_TERMS: tuple[str, ...] = ("k1",)


def elastic_terms(spec: ModelSpec) -> tuple[str, ...]:
    """Names of the elastic regressors of the joint law."""
    names: tuple[str, ...] = ("k0",)
    if spec.has("angle_dependent_stiffness"):
        names += ANGLE_TERMS
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


def activation_modulation(spec: ModelSpec, t_s) -> np.ndarray:
    """``g(t)`` with ``a(t) E = E + sum_k c_k g(t) E_k`` (linear in ``c_k``): ``-exp(-t/tau)`` or the bell."""
    t = np.maximum(np.asarray(t_s, float), 0.0)
    if spec.activation_shape == "bell":
        return np.where(t < spec.tau_s, np.sin(np.pi * t / spec.tau_s) ** 2, 0.0)
    return -np.exp(-t / spec.tau_s)


#: Elastic terms whose tangent-form activation integrals are law states (fixed order).
ELASTIC_ALL = ("k0", "k1", "k2", "k3", "k3_speed")


def elastic_rates(dr, w, w0) -> list:
    """``dE_k/dt`` of :data:`ELASTIC_ALL` (``dr``, ``omega``, ``omega0`` broadcast)."""
    return [w, dr * w, dr**2 * w, (w - w0) * w, (np.abs(w) - np.abs(w0)) * w]


def rate_column(spec: ModelSpec, s_int, s_speed, dr, w0, k0_col=None):
    """The ``k3`` regressor of :attr:`ModelSpec.rate_form`: ``S``, ``S_speed`` or ``S_speed + |omega0| dr``
    (``abs_speed``: ``int |omega| omega dt``). With ``k0_col`` given, ``s_speed`` and ``k0_col`` are the tangent-form
    integrals of ``k3_speed`` and ``k0`` and the same sum gives ``abs_speed``'s."""
    if spec.rate_form == "signed":
        return s_int
    if spec.rate_form == "speed":
        return s_speed
    return s_speed + np.abs(w0) * (dr if k0_col is None else k0_col)


def angle_column(term: str, dr, held=None):
    """The ``k1`` / ``k2`` regressor ``dr^2/2`` / ``dr^3/3``; with ``held`` (``dr`` clipped to a range,
    :attr:`FittedLaw.angle_range`) its continuation past the range at the edge's stiffness, ``c^2/2 + c (dr - c)`` /
    ``c^3/3 + c^2 (dr - c)`` with ``c = held``: the same inside the range, the moment's slope there held outside."""
    if held is None:
        return dr**2 / 2 if term == "k1" else dr**3 / 3
    return held**2 / 2 + held * (dr - held) if term == "k1" else held**3 / 3 + held**2 * (dr - held)


def features(spec: ModelSpec, t_s, dr, dw, s_int, s_speed=None, tangent=None, w0=None, held=None) -> np.ndarray:
    """Regressor matrix of one joint, shape (N, len(feature_names(spec))): :func:`feature_columns` side by side.

    Parameters
    ----------
    t_s : ndarray, shape (N,)
        Time since touchdown (s).
    dr, dw, s_int : ndarray, shape (N,)
        ``rho - rho0`` (rad), ``omega - omega0`` (rad/s), ``S`` (rad^2/s).
    s_speed : ndarray, shape (N,)
        ``S_speed`` (rad^2/s); needed only with ``rate_form`` ``"speed"`` or ``"abs_speed"``.
    tangent : ndarray, shape (N, 5)
        ``int g(t) dE_k`` of :data:`ELASTIC_ALL`; needed only with a tangent-form activation.
    w0 : float or ndarray
        ``omega0`` (rad/s); needed only with ``rate_form="abs_speed"``.
    held : ndarray, shape (N,), optional
        ``dr`` clipped to a range for the angle terms (:func:`angle_column`); None: the polynomial everywhere.
    """
    out = feature_columns(spec, t_s, dr, dw, s_int, s_speed, tangent, w0, held)
    dr = np.asarray(dr, float)
    matrix = np.empty(dr.shape + (len(out),))  # what np.stack(out, axis=-1) returns, without its generic checks
    for k, column in enumerate(out):
        matrix[..., k] = column
    return matrix


def feature_columns(spec: ModelSpec, t_s, dr, dw, s_int, s_speed=None, tangent=None, w0=None, held=None) -> list:
    """The regressors of :func:`features` (same arguments), one array per column in :func:`feature_names` order; a
    column of time alone (activation, push) keeps ``t_s``'s shape, so a scalar time broadcasts over the joints."""
    t_s, dr, dw, s_int = np.asarray(t_s, float), np.asarray(dr, float), np.asarray(dw, float), np.asarray(s_int, float)
    # only the columns the spec uses: the simulator evaluates them at every step (FittedLaw.moments_nm)
    el = [dr if e == "k0" else angle_column(e, dr, held) if e in ("k1", "k2")
          else rate_column(spec, s_int, s_speed, dr, w0) for e in elastic_terms(spec)]
    out = list(el)
    if spec.has("time_dependent_activation"):
        if spec.activation_form == "tangent":
            col = {e: tangent[..., i] for i, e in enumerate(ELASTIC_ALL)}
            out += [rate_column(spec, col["k3"], col["k3_speed"], dr, w0, col["k0"]) if e == "k3" else col[e]
                    for e in elastic_terms(spec)]
        else:
            g = activation_modulation(spec, t_s)
            out += [g * e for e in el]
    if spec.has("joint_damping"):
        out += [dw, dw**2 / 2]
    if spec.has("active_push_off"):
        out.append(push_profile(t_s, spec.onset_s, spec.duration_s))
    return out


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
    s_speed = cumulative_trapezoid((np.abs(omega) - np.abs(omega[0])) * omega, t_s, axis=0, initial=0.0)
    tangent: list[np.ndarray | None] = [None] * 3
    if spec.has("time_dependent_activation") and spec.activation_form == "tangent":
        g = activation_modulation(spec, t_s)
        tangent = [np.stack([cumulative_trapezoid(g * r, t_s, initial=0.0)
                             for r in elastic_rates(dr[:, j], omega[:, j], omega[0, j])], axis=-1) for j in range(3)]
    return [features(spec, t_s, dr[:, j], dw[:, j], s_int[:, j], s_speed[:, j], tangent[j], omega[0, j])
            for j in range(3)]


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
    reference : TouchdownReference or None
        ``rho0``/``omega0`` of the regressors (:func:`stance_features` takes them from the measured stance's first
        sample, and ``M_td`` is estimated against them); None: the simulator's, read from the state the simulation
        starts from. Session 15: the law keeps the identification's reference when the simulation starts from
        another touchdown state (``measurement.TOUCHDOWN_STATE``); with the filtered kinematics' state both are the
        same numbers.
    angle_range : ndarray, shape (3, 2), or None
        Per joint the ``rho - rho0`` range (rad, low, high) past which the angle terms' stiffness ``k1 dr + k2 dr^2``
        is held at the edge's value (:func:`angle_column`; ``forward_selection.ANGLE_HOLD``, session 29); None: the
        polynomial everywhere.
    """

    spec: ModelSpec
    coefficients: np.ndarray = field(default_factory=lambda: np.zeros((3, 1)))
    touchdown_moment_nm: np.ndarray = field(default_factory=lambda: np.zeros(3))
    reference: TouchdownReference | None = None
    angle_range: np.ndarray | None = None

    def held(self, dr):
        """``dr`` clipped to :attr:`angle_range` (None without one)."""
        return None if self.angle_range is None else np.clip(dr, self.angle_range[:, 0], self.angle_range[:, 1])

    @cached_property  # read at every right-hand side (state_rates)
    def n_states(self) -> int:
        """``S`` and ``S_speed`` per joint, then ``int g(t) dE_k`` per term of :data:`ELASTIC_ALL` and joint (state
        ``6 + 3 m + j``); integrated only when the moment reads them, with a rate term (``k3``) or a tangent-form
        activation, else none. Session 35: LSODA's finite-difference Jacobian costs one right-hand side per state,
        and the 21 states integrated always, unread by most models, took 928 of a held-out stance's 1304 right-hand
        sides (docs/discovery.md, Runtime, session 35)."""
        tangent = self.spec.has("time_dependent_activation") and self.spec.activation_form == "tangent"
        return 6 + 3 * len(ELASTIC_ALL) if tangent or "k3" in elastic_terms(self.spec) else 0

    def moments_nm(self, t_s, rho, omega, states, ref):  # noqa: D102
        # all three joints in one call of feature_columns() (joint axis before the regressor axis): the same
        # regressors as the fit; the simulator calls this at every step, so it is its hot path
        ref = self.reference or ref
        dr = np.asarray(rho, float) - ref.rho0_rad
        dw = np.asarray(omega, float) - ref.omega0_rad_s
        s = np.asarray(states, float)
        one_instant = dr.ndim == 1 and np.ndim(t_s) == 0
        # one instant: the time's columns (activation, push) broadcast over the joints as a scalar
        t = t_s if one_instant else np.broadcast_to(np.asarray(t_s, float)[..., None], dr.shape)
        tangent = None  # read by feature_columns() only with a tangent-form activation
        if self.spec.has("time_dependent_activation") and self.spec.activation_form == "tangent":
            tangent = np.swapaxes(s[..., 6:].reshape(s.shape[:-1] + (len(ELASTIC_ALL), 3)), -1, -2)
        columns = feature_columns(self.spec, t, dr, dw, s[..., 0:3], s[..., 3:6], tangent, ref.omega0_rad_s,
                                  self.held(dr))
        # the columns summed in order, the same operations at one instant (the simulator's call at every step, where
        # a regressor matrix and einsum's dispatch cost more than the sum) and over a batch
        total = self.coefficients[:, 0] * columns[0]
        for coefficient, column in zip(self.coefficients.T[1:], columns[1:]):
            total = total + coefficient * column
        return self.touchdown_moment_nm + total

    def state_rates(self, t_s, rho, omega, states, ref):  # noqa: D102
        ref = self.reference or ref
        w = np.asarray(omega, float)
        w0 = ref.omega0_rad_s
        if not self.n_states:
            return np.zeros(w.shape[:-1] + (0,))
        if not self.spec.has("time_dependent_activation"):  # the activation integrals stay 0
            out = np.zeros(w.shape[:-1] + (self.n_states,))
            out[..., 0:3] = (w - w0) * w
            out[..., 3:6] = (np.abs(w) - np.abs(w0)) * w
            return out
        rates = [(w - w0) * w, (np.abs(w) - np.abs(w0)) * w]
        g = np.asarray(activation_modulation(self.spec, t_s), float)
        g = g[..., None] if g.ndim else g
        dr = np.asarray(rho, float) - ref.rho0_rad
        held = self.held(dr)  # d/dt of angle_column's continuation: held dr in place of dr
        return np.concatenate(rates + [g * r for r in elastic_rates(dr if held is None else held, w, w0)], axis=-1)

    def to_dict(self) -> dict:  # noqa: D102
        names = feature_names(self.spec)
        return {"type": "discovery", "terms": list(names), "coefficients": self.coefficients.tolist()}
