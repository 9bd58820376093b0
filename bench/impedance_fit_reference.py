"""Snapshot the impedance fit's inputs and outputs, then check a changed fit against the snapshot.

Issue 20 asks that a refactor of ``hop_impedance/impedance/`` change no number.
Comparing through a fresh ``analyze`` would mix in changes of the analysis
windows (other work), so the snapshot stores the per-stance joint series the
fit consumes, and ``--check`` refits exactly those arrays.

    .venv/bin/python bench/impedance_fit_reference.py --save /tmp/imp_ref    # before changing the fit
    .venv/bin/python bench/impedance_fit_reference.py --check /tmp/imp_ref   # after each change

Inputs saved:

* every bundled recording in ``recordings/`` through ``analyze_recording``
  with the default options: per stance the stance's rejection reason and the
  ankle/knee/hip time, angle, angular velocity and moment series, plus the
  ``FitOptions`` that ``fit_recording_trial`` uses for it;
* synthetic noisy seed stances (``bench_impedance_fit.py``'s generator, 20
  per frequency) fitted with the reduction and with the structure given
  (k0, k1, b0), as the benchmark runs them.

Fits are repeated in the order ``fit_recording_trial`` runs them (per-stance
reductions with one workspace per joint, the structure chosen per joint, the
structured refits with one workspace per joint and structure), so OSQP's warm
starts are the same. At ``--save`` the replayed order is checked against
``fit_recording_trial`` itself.

Compared (``--check``): status, rejection reason, kept terms, elimination
steps (term, reason, p, F, VIF), per-stance F and p of the kept terms,
effective samples, every coefficient, standard error and p-value, SSE of the
variable and the constant model, RMSE, R^2, Table 3 errors, overall and
average stiffness, the K, B and moment series, every collinearity diagnostic
and the chosen structures. Numbers must agree within ``--rtol`` (1e-9)
relative: ``|a - b| <= rtol * max(|a|, |b|)`` for scalars and
``max|a - b| <= rtol * max(max|a|, max|b|)`` for arrays (NaN equals NaN, inf
equals inf). Prints one line per source and the largest relative difference
of each quantity; exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import math
import pickle
import sys
from pathlib import Path

import numpy as np

from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.recording_fits import choose_structure, structured_options
from hop_impedance.impedance.stance_fit import FitOptions, JointImpedanceFit, fit_joint_stance

JOINTS = ("ankle", "knee", "hip")
REPO = Path(__file__).resolve().parents[1]
SYNTHETIC_FREQUENCIES_HZ = (1.53, 1.87, 2.20)
SYNTHETIC_STANCES = 20
SEED_TERMS = ("k0", "k1", "b0")


# -- inputs -----------------------------------------------------------------
def recording_inputs(path: Path) -> dict:
    """The fit's inputs of one recording: options and per-stance joint arrays (None for a rejected stance)."""
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.impedance.recording_fits import _recording_options
    from hop_impedance.io.recording_io import load_recording

    analysis = analyze_recording(load_recording(path))
    stances = []
    for stance in analysis.stances:
        if stance.rejection_reason is not None or stance.joints is None:
            stances.append({"reason": stance.rejection_reason or "no joint data for this stance"})
            continue
        joints = {}
        for joint in JOINTS:
            data = stance.joints.joint(joint)
            joints[joint] = tuple(
                np.array(data[key], float) for key in ("time_s", "angle_rad", "angular_velocity_rad_s", "moment_nm")
            )
        stances.append({"reason": None, "joints": joints})
    return {"options": _recording_options(analysis, None), "stances": stances, "analysis": analysis}


def synthetic_inputs() -> dict:
    """Seeded noisy seed stances (three joints) at the three frequencies, as the fit benchmark makes them."""
    from hop_impedance.impedance.synthetic import synthetic_stance

    rng = np.random.default_rng(0)
    stances = []
    for freq in SYNTHETIC_FREQUENCIES_HZ:
        for _ in range(SYNTHETIC_STANCES):
            joints = {}
            for joint in JOINTS:
                st = synthetic_stance(joint, freq, rng, realistic_noise=True)
                joints[joint] = (st.time_s, st.angle_rad, st.angular_velocity_rad_s, st.moment_nm)
            stances.append({"reason": None, "joints": joints})
    return {"options": FitOptions(noise_bandwidth_hz=12.0), "stances": stances}


# -- the fits, in fit_recording_trial's order -------------------------------
def _fit(arrays, options: FitOptions, solver: ConstrainedLeastSquares) -> JointImpedanceFit:
    return fit_joint_stance(*arrays, options, solver)


