"""Session 17: can discovery's Eq. 7 fit use the seed's one constrained least-squares solver?

``identify.constrained_lstsq`` (session 16: SVD -> LSI -> LDP -> ``scipy.optimize.nnls`` + polish) and
``impedance.qp_fit.ConstrainedLeastSquares.solve`` (OSQP working set + polish) solve the same problem,
``min |y - x c|^2`` subject to ``rows @ c >= 0``. This bench collects the problems discovery really hands to the
constrained path (every ``fit_joint_law`` joint whose unconstrained optimum breaks Eq. 7) and solves each with both:

- ``--record DIR``: the joint-law fits discovery makes (baseline and each joint effect, all stances and the gate's
  two folds; :func:`record`) on a few recordings with ``identify.EQ7_FIT`` on, saving each constrained problem to
  ``DIR/<n>.npz``;
- ``--seed-problems``: the seed's own problems (synthetic stances, Eqs. 7-9 rows): per stance the time, the
  objective relative to the exact path's and the smallest row over ``|rows| @ |c|`` of OSQP's working set, OSQP's
  full row set and the exact path;
- ``--compare DIR``: per saved problem ``qp_fit.exact_constrained_lstsq`` (session 16's ``identify.constrained_lstsq``,
  moved in session 17: the largest coefficient difference to the copy this bench kept then was 0.0; the copy is gone,
  ``git show 1467d67:hop_impedance/discovery/identify.py`` has it) and ``ConstrainedLeastSquares.solve`` (zero-norm
  columns dropped for it, it raises on them; their coefficient set to 0); printed: the largest coefficient
  difference over ``max(1, |c|)``, OSQP's objective relative to the NNLS one, the smallest row value
  ``min(rows @ c)`` (K or B, N m/rad or N m s/rad), the time, how often OSQP fell back to the full row set or did not converge.

Usage::

    PYTHONPATH=<checkout> nice -n 19 .venv/bin/python bench/eq7_solver_fold.py --record /tmp/p
    PYTHONPATH=<checkout> nice -n 19 .venv/bin/python bench/eq7_solver_fold.py --compare /tmp/p
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def record(args) -> None:
    """Every constrained problem of the joint-law fits discovery makes on the recordings (regression only).

    Per recording (``--strict-null-seeds`` of the second generator, ``--cases`` of our simulator at 2.2 Hz, seed 0),
    with the table body: the baseline and each joint effect added (the baseline plus it, and the angle law plus
    it), fitted on all stances and on each of the gate's two folds' training stances, with EQ7_FIT on; each joint
    whose unconstrained optimum breaks Eq. 7 goes to the constrained solver and is saved.
    """
    import discovery_hit_rates as hr

    from hop_impedance.discovery import identify
    from hop_impedance.discovery.measurement import measure_trial
    from hop_impedance.discovery.model import JOINT_EFFECTS, ModelSpec
    from hop_impedance.discovery.stiffness_gate import fold_indices
    from hop_impedance.validation.strict_generator import strict_recording

    out = Path(args.record)
    out.mkdir(parents=True, exist_ok=True)
    identify.EQ7_FIT = True
    solver = identify.exact_constrained_lstsq
    count = [0]

    def saving(x, y, rows):
        count[0] += 1
        np.savez(out / f"{count[0]:05d}.npz", x=x, y=y, rows=rows)
        return solver(x, y, rows)

    identify.exact_constrained_lstsq = saving
    recs = [(f"strict null {s}", strict_recording(replace(hr.STRICT_CASES["null"], seed=s, hops=8))[0])
            for s in (int(v) for v in args.strict_null_seeds.split(",") if v)]
    recs += [(f"{c} 2.2 Hz", hr.generate(c, 0, 8, freqs=(2.2,))[0]) for c in filter(None, args.cases.split(","))]
    for label, rec in recs:
        trial = measure_trial(rec)
        order = [s.index for s in trial.stances]
        sets = [tuple(order)] + [tr for tr, _ in fold_indices(order, 2)]
        specs = [(ModelSpec(), None)] + [(ModelSpec(), e) for e in JOINT_EFFECTS]
        specs += [(ModelSpec().with_effect("angle_dependent_stiffness"), e) for e in JOINT_EFFECTS
                  if e != "angle_dependent_stiffness"]
        before = count[0]
        for spec, effect in specs:
            for train in sets:
                identify.identify(spec, trial, [s for s in trial.stances if s.index in train], effect)
        print(f"{label}: {count[0] - before} constrained problems", flush=True)


def compare(args) -> None:
    from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares, exact_constrained_lstsq

    files = sorted(Path(args.compare).glob("*.npz"))[::args.every]
    osqp_solver = ConstrainedLeastSquares()
    shapes, zero_cols, rank_def = [], 0, 0
    stats = {k: [] for k in ("osqp_vs_exact", "sse_osqp_rel", "min_row_exact", "min_row_osqp", "t_exact", "t_osqp",
                             "osqp_fallback", "osqp_unconverged")}
    for f in files:
        d = np.load(f)
        x, y, rows = d["x"], d["y"], d["rows"]
        shapes.append((x.shape, rows.shape))
        zero = np.linalg.norm(x, axis=0) == 0
        zero_cols += bool(zero.any())
        rank_def += np.linalg.matrix_rank(x) < x.shape[1]
        t1 = time.perf_counter()
        c_new = exact_constrained_lstsq(x, y, rows)
        t2 = time.perf_counter()
        keep = ~zero
        try:
            sol = osqp_solver.solve(x[:, keep], y, rows[:, keep])
            c_osqp = np.zeros(x.shape[1])
            c_osqp[keep] = sol.coefficients
            stats["osqp_fallback"].append(sol.working_rows == -1)
            stats["osqp_unconverged"].append(not sol.converged)
        except ValueError:
            c_osqp = np.full(x.shape[1], np.nan)
        t3 = time.perf_counter()
        scale = max(np.abs(c_new).max(), np.abs(c_osqp).max() if np.isfinite(c_osqp).all() else 0.0, 1.0)
        def sse(c, x=x, y=y):
            return float(np.sum((y - x @ c) ** 2))

        stats["osqp_vs_exact"].append(np.abs(c_osqp - c_new).max() / scale)
        stats["sse_osqp_rel"].append(sse(c_osqp) / max(sse(c_new), 1e-300) - 1)
        stats["min_row_exact"].append(float(np.min(rows @ c_new)))
        stats["min_row_osqp"].append(float(np.min(rows @ c_osqp)))
        stats["t_exact"].append(t2 - t1)
        stats["t_osqp"].append(t3 - t2)
    print(f"{len(files)} problems; rows {min(r[0] for _, r in shapes)}-{max(r[0] for _, r in shapes)}, "
          f"unknowns {min(s[1] for s, _ in shapes)}-{max(s[1] for s, _ in shapes)}; with a zero-norm column "
          f"{zero_cols}, rank-deficient {rank_def}")
    for k, v in stats.items():
        v = np.asarray(v, float)
        if v.size:
            print(f"  {k:18s} min {np.nanmin(v):.3g}  max {np.nanmax(v):.3g}  median {np.nanmedian(v):.3g}  "
                  f"sum {np.nansum(v):.4g}  nan {int(np.isnan(v).sum())}")


def seed_problems() -> None:
    """The seed's own problems (synthetic stances, Eqs. 7-9 rows): OSQP working set, OSQP all rows, exact path."""
    import time

    from hop_impedance.impedance.constraints import constraint_rows
    from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares, exact_constrained_lstsq
    from hop_impedance.impedance.regression_model import TERM_NAMES, parameter_indices, stance_regressors
    from hop_impedance.impedance.synthetic import synthetic_stance

    # test_qp_fit.py's FULL_ROW_FALLBACK_CASES, then the full model on 24 stances
    cases = [(1.53, 55, "ankle", ("k0", "k1", "b0", "b3")), (2.20, 2, "knee", ("k0", "k1", "b0", "b3")),
             (2.20, 50, "ankle", ("k0", "k1", "b0", "b1")), (2.20, 73, "knee", ("k0", "k1", "b0", "b3"))]
    cases += [(f, s, j, TERM_NAMES) for f in (1.53, 2.2) for s in range(4) for j in ("ankle", "knee", "hip")]
    for f, seed, joint, terms in cases:
        st = synthetic_stance(joint, f, np.random.default_rng(seed), realistic_noise=True)
        regs = stance_regressors(st.time_s, st.angle_rad, st.angular_velocity_rad_s)
        cols = parameter_indices(terms)
        rows, _ = constraint_rows(regs, cols)
        x, y = regs.moment_rows[:, cols], st.moment_nm
        out = {}
        for name in ("OSQP working set", "OSQP all rows", "exact"):
            t0 = time.perf_counter()
            if name == "exact":
                c = exact_constrained_lstsq(x, y, rows)
            else:
                c = ConstrainedLeastSquares(working_set=name == "OSQP working set").solve(x, y, rows).coefficients
            out[name] = (c, time.perf_counter() - t0)
        sse_exact = float(np.sum((y - x @ out["exact"][0]) ** 2))
        line = f"{f} Hz seed {seed} {joint:5s} {len(terms)} terms, {rows.shape[0]} rows:"
        for name, (c, t) in out.items():
            worst = np.min(rows @ c / np.maximum(np.abs(rows) @ np.abs(c), 1e-300))
            line += (f" | {name} {t * 1e3:.1f} ms, objective / exact - 1 {np.sum((y - x @ c) ** 2) / sse_exact - 1:+.1e},"
                     f" min scaled row {worst:+.1e}")
        print(line, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--record")
    ap.add_argument("--compare")
    ap.add_argument("--seed-problems", action="store_true", help="the seed's problems: OSQP against the exact path")
    ap.add_argument("--every", type=int, default=1, help="compare every N-th saved problem")
    ap.add_argument("--strict-null-seeds", default="35,3,47")
    ap.add_argument("--cases", default="joint_damping,angle_dependent_stiffness,time_dependent_activation")
    args = ap.parse_args()
    if args.record:
        record(args)
    if args.compare:
        compare(args)
    if args.seed_problems:
        seed_problems()


if __name__ == "__main__":
    main()
