"""``impedance_estimator``: one impedance fit per joint per stance, and the controller feed.

Subscribes ``/stance/kinetics`` (one message per stance from
``inverse_dynamics``), fits the seed paper's model to ankle, knee and hip with
:func:`hop_impedance.impedance.recording_fits.fit_stance_joints` (the same
call, options and warm-started OSQP workspaces as ``hop-impedance analyze``)
and publishes, per stance:

- three ``ImpedanceProfile`` on ``/impedance/profile`` (reliable): accepted
  with coefficients and fit statistics, or ``accepted = false`` with the
  rejection reason;
- one ``StanceSummary`` on ``/impedance/stance_summary`` (reliable);
- one ``ControllerImpedance`` on ``/impedance/controller`` (reliable,
  transient-local depth 1: a controller that starts late gets the latest
  values at once), for *every* stance, accepted or not, and once at start
  (all joints invalid). A joint is ``valid`` only if its stance passed the
  input checks (:mod:`hop_impedance.input_checks`, run by ``inverse_dynamics``),
  its fit was accepted and the fit is physically plausible
  (:func:`hop_impedance.impedance.plausibility.controller_rejection`, bounds
  from the parameters ``min_r_squared``, ``k0_factor``, ``k1_factor``,
  ``damping_tolerance``). See docs/pipeline.md, "The controller's contract".

  Issue 21: the feed also carries ``side`` (parameter; ``lumped`` today),
  the ``subject_id`` of ``/subject``, the stance's touchdown / take-off
  stamps, each coefficient's standard error, and the pooled estimate over the
  last ``pool_stances`` valid stances (:mod:`hop_impedance.impedance.pooling`).
  The feed invalidates itself, by publishing ``valid = false`` with
  ``invalid_reason``: when a valid value is older than ``max_age_s`` (wall
  clock since its take-off reached ``inverse_dynamics``; checked every
  ``max_age_s / 10``), and when ``/subject`` changes (values set to NaN, pool
  emptied; a stance that touched down before the new ``/subject``'s stamp, or
  was analysed for another body mass than ``/subject``'s, is not valid).

A stance rejected by an input check turns this node's ``/diagnostics`` to
ERROR with the rule's reason.

Issue 15: in low-latency mode a stance arrives 5 ms after its *provisional*
take-off. If the detector withdraws that take-off (the force came back within
``min_flight_s``), ``inverse_dynamics`` sends the stance again rejected with
:data:`stages.WITHDRAWN`: its fits leave the pools, and the feed publishes
every joint ``valid = false`` with that reason until the stance's real
take-off brings it again.

Model structure (one per joint for the session, ``recording_fits``, "One
model per trial"): ``model_terms_ankle``, ``model_terms_knee``,
``model_terms_hip`` (default the seed's reduced model k0, k1, b0) are fitted
to every stance; with ``model_warmup_stances`` N > 0 the
structure is instead chosen by the offline rule over the first N stances
(fitted with the seed's k0, k1, b0 meanwhile) and kept from then on. The
profiles' ``terms`` carry it and ``/diagnostics`` says which and why
(``model_ankle``, ...).

``latency_s`` of a profile = wall-clock now minus the arrival of the first
force sample at or after take-off at ``inverse_dynamics``
(``StanceKinetics.takeoff_received_ns``); both nodes run on one machine.
"""

from __future__ import annotations

import collections
import math
import time

import numpy as np
from hop_impedance_msgs.msg import ControllerImpedance, ImpedanceProfile, StanceKinetics, StanceSummary, SubjectInfo
from rclpy.node import Node

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.biomech.stages import WITHDRAWN, equivalent_linear_impedance
from hop_impedance.impedance.plausibility import PlausibilityBounds, controller_damping, controller_rejection
from hop_impedance.impedance.pooling import StancePool
from hop_impedance.impedance.recording_fits import SEED_TERMS, StructureSelector, default_fit_options, fit_stance_joints
from hop_impedance.impedance.stance_fit import JointImpedanceFit
from hop_impedance.input_checks import INPUT_CHECK_PREFIX
from hop_impedance.nodes.common import (
    CONTROLLER_TOPIC,
    PROFILE_TOPIC,
    STANCE_KINETICS_TOPIC,
    SUMMARY_TOPIC,
    Diagnostics,
    declare,
    float64_sequence,
    percentile_ms,
    stamp_ns,
)
from hop_impedance.nodes.inverse_dynamics import stance_from_message
from hop_impedance.nodes.qos import STANCE_HISTORY, history_qos, latched_qos, result_qos
from hop_impedance.recording import GRAVITY_M_S2, SUBJECT_TOPIC