def trial_fits(inputs: dict) -> dict:
    """Per-stance reduced fits, chosen structures and structured refits (``fit_recording_trial``'s steps)."""
    options = inputs["options"]
    solvers: dict = {}

    def stance_fits(opts_of_joint, key_of_joint):
        out = []
        for stance in inputs["stances"]:
            if stance["reason"] is not None:
                out.append({j: JointImpedanceFit(status="rejected", rejection_reason=stance["reason"]) for j in JOINTS})
                continue
            fits = {}
            for j in JOINTS:
                solver = solvers.setdefault(key_of_joint(j), ConstrainedLeastSquares(eps=options.osqp_eps))
                fits[j] = _fit(stance["joints"][j], opts_of_joint(j), solver)
            out.append(fits)
        return out

    own = stance_fits(lambda j: options, lambda j: j)
    structures = {j: choose_structure([f[j] for f in own]) for j in JOINTS}
    structured = stance_fits(
        lambda j: structured_options(options, structures[j]), lambda j: f"{j} {' '.join(structures[j].terms)}"
    )
    return {"own": own, "structures": structures, "fits": structured}


def given_structure_fits(inputs: dict, terms=SEED_TERMS) -> list:
    """Every stance fitted with ``terms`` (no reduction), one workspace per joint (the live, fixed-structure path)."""
    options = FitOptions(noise_bandwidth_hz=inputs["options"].noise_bandwidth_hz, reduce=False, terms=terms)
    solvers = {j: ConstrainedLeastSquares(eps=options.osqp_eps) for j in JOINTS}
    return [{j: _fit(s["joints"][j], options, solvers[j]) for j in JOINTS} for s in inputs["stances"]]


def all_fits(inputs: dict) -> dict:
    out = trial_fits(inputs)
    out["given"] = given_structure_fits(inputs)
    return out


# -- flattening and comparison ----------------------------------------------
def fit_record(fit: JointImpedanceFit) -> dict:
    """Every reported number of one fit, as plain values and arrays."""
    rec = {
        "status": fit.status,
        "rejection_reason": fit.rejection_reason,
        "terms": tuple(fit.terms),
        "effective_samples": fit.effective_samples,
    }
    for group in ("coefficients", "std_errors", "p_values"):
        for name, value in getattr(fit, group).items():
            rec[f"{group}.{name}"] = value
    for name in ("rho0", "omega0", "rmse", "r_squared", "sse_variable", "sse_constant", "table3_variable",
                 "table3_constant", "overall_stiffness", "average_stiffness"):
        rec[name] = getattr(fit, name)
    for name in ("stiffness", "damping", "moment_fit", "moment_constant"):
        rec[name] = np.asarray(getattr(fit, name), float)
    if fit.reduction is not None:
        r = fit.reduction
        rec["reduction.terms"] = tuple(r.terms)
        rec["reduction.steps"] = tuple((s.term, s.reason) for s in r.steps)
        for k, s in enumerate(r.steps):
            rec[f"reduction.step{k}.p"], rec[f"reduction.step{k}.F"], rec[f"reduction.step{k}.vif"] = (
                s.p_value, s.f_statistic, s.vif)
        for name, value in r.p_values.items():
            rec[f"reduction.p.{name}"] = value
        for name, value in r.f_statistics.items():
            rec[f"reduction.F.{name}"] = value
        rec["reduction.effective_samples"] = r.effective_samples
    if fit.diagnostics is not None:
        d = fit.diagnostics
        rec["diagnostics.terms"] = tuple(d.terms)
        for name in ("hessian_log10_determinant", "hessian_eigenvalue_ratio", "correlation_determinant",
                     "correlation_eigenvalue_ratio"):
            rec[f"diagnostics.{name}"] = getattr(d, name)
        rec["diagnostics.correlation_matrix"] = np.asarray(d.correlation_matrix, float)
        rec["diagnostics.vif"] = np.asarray(d.variance_inflation_factors, float)
    return rec


def records(fits: dict) -> dict:
    out = {"structures": {j: tuple(s.terms) for j, s in fits["structures"].items()}}
    for kind in ("own", "fits", "given"):
        out[kind] = [{j: fit_record(f) for j, f in stance.items()} for stance in fits[kind]]
    return out


