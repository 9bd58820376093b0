"""The truth file written next to a simulated recording (``REC.truth.json``).

Layout (format ``hop_impedance.simulation.truth/1``)
-----------------------------------------------------
- ``generator``: command line / parameters that produced the file; ``seed``.
- ``subject``, ``body_model`` (segment parameters, alpha), ``effects``
  (every switch), ``law`` (every parameter), ``surface`` and
  ``unexpected_surface`` (law parameters), ``sensors`` (rates, noise, offset,
  stream time offset, the occlusion spans drawn), ``config``, ``calibration``.
- ``recording``: ``start_ns`` (stamp of t = 0 s), ``duration_s``.
- ``stances``: one entry per simulated stance, in order, with
  ``touchdown_s``/``takeoff_s`` (s since ``start_ns``, force-plate time) and
  their stamps (ns), ``duration_s``, ``surface``, ``end_reason``, peak GRF
  (N and body weights), seed 001 leg stiffness and compression, the Eq. 3
  coefficients per joint (``m0, k0..k3, b0..b3``, with ``rho0_rad`` and
  ``omega0_rad_s`` at touchdown; ``activation`` and ``push_off`` where
  present), and ``samples``: the true joint angles (rad), velocities (rad/s),
  net moments (N m, extensor positive), the same split into the Eq. 3 part
  (``eq3_moments_nm``, incl. activation), the push-off part
  (``push_off_moments_nm``) and the trunk-balance part at the hip
  (``trunk_balance_moments_nm``, zero without one; its law and the touchdown trunk
  angle q4 are in the stance's ``trunk_balance``: the whole hip law is the
  Eq. 3 hip law plus that term), and GRF ``[Fx, Fz]`` (N) at every force-plate
  sample inside the stance (``t_s`` in recording time). Only with a passive knee-ankle spring
  (:class:`~hop_impedance.simulation.impedance_laws.BiarticularSpring`, off by default) the stance has
  ``biarticular`` (its law) and ``samples.biarticular_moments_nm``, its part of the net moments (the
  ankle and knee laws are then the Eq. 3 law plus that term).

- ``stances[i].energy_j``: the hop's energy budget (J): push-off work, Eq. 3 work, springs left at
  take-off, damping, trunk-balance work, ground work, energy at touchdown / take-off, bookkeeping
  residual, and ``flight_j`` (what the following flight discards; absent on the last stance), see
  :mod:`hop_impedance.simulation.energy_budget`.
- ``whole_hip_law`` (only with a trunk balance): the whole hip law's reference against which hip recovery is
  judged, the seed's Eq. 3 fit (k0, k1, b0) of each stance's noise-free whole hip moment on the true hip angle,
  per stance and pooled over the stances after the first (:func:`~hop_impedance.simulation.whole_hip.whole_hip_reference`).

Numbers in ``samples`` are rounded to 7 significant digits to keep files small.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from hop_impedance.biomech.body_model import BodyModel
from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.recording import Subject
from hop_impedance.simulation.energy_budget import part_moments_nm, trial_energy_budget
from hop_impedance.simulation.hopping_trial import HoppingTrial, StanceRecord, leg_stiffness_n_per_m, simulate_resample
from hop_impedance.simulation.impedance_laws import COEFFICIENT_NAMES, BiarticularSpring, Eq3Law, PushOff, law_part
from hop_impedance.simulation.sensors import SensorConfig, sample_times_s, stamps_ns
from hop_impedance.simulation.whole_hip import whole_hip_reference

TRUTH_FORMAT = "hop_impedance.simulation.truth/1"


def truth_path(recording_path: str | Path) -> Path:
    """``REC.mcap`` -> ``REC.truth.json`` (same folder)."""
    p = Path(recording_path)
    return p.with_name(p.stem + ".truth.json")


def _round(a: np.ndarray) -> list:
    return np.vectorize(lambda v: float(f"{v:.7g}"))(np.asarray(a, float)).tolist() if np.size(a) else []


def stance_truth(trial: HoppingTrial, rec: StanceRecord, sensors: SensorConfig, weight_n: float) -> dict:
    """Truth entry of one stance (see module docstring)."""
    rate = sensors.force_rate_hz
    t_all = sample_times_s(trial.t_end_s, rate)
    t_in = t_all[(t_all >= rec.t_touchdown_s) & (t_all <= rec.t_takeoff_s)]
    st = simulate_resample(trial.chain, rec, t_in - rec.t_touchdown_s)
    k_leg, peak, compression = leg_stiffness_n_per_m(trial.chain, rec.stance)
    eq3 = law_part(rec.law, Eq3Law)
    push = law_part(rec.law, PushOff)
    impedance = {}
    for j, name in enumerate(JOINT_NAMES):
        entry = {c: (float(getattr(eq3, c)[j]) if eq3 is not None else 0.0) for c in COEFFICIENT_NAMES}
        entry["rho0_rad"] = float(rec.stance.ref.rho0_rad[j])
        entry["omega0_rad_s"] = float(rec.stance.ref.omega0_rad_s[j])
        impedance[name] = entry
    start = sensors.start_ns
    out: dict = {
        "index": rec.index,
        "touchdown_s": rec.t_touchdown_s,
        "takeoff_s": rec.t_takeoff_s,
        "touchdown_stamp_ns": int(stamps_ns(np.array([rec.t_touchdown_s]), start)[0]),
        "takeoff_stamp_ns": int(stamps_ns(np.array([rec.t_takeoff_s]), start)[0]),
        "duration_s": rec.stance.duration_s,
        "surface": rec.surface.name,
        "end_reason": rec.stance.end_reason,
        "friction_phases": [[float(t), int(sign)] for t, sign in rec.stance.friction_phases],
        "peak_grf_n": peak,
        "peak_grf_bw": peak / weight_n,
        "leg_stiffness_n_m": k_leg,  # N/m; the key's unit suffix is kept so truth/1 files read the same
        "leg_compression_m": compression,
        "impedance": impedance,
        "activation": None if eq3 is None or eq3.activation is None else vars(eq3.activation).copy(),
        "push_off": None if push is None else push.to_dict(),
        "trunk_balance": None if st.trunk_balance is None else {**st.trunk_balance.to_dict(),
                                                                "q4_touchdown_rad": float(rec.touchdown.g[5])},
        "samples": {
            "rate_hz": rate,
            "t_s": _round(t_in),
            "rho_rad": _round(st.rho_rad),
            "omega_rad_s": _round(st.omega_rad_s),
            "moments_nm": _round(st.moments_nm),
            "eq3_moments_nm": _round(part_moments_nm(eq3, st)),
            "push_off_moments_nm": _round(part_moments_nm(push, st)),
            "trunk_balance_moments_nm": _round(st.trunk_moments_nm if st.trunk_moments_nm is not None
                                               else np.zeros_like(st.moments_nm)),
            "grf_n": _round(st.grf_n),
        },
    }
    biarticular = law_part(rec.law, BiarticularSpring)
    if biarticular is not None:  # only then (older truth files stay the same)
        out["biarticular"] = biarticular.to_dict()
        out["samples"]["biarticular_moments_nm"] = _round(part_moments_nm(biarticular, st))
    return out


def _flight_model(cfg) -> str:
    """The truth file's description of ``cfg``'s flight (HoppingConfig.flight, .landing)."""
    if cfg.flight == "prescribed":
        return "COM ballistic, segment angles prescribed (quintic) to rest at touchdown; force plate zero"
    return ("COM ballistic, segment angles quintic to touchdown rates that keep the take-off's segment kinetic energy "
            "plus the springs' returned energy; force plate zero"
            + ("; landing along the prescribed flight's landing motion" if cfg.landing == "prescribed" else "")
            + ("; the trunk balance holds the trunk in flight (zero trunk pitch rate at touchdown, the trunk's share of "
               "the landing motion lost: stances' energy_j.flight_balance_loss_j)" if cfg.flight == "trunk_held" else "")
            + ("; the trunk lands without pitching, all of the carried energy in the legs" if cfg.flight == "trunk_still"
               else ""))


def trial_truth(
    trial: HoppingTrial,
    sensors: SensorConfig,
    subject: Subject,
    model: BodyModel,
    effects: dict,
    sensor_truth: dict,
    generator: dict,
) -> dict:
    """The whole truth document of a simulated recording."""
    cfg = trial.config
    stances = [{**stance_truth(trial, rec, sensors, subject.body_weight_n), "energy_j": budget}
               for rec, budget in zip(trial.stances, trial_energy_budget(trial))]
    document = {
        "format": TRUTH_FORMAT,
        "generator": generator,
        "subject": {"subject_id": subject.subject_id, "body_mass_kg": subject.body_mass_kg,
                    "body_height_m": subject.body_height_m, "sex": subject.sex},
        "body_model": {
            "segments": {s.name: {"mass_kg": s.mass_kg, "length_m": s.length_m, "com_along_m": s.com_along_m,
                                  "com_perp_m": s.com_perp_m, "inertia_kgm2": s.inertia_kgm2}
                         for s in model.segments},
            "alpha_rad": model.foot_geometry.alpha_rad,
        },
        "effects": effects,
        "law": cfg.law.to_dict(),
        "surface": cfg.surface.to_dict(),
        "unexpected_surface": None if cfg.unexpected_surface is None else cfg.unexpected_surface.to_dict(),
        "sensors": {**sensors.to_dict(), **sensor_truth},
        "config": {
            "freq_hz": cfg.freq_hz, "n_hops": cfg.n_hops, "touchdown_rho_rad": list(cfg.touchdown_rho_rad),
            "unexpected_hops": list(cfg.unexpected_hops), "posture_sd_rad": cfg.posture_sd_rad,
            "speed_sd": cfg.speed_sd, "push_sd": cfg.push_sd, "placement_gain_s": cfg.placement_gain_s,
            "lead_in_s": cfg.lead_in_s, "rtol": cfg.rtol, "atol": cfg.atol,
            "friction_coefficient": cfg.friction_coefficient,
            "flight_model": _flight_model(cfg),
            "trunk_balance": None if cfg.trunk_balance is None else cfg.trunk_balance.to_dict(),
            "contact_ahead_of_toe_marker_m": float(np.hypot(trial.chain.toe_marker_along_m,
                                                            trial.chain.toe_marker_perp_m)),
            "horizontal_contact": ("no-slip kinematic constraint at the toe while |Fx| <= mu Fz, Coulomb sliding "
                                   "beyond" if cfg.friction_coefficient is not None
                                   else "no-slip kinematic constraint at the toe"),
            # issue 17's landing controller and start state, only when used (older truth files stay the same)
            **({"landing_rates_rad_s": [float(v) for v in cfg.landing_rates_rad_s]}
               if cfg.landing_rates_rad_s is not None else {}),
            **({"first_touchdown": [float(v) for v in cfg.first_touchdown]} if cfg.first_touchdown is not None else {}),
        },
        "calibration": {k: (bool(v) if isinstance(v, (bool, np.bool_)) else float(v))
                        for k, v in (trial.calibration.to_dict() if trial.calibration is not None else {}).items()},
        "recording": {"start_ns": sensors.start_ns, "duration_s": trial.t_end_s},
        "stop_reason": trial.stop_reason,
        "notes": list(trial.notes),
        "stances": stances,
    }
    if cfg.trunk_balance is not None:  # the whole hip law differs from the Eq. 3 law (older files stay the same)
        document["whole_hip_law"] = whole_hip_reference(document)
    return document


def write_truth(path: str | Path, truth: dict) -> None:
    """Write the truth document as compact JSON."""
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(truth, fh, separators=(",", ":"))


def load_truth(path: str | Path) -> dict:
    """Read a truth file; checks the format tag."""
    with open(path, encoding="utf-8") as fh:
        data = json.load(fh)
    if data.get("format") != TRUTH_FORMAT:
        raise ValueError(f"{path}: not a simulator truth file (format {data.get('format')!r}, expected {TRUTH_FORMAT!r})")
    return data