#: Default stated maximum age of a valid controller value (s); reasoning in docs/pipeline.md ("How old").
MAX_AGE_S = 2.0
#: Stances a controller value may have been analysed for another mass than /subject's: relative tolerance.
MASS_TOLERANCE = 0.005


class ImpedanceEstimatorNode(Node):
    """Fits each stance and publishes profiles, summary and controller feed; see the module docstring."""

    def __init__(self, **kwargs) -> None:
        super().__init__("impedance_estimator", **kwargs)
        diag = declare(self, "diagnostics_period_s", 1.0, "publish /diagnostics this often (s); 0 = never")
        from hop_impedance.biomech.analysis import AnalysisOptions

        # the same default as inverse_dynamics' (the analysis' one); set both together (config/pipeline.yaml)
        cutoff = declare(self, "cutoff_hz", AnalysisOptions().marker_cutoff_hz,
                         "low-pass cut-off the joint data were filtered with (Hz): the fit's noise bandwidth")
        self.options = default_fit_options(AnalysisOptions(marker_cutoff_hz=cutoff, force_cutoff_hz=cutoff))
        d = PlausibilityBounds()
        self.bounds = PlausibilityBounds(
            min_r_squared=declare(self, "min_r_squared", d.min_r_squared, "controller feed: least R^2 of a valid fit"),
            k0_factor=declare(self, "k0_factor", d.k0_factor, "controller feed: k0 within this factor of Table 2 (mass-scaled)"),
            k1_factor=declare(self, "k1_factor", d.k1_factor, "controller feed: |k1| at most this times Table 2 (mass-scaled)"),
            damping_tolerance=declare(self, "damping_tolerance", d.damping_tolerance,
                                      "controller feed: b_eq down to minus this is published as 0 (N m s/rad)"),
        )
        self.valid = np.zeros(3, int)
        self.input_failure = ""
        self.last_invalid = ""
        warmup = declare(self, "model_warmup_stances", 0, "choose the model structure over the first N stances (0 = model_terms)")
        terms = {j: declare(self, f"model_terms_{j}", list(SEED_TERMS), f"{j}: model structure fitted to every stance "
                            "when model_warmup_stances is 0") for j in JOINT_NAMES}
        self.selector = StructureSelector(
            self.options, None if warmup > 0 else terms, max(warmup, 1),
            "given (model_terms_<joint>; default: the seed's reduced model, its Eq. 10, fitted to every stance so "
            "the coefficients mean the same in each; model_warmup_stances N chooses from the first N stances)")
        self.selector.warm_up()  # the first-call costs of a fit are paid here, not by the first stance's profile
        self._stance_solvers: dict = {}  # OSQP workspaces of the per-stance reductions (warm start)
        self.fit_s, self.fit_cpu_s = [], []  # type: list[float], list[float]  # fit wall (the feed waits) and CPU time
        self.latency_s, self.receipt_s = [], []  # type: list[float], list[float]  # take-off -> feed out / stance heard
        self.stances_in = 0
        self.accepted, self.rejected = np.zeros(3, int), np.zeros(3, int)
        side = declare(self, "side", "lumped", "controller feed: which leg the values are for (lumped, left, right)")
        if side not in ("lumped", "left", "right"):
            raise ValueError(f"parameter side must be lumped, left or right, got {side!r}")
        self.max_age_s = float(declare(self, "max_age_s", MAX_AGE_S, "controller feed: a valid value older than this (s, "
                                       "since its take-off reached inverse_dynamics) is republished invalid; 0 = no age "
                                       "rule (only for replays faster than real time, where wall-clock age means nothing)"))
        pool_n = declare(self, "pool_stances", 10, "controller feed: pool each coefficient over the last N valid stances")
        self.pools = {name: StancePool(pool_n) for name in JOINT_NAMES}
        self.valid_since_ns = [0, 0, 0]  # wall clock (ns) at which each valid value's take-off reached the pipeline
        self.subject_key: tuple | None = None
        self.feed_mass_kg = math.nan  # body mass the latest stance was analysed for
        self.subject_since_ns = 0  # touchdowns before this stamp belong to the previous subject
        self.feed = _empty_feed(side, self.max_age_s, pool_n)
        self.pub_profile = self.create_publisher(ImpedanceProfile, PROFILE_TOPIC, result_qos())
        self.pub_summary = self.create_publisher(StanceSummary, SUMMARY_TOPIC, result_qos())
        self.pub_feed = self.create_publisher(ControllerImpedance, CONTROLLER_TOPIC, latched_qos())
        self.pub_feed.publish(self.feed)  # nothing valid until a stance passed every check
        # transient-local: started mid-session, the recent stances arrive at once (de-duplicated by touchdown stamp)
        self.create_subscription(StanceKinetics, STANCE_KINETICS_TOPIC, self._on_stance, history_qos())
        self.create_subscription(SubjectInfo, SUBJECT_TOPIC, self._on_subject, latched_qos())
        if self.max_age_s > 0:
            self.create_timer(self.max_age_s / 10.0, self._expire)
        # (touchdown ns, take-off ns, withdrawn) of the stances heard: a provisional stance, its withdrawal
        # and the same stance at its real take-off are three different messages
        self.seen_touchdowns: collections.deque = collections.deque(maxlen=4 * STANCE_HISTORY)
        self.last_pooled: tuple = (None, {})  # (touchdown, take-off) of the last stance and its pooled fits
        self.diagnostics = Diagnostics(self, diag, self._diag_values, self._diag_level)

    def _on_stance(self, msg: StanceKinetics) -> None:
        touchdown_ns = stamp_ns(msg.touchdown_stamp)
        withdrawn = msg.rejection_reason.startswith(WITHDRAWN)
        key = (touchdown_ns, stamp_ns(msg.takeoff_stamp), withdrawn)
        if key in self.seen_touchdowns:  # heard live and again from the transient-local history
            return
        self.seen_touchdowns.append(key)
        if withdrawn and self.last_pooled[0] == key[:2]:
            # the provisional take-off was a dip: its fits leave the pools; the feed turns invalid below
            for name, fit in self.last_pooled[1].items():
                self.pools[name].withdraw(fit)
        t_start, cpu_start = time.perf_counter(), time.thread_time()
        if msg.takeoff_received_ns and not withdrawn:  # inverse_dynamics' part and the delivery to this node
            self.receipt_s.append((time.time_ns() - msg.takeoff_received_ns) * 1e-9)
        self.stances_in += 1
        stance = stance_from_message(msg)
        was_fixed = self.selector.fixed
        fits, stance_fits = self.selector.fit(stance)
        if self.selector.fixed and not was_fixed:
            self.get_logger().info("model structure: " + "; ".join(
                f"{j} {' '.join(s.terms)} ({s.reason})" for j, s in self.selector.structures.items()))
        self.fit_s.append(time.perf_counter() - t_start)
        self.fit_cpu_s.append(time.thread_time() - cpu_start)
        latency = (time.time_ns() - msg.takeoff_received_ns) * 1e-9 if msg.takeoff_received_ns else math.nan
        if math.isfinite(latency) and not withdrawn:
            self.latency_s.append(latency)
        # the controller first (its latency is the one that matters), then the per-stance reports
        before = (f"stance touched down before /subject changed to {self.feed.subject_id!r}"
                  if touchdown_ns < self.subject_since_ns else None)
        subject_mass = self.subject_key[1] if self.subject_key is not None else None
        reasons = update_feed(self.feed, msg, stance, fits, self.bounds, self.pools, before, subject_mass)
        self.feed_mass_kg = stance_mass_kg(msg)
        self.last_pooled = (key[:2], {name: fits[name] for name in JOINT_NAMES if reasons[name] is None})
        for j, name in enumerate(JOINT_NAMES):
            if reasons[name] is None:
                self.valid_since_ns[j] = msg.takeoff_received_ns or time.time_ns()
        self._expire(publish=False)  # a stance that arrives already too old is not valid
        self.pub_feed.publish(self.feed)
        if stance_fits is None:  # structure fixed: this stance's own diagnostics and F-tests, reported beside it
            stance_fits = fit_stance_joints(stance, self.options, self._stance_solvers)
        for j, name in enumerate(JOINT_NAMES):
            self.pub_profile.publish(profile_message(msg, name, fits[name], latency, stance_fits[name]))
            if fits[name].ok:
                self.accepted[j] += 1
            else:
                self.rejected[j] += 1
        self.pub_summary.publish(summary_message(msg, fits))
        for j, name in enumerate(JOINT_NAMES):
            self.valid[j] += reasons[name] is None
            if reasons[name] is not None:
                self.last_invalid = f"stance {msg.stance_index} {name}: {reasons[name]}"
        if msg.rejection_reason.startswith(INPUT_CHECK_PREFIX):
            self.input_failure = msg.rejection_reason
        self.diagnostics.sample_ns = stamp_ns(msg.header.stamp)

    def _on_subject(self, msg: SubjectInfo) -> None:
        """A new subject: everything latched from the previous one is invalid (published), the pool emptied."""
        key = (msg.subject_id, float(msg.body_mass), float(msg.body_height))
        if key == self.subject_key:
            return  # the same /subject again (a looped replay, a late transient-local copy)
        # The first /subject heard is a change only if the latched valid values were analysed for another body
        # mass: in separate processes /subject can reach this node after the first stance (discovery order),
        # and that stance was analysed for this very subject by inverse_dynamics.
        changed = self.subject_key is not None or (any(self.feed.valid) and not (
            abs(self.feed_mass_kg - msg.body_mass) <= MASS_TOLERANCE * msg.body_mass))
        old = self.feed.subject_id
        self.subject_key = key
        self.feed.subject_id = msg.subject_id
        if not changed:
            return
        self.subject_since_ns = stamp_ns(msg.header.stamp)
        for pool in self.pools.values():
            pool.clear()
        reason = f"subject changed from {old!r} to {msg.subject_id!r}"
        reset_feed(self.feed, reason)
        self.last_invalid = reason
        self.pub_feed.publish(self.feed)

    def _expire(self, publish: bool = True) -> None:
        """Mark valid values older than ``max_age_s`` invalid; publish if any changed (``publish``)."""
        if self.max_age_s <= 0:
            return
        now = time.time_ns()
        valid, reasons = list(self.feed.valid), list(self.feed.invalid_reason)
        for j, name in enumerate(JOINT_NAMES):
            age_s = (now - self.valid_since_ns[j]) * 1e-9
            if valid[j] and age_s > self.max_age_s:
                valid[j] = False
                reasons[j] = f"older than max_age_s {self.max_age_s:g} s (take-off {age_s:.2f} s ago)"
                self.last_invalid = f"stance {self.feed.stance_index} {name}: {reasons[j]}"
        if valid != list(self.feed.valid):
            self.feed.valid, self.feed.invalid_reason = valid, reasons
            if publish:
                self.pub_feed.publish(self.feed)

    def _diag_values(self) -> dict:
        out: dict[str, object] = {"stances_received": self.stances_in,
               "fit_p50_ms": percentile_ms(self.fit_s, 50), "fit_p99_ms": percentile_ms(self.fit_s, 99),
               "fit_cpu_p50_ms": percentile_ms(self.fit_cpu_s, 50), "fit_cpu_p99_ms": percentile_ms(self.fit_cpu_s, 99),
               "takeoff_to_profile_p50_ms": percentile_ms(self.latency_s, 50),
               "takeoff_to_profile_p99_ms": percentile_ms(self.latency_s, 99),
               "takeoff_to_receipt_p50_ms": percentile_ms(self.receipt_s, 50),
               "takeoff_to_receipt_p99_ms": percentile_ms(self.receipt_s, 99)}
        for j, name in enumerate(JOINT_NAMES):
            out[f"{name}_accepted"] = int(self.accepted[j])
            out[f"{name}_rejected"] = int(self.rejected[j])
            s = self.selector.structures[name]
            out[f"model_{name}"] = f"{' '.join(s.terms)}: {s.reason}"
            out[f"{name}_controller_valid"] = int(self.valid[j])
        out["last_controller_invalid"] = self.last_invalid
        out["input_check"] = self.input_failure or "ok"
        return out

    def _diag_level(self) -> tuple[int, str]:
        return (2, self.input_failure) if self.input_failure else (0, "ok")