def relative_difference(a, b) -> float:
    """0 for equal values (NaN = NaN, inf = inf); else the relative difference (module docstring); inf for a type/shape change."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a, float), np.asarray(b, float)
        if a.shape != b.shape:
            return math.inf
        if not np.array_equal(np.isnan(a), np.isnan(b)) or not np.array_equal(np.isinf(a), np.isinf(b)):
            return math.inf
        finite = np.isfinite(a)
        if not np.array_equal(a[~finite & ~np.isnan(a)], b[~finite & ~np.isnan(b)]):
            return math.inf
        if not finite.any():
            return 0.0
        diff = float(np.max(np.abs(a[finite] - b[finite])))
        scale = max(float(np.max(np.abs(a[finite]))), float(np.max(np.abs(b[finite]))))
        return 0.0 if diff == 0.0 else diff / scale
    if isinstance(a, float) or isinstance(b, float):
        if not isinstance(a, (int, float)) or not isinstance(b, (int, float)):
            return math.inf
        a, b = float(a), float(b)
        if math.isnan(a) or math.isnan(b):
            return 0.0 if math.isnan(a) and math.isnan(b) else math.inf
        if a == b:
            return 0.0
        if math.isinf(a) or math.isinf(b):
            return math.inf
        return abs(a - b) / max(abs(a), abs(b))
    return 0.0 if a == b else math.inf


def compare(reference: dict, current: dict, rtol: float, label: str) -> tuple[bool, dict]:
    """(all within rtol, largest relative difference per quantity name); prints every failure."""
    worst: dict[str, float] = {}
    ok = True
    if reference["structures"] != current["structures"]:
        print(f"  {label}: structures differ: {reference['structures']} vs {current['structures']}")
        ok = False
    for kind in ("own", "fits", "given"):
        for i, (ref_stance, cur_stance) in enumerate(zip(reference[kind], current[kind], strict=True)):
            for joint in JOINTS:
                ref, cur = ref_stance[joint], cur_stance[joint]
                for key in sorted(set(ref) | set(cur)):
                    generic = key.split(".")[0] + ("." + key.split(".")[-1] if "step" in key else "")
                    diff = relative_difference(ref.get(key), cur.get(key)) if key in ref and key in cur else math.inf
                    worst[generic] = max(worst.get(generic, 0.0), diff)
                    if diff > rtol:
                        ok = False
                        print(f"  {label} {kind} stance {i} {joint} {key}: {ref.get(key)!r} -> {cur.get(key)!r} "
                              f"(relative {diff:.3g})")
    return ok, worst


# -- commands ---------------------------------------------------------------
def sources() -> dict:
    out = {path.name: path for path in sorted((REPO / "recordings").glob("*.mcap"))}
    out["synthetic"] = None
    return out


def save(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for name, path in sources().items():
        inputs = recording_inputs(path) if path is not None else synthetic_inputs()
        fits = all_fits(inputs)
        if path is not None:  # the replayed order is fit_recording_trial's own
            from hop_impedance.impedance.recording_fits import fit_recording_trial

            trial = fit_recording_trial(inputs.pop("analysis"))
            check = {"structures": trial.structures, "own": trial.stance_fits, "fits": trial.fits, "given": fits["given"]}
            # 1e-12, not 0: the saved arrays are contiguous copies of the analysis' strided joint columns,
            # which changes numpy's summation order (measured differences ~1e-15)
            same, _ = compare(records(check), records(fits), 1e-12, f"{name} (replay vs fit_recording_trial)")
            if not same:
                raise SystemExit(f"{name}: the replayed fit order does not reproduce fit_recording_trial")
        with open(directory / f"{name}.pkl", "wb") as fh:
            pickle.dump({"inputs": inputs, "records": records(fits)}, fh)
        n_fit = sum(s["reason"] is None for s in inputs["stances"])
        print(f"{name}: {len(inputs['stances'])} stances ({n_fit} with joint data) saved")


def check(directory: Path, rtol: float) -> int:
    files = sorted(directory.glob("*.pkl"))
    if not files:
        print(f"no snapshot in {directory} (run --save first)", file=sys.stderr)
        return 2
    all_ok, worst_all = True, {}
    for file in files:
        with open(file, "rb") as fh:
            saved = pickle.load(fh)
        current = records(all_fits(saved["inputs"]))
        ok, worst = compare(saved["records"], current, rtol, file.stem)
        all_ok &= ok
        for k, v in worst.items():
            worst_all[k] = max(worst_all.get(k, 0.0), v)
        n = sum(len(current[kind]) for kind in ("own", "fits", "given")) * len(JOINTS)
        print(f"{file.stem}: {n} joint fits, {'equal' if ok else 'DIFFERENT'} within {rtol:g} "
              f"(largest relative difference {max(worst.values(), default=0.0):.3g})")
    nonzero = ", ".join(f"{k} {v:.2g}" for k, v in sorted(worst_all.items()) if v > 0)
    print(f"largest relative difference per quantity: {nonzero or 'none (all exactly equal)'}")
    print("ALL EQUAL" if all_ok else "DIFFERENCES FOUND")
    return 0 if all_ok else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--save", type=Path, metavar="DIR", help="analyse the bundled recordings, save inputs and fits")
    group.add_argument("--check", type=Path, metavar="DIR", help="refit the saved inputs and compare")
    parser.add_argument("--rtol", type=float, default=1e-9, help="relative tolerance of --check (default 1e-9)")
    args = parser.parse_args()
    if args.save:
        save(args.save)
        return 0
    return check(args.check, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
