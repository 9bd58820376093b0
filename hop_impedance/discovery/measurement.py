"""The measured side of the comparison: per-stance signals extracted from a contract recording.

Everything the discovery workflow compares with a model comes from here, on
the force-plate time base, time since touchdown:

- joint angles ``rho``, velocities ``omega`` and inverse-dynamics moments
  (extensor positive) from :func:`hop_impedance.biomech.analysis.analyze_recording`;
- the *raw* vertical plate force (no flight zeroing: a plate offset must stay
  visible) and the same low-passed at the analysis cut-off;
- the toe marker's height change since touchdown (surface displacement);
- the whole-body COM vertical acceleration from the markers, as a spline
  that can be evaluated at shifted times (stream latency);
- the touchdown state ``[x_toe, z_toe, q1..q4]`` and rates for forward simulation;
- the raw vertical force of the flight before the stance.

Stances the analysis rejects (cut at a file edge, too short, marker gaps)
are kept in ``rejected`` with the analysis' reason; nothing is dropped silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.interpolate import CubicSpline

from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.biomech.filtering import fill_gaps, lowpass, sampling_rate_hz
from hop_impedance.biomech.kinematics import POINT_NAMES, compute_kinematics, sagittal_markers, segment_angles_from_points
from hop_impedance.recording import GRAVITY_M_S2, MARKER_NAMES, Recording
from hop_impedance.simulation.dynamics import Chain, chain_from_body_model, com_offset_jacobian
from hop_impedance.simulation.stance import TouchdownState

#: Fewer force samples than this in an analysed stance: rejected for discovery.
MIN_STANCE_SAMPLES = 40
#: Flight samples this close to a contact are not used for the flight force (s).
FLIGHT_MARGIN_S = 0.03
#: Session 14's options for the touchdown state, measured and not adopted (docs/discovery.md, "Session 14";
#: ``bench/discovery_stance_edges.py``). The default reads it from the low-passed kinematics, whose filter runs across
#: the impact (session 14 blamed it for the TRUE law taking off 5-11 ms late on rigid grounds; session 15: mostly the
#: bench's ``M_td``, see :data:`TOUCHDOWN_KINK_FIT`). TOUCHDOWN_FROM_FLIGHT: the
#: state extrapolated from the flight's markers (:func:`_flight_touchdown_state`; a quadratic over the last
#: TOUCHDOWN_FIT_S): that error's mean per file is -8.3..+7.4 ms and per stance it spreads to -21..+23 ms (longer
#: windows make stances collapse). TOUCHDOWN_CUTOFF_HZ: the state's kinematics at another cut-off (None: the
#: analysis'); 25 Hz leaves +8..+9 ms on two outside rigid nulls, 40 Hz -4.4 / +5.7 ms with stances to -19 ms.
TOUCHDOWN_FROM_FLIGHT = False
TOUCHDOWN_FIT_S = 0.08
TOUCHDOWN_FIT_DEGREE = 2
TOUCHDOWN_CUTOFF_HZ: float | None = None
#: Fewest flight marker samples for that fit; with fewer the low-passed kinematics at the touchdown are used.
TOUCHDOWN_FIT_MIN_SAMPLES = 4
#: Session 15's option for the touchdown state, measured and not adopted (docs/discovery.md, "Session 15";
#: ``bench/discovery_stance_edges.py --kink-fit``): per marker coordinate a least-squares fit over the marker samples
#: within TOUCHDOWN_KINK_WINDOW_S (before, after) the detected touchdown (not past the previous take-off's flight margin
#: nor the take-off) of a polynomial of TOUCHDOWN_KINK_DEGREE plus ``b max(t - t_td, 0)``: positions continuous, the
#: velocity free to jump at the touchdown (an impact), so no filter runs across it. Positions at the stance's first
#: plate sample, rates from the stance side. Why: where the joint rates jump at the impact (our simulator: they turn fast
#: from the first millisecond) the 12 Hz filter leaves the ankle angle 34.8 mrad off at the touchdown, and the true law,
#: with ``M_td`` estimated as for a candidate, ends 2.45 ms early (+0.96 ms with this fit). Why not adopted: with 1 mm
#: marker noise (outside files, the second generator) the fit's angles and rates are noisier than the filter's.
TOUCHDOWN_KINK_FIT = False
TOUCHDOWN_KINK_WINDOW_S = (0.1, 0.1)
TOUCHDOWN_KINK_DEGREE = 3


@dataclass
class StanceKinematics:
    """The low-passed kinematics of one stance on the plate's samples, from two samples before its first (session 22).

    ``first``: the index of the stance's first sample in these arrays; ``t_s``: plate times (s); ``q``, ``qd``: segment
    angles and rates (N, 4); ``com_xz``: segment COMs (N, segments, 2); ``points_xz``: the toe (N, 1, 2).
    """

    first: int
    t_s: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    com_xz: np.ndarray
    points_xz: np.ndarray


@dataclass
class MeasuredStance:
    """One analysed stance (arrays on the force-plate samples inside the stance).

    Attributes
    ----------
    index : int
        Index among the analysis' stances.
    touchdown_s, takeoff_s : float
        Event times (s since the recording's first stamp).
    t_s : ndarray, shape (N,)
        Time since touchdown (s).
    rho_rad, omega_rad_s, moment_nm : ndarray, shape (N, 3)
        Joint angles, velocities, ID moments (ankle, knee, hip; flexion
        positive, extensor moment positive).
    fz_raw_n, fz_lp_n : ndarray, shape (N,)
        Raw vertical force and the same low-passed (N), offsets *not* removed.
    toe_dz_m : ndarray, shape (N,)
        Toe marker height minus its height at touchdown (m), low-passed.
    touchdown : TouchdownState
        ``g = [x_toe, 0, q1..q4]``, ``gd = [0, vz_toe, qd1..qd4]`` at touchdown.
    flight_fz_n : ndarray, shape (F,)
        Raw vertical force in the flight before this stance (N), margins trimmed.
    kinematics : StanceKinematics or None
        The low-passed kinematics the touchdown state is built from, over the stance, for a state at a later sample
        (:func:`filtered_state`; session 22).
    """

    index: int
    touchdown_s: float
    takeoff_s: float
    t_s: np.ndarray
    rho_rad: np.ndarray
    omega_rad_s: np.ndarray
    moment_nm: np.ndarray
    fz_raw_n: np.ndarray
    fz_lp_n: np.ndarray
    toe_dz_m: np.ndarray
    touchdown: TouchdownState
    flight_fz_n: np.ndarray
    kinematics: StanceKinematics | None = None

    @property
    def abs_t_s(self) -> np.ndarray:
        """Sample times since the recording start (s)."""
        return self.t_s + self.touchdown_s


@dataclass
class MeasuredTrial:
    """All stances of a recording ready for comparison.

    Attributes
    ----------
    stances : list of MeasuredStance
    rejected : list of dict
        ``{"index", "touchdown_s", "reason"}`` for every stance not used.
    chain : Chain
        Segment parameters of the body model the analysis used.
    body_mass_kg : float
    com_acc_z : CubicSpline
        Whole-body COM vertical acceleration (m/s^2) as a function of time
        since the recording start (s), from the (low-passed) markers.
    marker_latency_s : float
        Latency that was removed from the marker stamps before analysis (s).
    warnings : list of str
    options : AnalysisOptions
        The analysis options it was measured with, before any body split (re-measuring keeps them).
    body_fraction : float
        Share of the table's thigh mass moved to the HAT for this measurement (:func:`split_overrides`).
    table_model : BodyModel or None
        The analysis' own (table) body model, before the split.
    """

    stances: list[MeasuredStance]
    rejected: list[dict]
    chain: Chain
    body_mass_kg: float
    com_acc_z: CubicSpline
    marker_latency_s: float = 0.0
    warnings: list[str] = field(default_factory=list)
    options: AnalysisOptions = field(default_factory=AnalysisOptions)
    body_fraction: float = 0.0
    table_model: BodyModel | None = None


def shift_marker_stream(rec: Recording, latency_s: float) -> Recording:
    """Copy of ``rec`` whose marker stamps are moved ``latency_s`` earlier.

    A marker sample stamped ``t`` that shows the body at ``t - latency_s``
    (positive latency = markers lag the plate) gets the stamp ``t - latency_s``.
    """
    if rec.markers is None or latency_s == 0.0:
        return rec
    shift = int(round(latency_s * 1e9))
    return replace(rec, markers=replace(rec.markers, stamp_ns=rec.markers.stamp_ns - shift))


def _com_z_spline(marker_t: np.ndarray, markers_xz: np.ndarray, model, cutoff_hz: float) -> CubicSpline:
    kin, _ = compute_kinematics(marker_t, markers_xz, marker_t, model, cutoff_hz)
    z = kin.body_com_xz(model)[:, 1]
    ok = np.isfinite(z)
    return CubicSpline(marker_t[ok], z[ok]).derivative(2)


def split_overrides(model: BodyModel, fraction: float) -> dict[str, dict[str, float]]:
    """Segment overrides moving ``fraction`` of ``model``'s thigh mass to its HAT (radii of gyration kept).

    The body nuisance of discovery (:mod:`hop_impedance.discovery.body_nuisance`); total mass unchanged.
    """
    dm = fraction * model.thigh.mass_kg
    out = {}
    for seg, mass in ((model.thigh, model.thigh.mass_kg - dm), (model.hat, model.hat.mass_kg + dm)):
        out[seg.name] = {"mass_kg": mass, "inertia_kgm2": seg.inertia_kgm2 * mass / seg.mass_kg}
    return out


def measure_trial(rec: Recording, marker_latency_s: float = 0.0, options: AnalysisOptions | None = None,
                  body_fraction: float = 0.0, table_model: BodyModel | None = None) -> MeasuredTrial:
    """Extract the per-stance signals of a recording (see module docstring).

    Parameters
    ----------
    rec : Recording
        Contract recording with force plate, markers and subject.
    marker_latency_s : float
        Marker latency to remove first (s, positive = markers lag).
    options : AnalysisOptions, optional
    body_fraction : float
        Share of the table's thigh mass to move to the HAT (:func:`split_overrides`); 0 = the table.
    table_model : BodyModel, optional
        The table model to split (default: the one the analysis scales from the markers).

    Returns
    -------
    MeasuredTrial

    Raises
    ------
    ValueError
        No markers, no subject, or no stance usable for discovery.
    """
    if rec.markers is None or len(rec.markers) < 8:
        raise ValueError(f"{rec.source or 'recording'}: discovery needs marker data on the marker topic")
    base_options = options = options or AnalysisOptions()
    rec = shift_marker_stream(rec, marker_latency_s)
    markers = rec.markers
    assert markers is not None  # checked above; shift_marker_stream keeps them
    analysis, options, table_model = _analysed(rec, options, body_fraction, table_model)
    t_f = (rec.force.stamp_ns - analysis.start_ns) * 1e-9
    t_m = (markers.stamp_ns - analysis.start_ns) * 1e-9
    fz_raw = rec.force.force_n[:, 2].astype(float)
    fz_lp = lowpass(fz_raw, sampling_rate_hz(t_f), options.force_cutoff_hz)
    xz = sagittal_markers(markers)
    filled, _, _ = fill_gaps(t_m, xz, options.max_gap_s)
    kin, _ = compute_kinematics(t_m, xz, t_f, analysis.model, options.marker_cutoff_hz, options.max_gap_s)
    com_acc = _com_z_spline(t_m, np.where(np.isfinite(filled), filled, np.nan), analysis.model, options.marker_cutoff_hz)
    chain = chain_from_body_model(analysis.model)
    kin_td = kin
    if TOUCHDOWN_CUTOFF_HZ is not None:
        kin_td, _ = compute_kinematics(t_m, xz, t_f, analysis.model, TOUCHDOWN_CUTOFF_HZ, options.max_gap_s)
    stances, rejected = _usable_stances(analysis, (t_f, fz_raw, fz_lp), kin, chain, (t_m, filled, kin_td))
    if not stances:
        reasons = "; ".join(f"stance {r['index']}: {r['reason']}" for r in rejected) or "no stance detected"
        raise ValueError(f"{rec.source or 'recording'}: no stance usable for discovery ({reasons})")
    mass = analysis.subject.body_mass_kg  # rec.subject (analyze_recording raises without one)
    return MeasuredTrial(stances, rejected, chain, mass, com_acc, marker_latency_s, list(analysis.warnings), base_options,
                         body_fraction, table_model)


def _usable_stances(analysis, force: tuple, kin, chain: Chain, markers: tuple) -> tuple[list[MeasuredStance], list[dict]]:
    """The analysis' stances discovery can use, and the others with their reasons.

    ``force``: plate times, raw and low-passed Fz; ``markers``: marker times and gap-filled sagittal markers.
    """
    t_f = force[0]
    stances, rejected = [], []
    prev_takeoff = float(t_f[0]) - 1.0
    for s in analysis.stances:
        reason = s.rejection_reason
        if reason is None:
            assert s.joints is not None  # analyze_recording keeps joint data exactly for the stances it accepts
            if len(s.joints.time_s) < MIN_STANCE_SAMPLES:
                reason = f"too short for discovery: {len(s.joints.time_s)} force samples < {MIN_STANCE_SAMPLES}"
        sel = (t_f >= s.touchdown_s) & (t_f <= s.takeoff_s)
        if reason is None and not np.all(np.isfinite(kin.points_xz[sel])):
            reason = "marker kinematics not finite in stance"
        if reason is not None:
            rejected.append({"index": s.index, "touchdown_s": s.touchdown_s, "reason": reason})
            prev_takeoff = s.takeoff_s
            continue
        stances.append(_measured_stance(s, sel, force, kin, chain, prev_takeoff, markers))
        prev_takeoff = s.takeoff_s
    return stances, rejected


def _analysed(rec: Recording, options: AnalysisOptions, body_fraction: float, table_model: BodyModel | None):
    """``(analysis, options it ran with, table model)``: the analysis with the body split applied."""
    if body_fraction:
        if table_model is None:
            table_model = analyze_recording(rec, options).model
        if table_model is not None:
            options = replace(options, overrides={**(options.overrides or {}), **split_overrides(table_model, body_fraction)})
    analysis = analyze_recording(rec, options)
    if analysis.model is None:
        raise ValueError(f"{rec.source or 'recording'}: no body model could be built from the markers")
    return analysis, options, table_model or analysis.model


def _measured_stance(s, sel, force: tuple, kin, chain: Chain, prev_takeoff_s: float, markers: tuple) -> MeasuredStance:
    t_f, fz_raw, fz_lp = force
    j = s.joints
    n = len(j.time_s)
    idx = np.nonzero(sel)[0][:n]
    toe_z = kin.points_xz[idx, 0, 1]
    i0 = idx[0]
    t_m, filled, kin_td = markers
    state = _flight_touchdown_state(t_m, filled, float(t_f[i0]), prev_takeoff_s) if TOUCHDOWN_FROM_FLIGHT else None
    if TOUCHDOWN_KINK_FIT:
        state = _kinked_touchdown_state(t_m, filled, (float(s.touchdown_s), float(t_f[i0])), prev_takeoff_s,
                                        float(s.takeoff_s))
    if state is None:
        state = _filtered_touchdown_state(t_f, kin_td, chain, i0)
    g0, gd0 = state
    fl = (t_f > prev_takeoff_s + FLIGHT_MARGIN_S) & (t_f < s.touchdown_s - FLIGHT_MARGIN_S)
    return MeasuredStance(
        index=s.index, touchdown_s=float(s.touchdown_s), takeoff_s=float(s.takeoff_s), t_s=np.asarray(j.time_s),
        rho_rad=np.asarray(j.angle_rad), omega_rad_s=np.asarray(j.angular_velocity_rad_s),
        moment_nm=np.asarray(j.moment_nm), fz_raw_n=fz_raw[idx], fz_lp_n=fz_lp[idx],
        toe_dz_m=toe_z - toe_z[0], touchdown=TouchdownState(g0, gd0), flight_fz_n=fz_raw[fl],
        kinematics=_stance_kinematics(t_f, kin_td, idx),
    )


def _stance_kinematics(t_f, kin, idx: np.ndarray) -> StanceKinematics:
    """:class:`StanceKinematics` of the stance on plate samples ``idx`` (copies of ``kin``'s rows there)."""
    lo, hi = max(int(idx[0]) - 2, 0), int(idx[-1]) + 3
    rows = [np.array(a[lo:hi]) for a in (t_f, kin.q, kin.qd, kin.com_xz, kin.points_xz[:, :1])]
    return StanceKinematics(int(idx[0]) - lo, *rows)


def filtered_state(s: MeasuredStance, chain: Chain, k: int) -> TouchdownState:
    """The state at the stance's sample ``k`` from the low-passed kinematics, built as the default touchdown state
    (:func:`_filtered_touchdown_state`; at ``k`` = 0 the same numbers), ``z_toe`` 0 (session 22: a held-out stance
    simulated from a sample after the impact, ``forward_selection.SIMULATE_FROM_S``)."""
    kin = s.kinematics
    if kin is None:
        raise ValueError(f"stance {s.index}: no kinematics kept for a state inside the stance")
    g, gd = _filtered_touchdown_state(kin.t_s, kin, chain, kin.first + int(k))
    return TouchdownState(g, gd)


def _filtered_touchdown_state(t_f, kin, chain: Chain, i0: int) -> tuple[np.ndarray, np.ndarray]:
    """``(g, gd)`` at plate sample ``i0`` from the low-passed kinematics (the default).

    The COM velocity from the marker COM; the toe z velocity = COM's minus the angles' share. The low-pass runs
    across the impact, so the velocities mix flight and stance (session 14, a noise-free null of our simulator:
    toe z velocity -0.36..-0.41 m/s against the flight's -0.82..-0.93, joint rates already those of the stance),
    and the touchdown angles carry the spread of an impact (session 15, that null: ankle 34.8 mrad above the kinked
    fit's). With ``M_td`` estimated as for a candidate the true law then ends 2.45 ms early there, and -0.2..+1.9 ms from
    the measured take-off on the outside rigid nulls (``bench/discovery_stance_edges.py``; session 14's 5-11 ms late
    were mostly that bench's ``M_td``).
    """
    q0, qd0 = kin.q[i0], kin.qd[i0]
    com_z = np.einsum("s,ns->n", chain.mass_kg, kin.com_xz[max(i0 - 2, 0): i0 + 3, :, 1]) / chain.total_mass_kg
    tt = t_f[max(i0 - 2, 0): i0 + 3]
    vz_com = float(np.polyfit(tt - tt[0], com_z, 1)[0])
    vz_toe = vz_com - float(com_offset_jacobian(chain, q0)[1] @ qd0)
    return np.r_[kin.points_xz[i0, 0, 0], 0.0, q0], np.r_[0.0, vz_toe, qd0]


def _flight_touchdown_state(t_m: np.ndarray, markers_xz: np.ndarray, at_s: float,
                            prev_takeoff_s: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(g, gd)`` at ``at_s`` (the stance's first plate sample) extrapolated from the flight before it.

    A quadratic in time per marker coordinate through the marker samples of the last :data:`TOUCHDOWN_FIT_S` of the
    flight (after :data:`FLIGHT_MARGIN_S` past the previous take-off), evaluated at ``at_s``: the state the body
    lands with, as a simulation that starts its contact there needs it (session 14). None with fewer than
    :data:`TOUCHDOWN_FIT_MIN_SAMPLES` complete samples.
    """
    sel = (t_m > max(prev_takeoff_s + FLIGHT_MARGIN_S, at_s - TOUCHDOWN_FIT_S)) & (t_m <= at_s)
    pts = markers_xz[sel][:, [MARKER_NAMES.index(p) for p in POINT_NAMES]]
    ok = np.all(np.isfinite(pts), axis=(1, 2))
    if ok.sum() < TOUCHDOWN_FIT_MIN_SAMPLES:
        return None
    coef = np.polyfit(t_m[sel][ok] - at_s, pts[ok].reshape(int(ok.sum()), -1), TOUCHDOWN_FIT_DEGREE)
    h = 1e-4
    at = np.stack([np.polyval(coef, t) for t in (-h, 0.0, h)]).reshape(3, -1, 2)
    q = segment_angles_from_points(at)
    qd = (q[2] - q[0]) / (2 * h)
    return np.r_[at[1, 0, 0], 0.0, q[1]], np.r_[0.0, coef[-2].reshape(-1, 2)[0, 1], qd]


def _kinked_touchdown_state(t_m: np.ndarray, markers_xz: np.ndarray, times: tuple[float, float], prev_takeoff_s: float,
                            takeoff_s: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(g, gd)`` at the stance's first plate sample from a fit with a kink at the detected touchdown (option
    :data:`TOUCHDOWN_KINK_FIT`). ``times``: the detected touchdown and that sample (s). None with fewer complete marker
    samples in the window than the fit has coefficients plus two.
    """
    td_s, at_s = times
    before, after = TOUCHDOWN_KINK_WINDOW_S
    sel = (t_m > max(prev_takeoff_s + FLIGHT_MARGIN_S, td_s - before)) & (t_m < min(takeoff_s, td_s + after))
    pts = markers_xz[sel][:, [MARKER_NAMES.index(p) for p in POINT_NAMES]]
    ok = np.all(np.isfinite(pts), axis=(1, 2))
    deg = TOUCHDOWN_KINK_DEGREE
    if ok.sum() < deg + 4:
        return None

    def basis(tau: np.ndarray, order: int) -> np.ndarray:
        """Columns ``tau^0..tau^deg, max(tau, 0)`` (order 0) or their time derivatives on the stance side (order 1)."""
        if order == 0:
            return np.column_stack([tau**k for k in range(deg + 1)] + [np.maximum(tau, 0.0)])
        return np.column_stack([np.zeros_like(tau)] + [k * tau ** (k - 1) for k in range(1, deg + 1)] + [np.ones_like(tau)])

    coef, *_ = np.linalg.lstsq(basis(t_m[sel][ok] - td_s, 0), pts[ok].reshape(int(ok.sum()), -1), rcond=None)
    tau = np.array([at_s - td_s])
    pos, vel = (basis(tau, 0) @ coef).reshape(-1, 2), (basis(tau, 1) @ coef).reshape(-1, 2)
    h = 1e-5
    q = segment_angles_from_points(np.stack([pos - h * vel, pos, pos + h * vel]))
    return np.r_[pos[0, 0], 0.0, q[1]], np.r_[0.0, vel[0, 1], (q[2] - q[0]) / (2 * h)]


def weight_n(trial: MeasuredTrial) -> float:
    """Body weight (N) with the contract's g."""
    return trial.body_mass_kg * GRAVITY_M_S2