def _c(fit: JointImpedanceFit, name: str) -> float:
    """Coefficient ``name`` of a fit; 0 for a term removed by the reduction, NaN for a rejected fit."""
    if not fit.ok:
        return math.nan
    return float(fit.coefficients.get(name, 0.0))


def _f(x) -> float:
    return math.nan if x is None else float(x)


def profile_message(stance: StanceKinetics, joint: str, fit: JointImpedanceFit, latency_s: float,
                    stance_fit: JointImpedanceFit | None = None) -> ImpedanceProfile:
    """One joint's fit as an ``ImpedanceProfile`` (rejection: ``accepted`` false with the reason).

    ``stance_fit``: the same stance fitted with its own reduction (per-stance F-tests); its kept terms
    go to ``stance_terms``.
    """
    msg = ImpedanceProfile(stance_index=stance.stance_index, joint=joint, accepted=fit.ok,
                           rejection_reason=fit.rejection_reason or "", solver_status=fit.status)
    msg.header = stance.header
    msg.touchdown_stamp, msg.takeoff_stamp = stance.touchdown_stamp, stance.takeoff_stamp
    msg.latency_s = float(latency_s)
    if fit.reduction is not None or fit.terms:
        msg.terms = list(fit.terms)
        msg.coefficients = [_f(fit.coefficients.get(t)) for t in fit.terms]
        msg.std_errors = [_f(fit.std_errors.get(t)) for t in fit.terms]
        msg.p_values = [_f(fit.p_values.get(t)) for t in fit.terms]
    if stance_fit is not None and stance_fit.reduction is not None:
        msg.stance_terms = list(stance_fit.terms)
    msg.rho0_rad, msg.omega0_rad_s = _f(fit.rho0), _f(fit.omega0)
    msg.moment0_nm = float(fit.moment_nm[0]) if fit.moment_nm.size else math.nan
    if fit.ok:
        msg.time_s = float64_sequence(fit.time_s)
        msg.angle_rad = float64_sequence(fit.angle_rad)
        msg.stiffness_nm_per_rad = float64_sequence(fit.stiffness)
        msg.damping_nms_per_rad = float64_sequence(fit.damping)
        msg.moment_measured_nm = float64_sequence(fit.moment_nm)
        msg.moment_fit_nm = float64_sequence(fit.moment_fit)
    msg.rmse_nm, msg.r_squared = float(fit.rmse), float(fit.r_squared)
    msg.sse_variable, msg.sse_constant = float(fit.sse_variable), float(fit.sse_constant)
    msg.table3_error_variable, msg.table3_error_constant = float(fit.table3_variable), float(fit.table3_constant)
    msg.overall_stiffness_nm_per_rad = float(fit.overall_stiffness)
    msg.average_stiffness_nm_per_rad = float(fit.average_stiffness)
    msg.constant_stiffness_nm_per_rad = float(fit.overall_stiffness)
    msg.initial_stiffness_nm_per_rad = fit.initial_stiffness
    msg.max_stiffness_nm_per_rad = fit.max_stiffness
    if fit.diagnostics is not None:
        d = fit.diagnostics
        with np.errstate(over="ignore"):
            msg.hessian_determinant = float(np.power(10.0, d.hessian_log10_determinant))
        msg.eigenvalue_ratio = float(d.hessian_eigenvalue_ratio)
        msg.vif_terms = list(d.terms)
        msg.vif = float64_sequence(d.variance_inflation_factors)
    return msg


