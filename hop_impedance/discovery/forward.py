"""The simulation side: each measured stance simulated forward from its measured touchdown state.

The gap of a model is measured on *held-out* stances: the stances are split
in two folds (even and odd positions); the model is identified on one fold
and every stance of the other is simulated with
:func:`hop_impedance.simulation.stance.simulate_stance` from its measured
touchdown state and compared sample by sample (force-plate rate) with:

- ``grf``: raw vertical plate force (N); the model's prediction is the
  simulated Fz plus the model's plate offset;
- ``angle_<joint>``: joint angles (rad);
- ``moment_<joint>``: ID moments (N m) against the simulated law moments.

Figures per signal: ``rms`` (pooled over samples), ``peak`` (largest
absolute residual), ``relative_rms`` = rms / mean per-stance range of the
measured signal, and ``rms_early|mid|late`` over the thirds of stance.
Where the simulated stance ends before the measured one, the overlap is
compared and ``duration_error_s`` records the difference.
"""

from __future__ import annotations

import numpy as np

from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.discovery.identify import identify, surface_law, touchdown_moments
from hop_impedance.discovery.measurement import MeasuredStance, MeasuredTrial
from hop_impedance.discovery.model import FittedLaw, ModelSpec
from hop_impedance.simulation.ground import GroundLaw
from hop_impedance.simulation.impedance_laws import ImpedanceLaw
from hop_impedance.simulation.stance import simulate_stance
from hop_impedance.simulation.stance_set import RIGID_NO_BOUNCE

GAP_SIGNALS: tuple[str, ...] = ("grf",) + tuple(f"angle_{j}" for j in JOINT_NAMES) + tuple(f"moment_{j}" for j in JOINT_NAMES)


def ground_of(spec: ModelSpec, s: MeasuredStance) -> GroundLaw:
    """Surface law under stance ``s``: rigid (no bounce) or the identified ``k |y|^n - d y'``."""
    law = surface_law(spec, s)
    if law is None or law[0] <= 0:
        return RIGID_NO_BOUNCE
    c, p, d = law
    return GroundLaw("identified", float(c ** (-1.0 / p)), float(1.0 / p), float(d))


def simulate_measured_stance(spec: ModelSpec, coefs: np.ndarray, trial: MeasuredTrial, s: MeasuredStance) -> dict:
    """Forward simulation of one measured stance; residual arrays per signal of :data:`GAP_SIGNALS`."""
    law = FittedLaw(spec, np.asarray(coefs, float), touchdown_moments(spec, coefs, s))
    return simulate_with_law(law, ground_of(spec, s), spec.offset_n, trial, s)


def simulate_with_law(law: ImpedanceLaw, ground: GroundLaw, offset_n: float, trial: MeasuredTrial,
                      s: MeasuredStance) -> dict:
    """Forward simulation of stance ``s`` from its measured touchdown state with any joint law and ground.

    ``offset_n`` (N) is added to the simulated Fz before comparing with the raw
    plate force. Returns ``end_reason``, ``duration_error_s``, ``n`` and the
    residual arrays (measured minus simulated) per signal of :data:`GAP_SIGNALS`.
    """
    t_max = 2.0 * float(s.t_s[-1]) + 0.1
    try:
        sim = simulate_stance(trial.chain, law, ground, s.touchdown, t_max_s=t_max, rtol=1e-6, atol=1e-8,
                              sample_times_s=s.t_s)
        end, n = sim.end_reason, len(sim.t_s)
    except RuntimeError as exc:  # integration failure: report, compare nothing
        return {"end_reason": f"failed: {exc}", "duration_error_s": float("nan"), "residuals": {}, "n": 0}
    res = {"grf": s.fz_raw_n[:n] - (sim.grf_n[:, 1] + offset_n)}
    for j, name in enumerate(JOINT_NAMES):
        res[f"angle_{name}"] = s.rho_rad[:n, j] - sim.rho_rad[:, j]
        res[f"moment_{name}"] = s.moment_nm[:n, j] - sim.moments_nm[:, j]
    duration_error = (sim.duration_s if end == "take_off" else float("nan")) - float(s.t_s[-1])
    return {"end_reason": end, "duration_error_s": duration_error, "residuals": res, "n": n,
            "simulated": sim}


def _measured(s: MeasuredStance, sig: str) -> np.ndarray:
    if sig == "grf":
        return s.fz_raw_n
    kind, joint = sig.split("_")
    j = JOINT_NAMES.index(joint)
    return (s.rho_rad if kind == "angle" else s.moment_nm)[:, j]


def gap_figures(per_stance: list[tuple[MeasuredStance, dict]]) -> dict:
    """Pooled gap figures per signal (see module docstring)."""
    out = {}
    for sig in GAP_SIGNALS:
        parts = [(s, r["residuals"][sig]) for s, r in per_stance if r["n"] > 1]
        if not parts:
            out[sig] = None
            continue
        allr = np.concatenate([r for _, r in parts])
        ranges = np.mean([np.ptp(_measured(s, sig)) for s, _ in parts])
        thirds = {k: [] for k in ("early", "mid", "late")}
        for s, r in parts:
            for k, chunk in zip(thirds, np.array_split(r, 3)):
                thirds[k].append(chunk)
        rms = float(np.sqrt(np.mean(allr**2)))
        out[sig] = {"rms": rms, "peak": float(np.max(np.abs(allr))), "relative_rms": rms / ranges if ranges > 0 else None,
                    **{f"rms_{k}": float(np.sqrt(np.mean(np.concatenate(v) ** 2))) for k, v in thirds.items()}}
    durations = [r["duration_error_s"] for _, r in per_stance if np.isfinite(r["duration_error_s"])]
    out["duration_error_rms_s"] = float(np.sqrt(np.mean(np.square(durations)))) if durations else None
    out["stances_not_taking_off"] = int(sum(r["end_reason"] != "take_off" for _, r in per_stance))
    return out


def held_out_forward_gap(spec: ModelSpec, trial: MeasuredTrial) -> tuple[dict, list[tuple[MeasuredStance, dict]]]:
    """Two-fold held-out forward-simulation gap of ``spec`` (nonlinear parameters kept, linear ones re-fitted).

    Returns
    -------
    figures : dict
        :func:`gap_figures` of all held-out stances.
    per_stance : list of (MeasuredStance, simulation dict)
    """
    folds = [trial.stances[0::2], trial.stances[1::2]]
    per_stance = []
    for k, test in enumerate(folds):
        train = folds[1 - k] or test
        fitted, coefs = identify(spec, trial, train)
        per_stance += [(s, simulate_measured_stance(fitted, coefs, trial, s)) for s in test]
    per_stance.sort(key=lambda x: x[0].index)
    return gap_figures(per_stance), per_stance


def law_forward_gap(trial: MeasuredTrial, law: ImpedanceLaw, ground: GroundLaw, offset_n: float = 0.0) -> dict:
    """:func:`gap_figures` of one given law (e.g. the simulation truth) on every stance, nothing identified.

    With the law that generated a simulated recording this is the recording's
    *noise floor*: what is left when the model is exactly right, i.e. the
    effect of sensor noise, low-pass/ID processing and the touchdown state
    estimated from filtered markers.
    """
    return gap_figures([(s, simulate_with_law(law, ground, offset_n, trial, s)) for s in trial.stances])