def summary_message(stance: StanceKinetics, fits: dict[str, JointImpedanceFit]) -> StanceSummary:
    """The per-stance line: events, global measures and each joint's k0, k1, R^2."""
    msg = StanceSummary(stance_index=stance.stance_index, complete=stance.complete,
                        rejection_reason=stance.rejection_reason)
    msg.header = stance.header
    msg.touchdown_stamp, msg.takeoff_stamp = stance.touchdown_stamp, stance.takeoff_stamp
    for name in ("contact_time_s", "peak_grf_n", "peak_grf_bw", "hop_frequency_hz", "leg_stiffness_n_per_m", "hip_excursion_m"):
        setattr(msg, name, getattr(stance, name))
    msg.flight_time_before_s = stance.flight_time_before_s
    msg.force_samples_lost_before = stance.force_samples_lost_before
    msg.force_samples_lost_in_stance = stance.force_samples_lost_in_stance
    ordered = [fits[n] for n in JOINT_NAMES]
    msg.k0 = [_c(f, "k0") for f in ordered]
    msg.k1 = [_c(f, "k1") for f in ordered]
    msg.r_squared = [float(f.r_squared) if f.ok else math.nan for f in ordered]
    msg.accepted = [f.ok for f in ordered]
    if not msg.rejection_reason and not all(msg.accepted):
        msg.rejection_reason = "; ".join(f"{n}: {fits[n].rejection_reason}" for n in JOINT_NAMES if not fits[n].ok)
    return msg


#: Per-joint value fields of ControllerImpedance (NaN until a valid stance; kept while invalid).
VALUE_FIELDS = ("k0_nm_per_rad", "k1_nm_per_rad2", "b0_nms_per_rad", "rho0_rad", "omega0_rad_s", "tau0_nm",
                "stiffness_eq_nm_per_rad", "damping_eq_nms_per_rad", "equilibrium_angle_rad",
                "k0_std_error", "k1_std_error", "b0_std_error")
#: Pooled fields: message field -> (coefficient, value or standard error).
POOLED_FIELDS = {"pooled_k0_nm_per_rad": ("k0", "value"), "pooled_k0_std_error": ("k0", "std_error"),
                 "pooled_k1_nm_per_rad2": ("k1", "value"), "pooled_k1_std_error": ("k1", "std_error"),
                 "pooled_b0_nms_per_rad": ("b0", "value"), "pooled_b0_std_error": ("b0", "std_error"),
                 **{f"pooled_{t}_chi2_per_dof": (t, "chi2_per_dof") for t in ("k0", "k1", "b0")}}


def _empty_feed(side: str = "lumped", max_age_s: float = MAX_AGE_S, pool_size: int = 0) -> ControllerImpedance:
    msg = ControllerImpedance(side=side, max_age_s=float(max_age_s), pool_size=int(pool_size))
    reset_feed(msg, "no valid stance yet")
    return msg


def reset_feed(feed: ControllerImpedance, reason: str) -> None:
    """Every joint invalid with ``reason``, every value and pooled value NaN, pooled counts 0."""
    for name in (*VALUE_FIELDS, *POOLED_FIELDS):
        setattr(feed, name, [math.nan] * 3)
    feed.pooled_n_stances = [0] * 3
    feed.valid = [False] * 3
    feed.invalid_reason = [reason] * 3


def stance_mass_kg(stance: StanceKinetics) -> float:
    """Body mass inverse_dynamics analysed the stance for: ``peak_grf_n / (peak_grf_bw g)`` (NaN if unknown)."""
    return stance.peak_grf_n / (stance.peak_grf_bw * GRAVITY_M_S2) if stance.peak_grf_bw > 0 else math.nan


def update_feed(feed: ControllerImpedance, stance: StanceKinetics, stance_result, fits: dict[str, JointImpedanceFit],
                bounds: PlausibilityBounds | None = None, pools: dict[str, StancePool] | None = None,
                reason: str | None = None, subject_mass_kg: float | None = None) -> dict[str, str | None]:
    """Update the controller feed with this stance; returns why each joint is not valid (None = valid).

    A joint is valid when the stance has no rejection reason (input checks, loss,
    markers), its fit was accepted and
    :func:`~hop_impedance.impedance.plausibility.controller_rejection` finds it
    physically plausible; its entries are then overwritten with this stance's
    values. ``tau0`` is the fitted moment at touchdown (``m0``, 0 if reduced
    away); the equivalent linear impedance comes from
    :func:`stages.equivalent_linear_impedance` on the measured moment, b_eq
    published through :func:`~hop_impedance.impedance.plausibility.controller_damping`
    (never negative). Invalid joints keep their previous values and get
    ``valid = false``. Body mass (for the Table 2 scaling) is the one
    inverse_dynamics used: ``peak_grf_n / (peak_grf_bw g)``.

    Issue 21: ``reason`` (if given) makes every joint invalid like a stance
    rejection; with ``subject_mass_kg`` (``/subject``'s), a stance analysed for
    a body mass more than 0.5 % away is not valid (analysed for another
    subject). Valid joints' fits enter ``pools`` (one
    :class:`~hop_impedance.impedance.pooling.StancePool` per joint) and the
    pooled k0, k1, b0 with their standard errors are published; each
    coefficient's own standard error comes from the fit (NaN for a term held
    at a bound or not fitted).
    """
    feed.header = stance.header
    feed.stance_index = stance.stance_index
    feed.touchdown_stamp, feed.takeoff_stamp = stance.touchdown_stamp, stance.takeoff_stamp
    arrays = {n: list(getattr(feed, n)) for n in VALUE_FIELDS}
    stance_reason = stance.rejection_reason or reason
    reasons: dict[str, str | None] = {}
    mass = stance_mass_kg(stance)
    hop_f = stance.hop_frequency_hz if math.isfinite(stance.hop_frequency_hz) else None
    for j, name in enumerate(JOINT_NAMES):
        fit = fits[name]
        if stance_reason:
            joint_reason, values = stance_reason, None
        elif stance_result.joints is None:
            joint_reason, values = fit.rejection_reason or "no joint data", None
        else:
            joint_reason, values = _joint_entry(name, fit, stance_result.joints.joint(name), hop_f, mass, bounds)
            if joint_reason is None and subject_mass_kg and not abs(mass - subject_mass_kg) <= MASS_TOLERANCE * subject_mass_kg:
                joint_reason = (f"stance analysed for body mass {mass:.1f} kg, /subject {feed.subject_id!r} "
                                f"has {subject_mass_kg:.1f} kg")
        reasons[name] = joint_reason
        if joint_reason is None and values is not None:
            for key, v in values.items():
                arrays[key][j] = v
            if pools is not None:
                pools[name].add(fit)
    for key, column in arrays.items():
        setattr(feed, key, column)
    if pools is not None:
        _set_pooled(feed, pools)
    feed.valid = [reasons[n] is None for n in JOINT_NAMES]
    feed.invalid_reason = [reasons[n] or "" for n in JOINT_NAMES]
    return reasons


def _joint_entry(name: str, fit: JointImpedanceFit, data: dict, hop_f: float | None, mass_kg: float,
                 bounds: PlausibilityBounds | None) -> tuple[str | None, dict[str, float]]:
    """One joint of a stance with joint data: why it is not plausible (None = plausible) and its feed values."""
    k_eq, b_eq, theta_eq = equivalent_linear_impedance(data["angle_rad"], data["angular_velocity_rad_s"], data["moment_nm"])
    reason = controller_rejection(name, fit, k_eq, b_eq, hop_f, mass_kg, bounds)
    values = {"k0_nm_per_rad": _c(fit, "k0"), "k1_nm_per_rad2": _c(fit, "k1"), "b0_nms_per_rad": _c(fit, "b0"),
              "rho0_rad": float(fit.rho0), "omega0_rad_s": float(fit.omega0), "tau0_nm": _c(fit, "m0"),
              "stiffness_eq_nm_per_rad": k_eq, "damping_eq_nms_per_rad": controller_damping(b_eq),
              "equilibrium_angle_rad": theta_eq,
              **{f"{t}_std_error": _f(fit.std_errors.get(t)) for t in ("k0", "k1", "b0")}}
    return reason, values


def _set_pooled(feed: ControllerImpedance, pools: dict[str, StancePool]) -> None:
    """The pooled k0, k1, b0 of every joint, their standard errors, chi^2/dof and stance counts."""
    estimates = {name: {t: pools[name].estimate(t) for t in ("k0", "k1", "b0")} for name in JOINT_NAMES}
    for field, (term, attr) in POOLED_FIELDS.items():
        setattr(feed, field, [float(getattr(estimates[n][term], attr)) for n in JOINT_NAMES])
    feed.pooled_n_stances = [len(pools[n]) for n in JOINT_NAMES]


def main(args=None) -> None:
    """Run the node (``python -m hop_impedance.nodes.impedance_estimator --ros-args -p ...``)."""
    from hop_impedance.nodes.common import spin_node

    spin_node(ImpedanceEstimatorNode, args)


if __name__ == "__main__":
    main()
