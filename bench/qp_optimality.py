"""How often the constrained fit misses the QP optimum: OSQP (our path) against SLSQP, per model size.

For bench-like synthetic stances (seed Table 1/2, 200 Hz, realistic noise),
fits each joint with the given terms and ``reduce=False`` (the constrained
QP of Eqs. 6-9 on exactly those terms), solves the same QP with scipy's SLSQP
(``cross_check.fit_by_slsqp``), and counts the fits where SLSQP's solution is
feasible (every row >= -1e-9 on the scaled rows) and its SSE lower than ours
by more than 1e-6 relative: our fit did not reach the optimum. Also counts
fits that printed OSQP's "Polishing not needed" line (file descriptor 1).

    .venv/bin/python bench/qp_optimality.py                       # full 8-term model, 100 stances x 3 joints
    .venv/bin/python bench/qp_optimality.py --terms k0 k1 b0      # the seed's reduced law
    .venv/bin/python bench/qp_optimality.py --fresh               # a new OSQP workspace per fit
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from hop_impedance.impedance.constraints import constraint_rows
from hop_impedance.impedance.cross_check import fit_by_slsqp
from hop_impedance.impedance.qp_fit import ConstrainedLeastSquares
from hop_impedance.impedance.regression_model import TERM_NAMES, parameter_indices, stance_regressors
from hop_impedance.impedance.stance_fit import FitOptions, fit_joint_stance
from hop_impedance.impedance.synthetic import synthetic_stance

JOINTS = ("ankle", "knee", "hip")


def fit_and_capture(stance, options, solver) -> tuple[object, bool]:
    """The fit and whether anything reached file descriptor 1 during it."""
    with tempfile.TemporaryFile() as sink:
        saved = os.dup(1)
        os.dup2(sink.fileno(), 1)
        try:
            fit = fit_joint_stance(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s, stance.moment_nm,
                                   options, solver)
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        sink.seek(0)
        return fit, bool(sink.read())


def slsqp_gap(stance, terms, fit) -> float:
    """(our SSE - SLSQP's SSE) / our SSE when SLSQP's point is feasible, else 0."""
    regs = stance_regressors(stance.time_s, stance.angle_rad, stance.angular_velocity_rad_s)
    columns = parameter_indices(terms)
    X = regs.moment_rows[:, columns]
    A, _ = constraint_rows(regs, columns)
    theta = fit_by_slsqp(X, stance.moment_nm, A)
    scaled_rows = A / np.maximum(np.linalg.norm(A, axis=1), 1e-300)[:, None]
    if (scaled_rows @ theta).min() < -1e-9 * max(1.0, float(np.abs(theta).max())):
        return 0.0
    sse = float(np.sum((stance.moment_nm - X @ theta) ** 2))
    return (fit.sse_variable - sse) / fit.sse_variable


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stances", type=int, default=100, help="stances per frequency")
    parser.add_argument("--terms", nargs="+", default=list(TERM_NAMES), help="model terms (default: all eight)")
    parser.add_argument("--fresh", action="store_true",
                        help="a new solver per fit (fit_joint_stance without a solver) instead of one per joint, warm-started")
    args = parser.parse_args()
    terms = tuple(t for t in TERM_NAMES if t in args.terms)
    options = FitOptions(noise_bandwidth_hz=12.0, reduce=False, terms=terms)
    cpu0 = time.process_time()
    rng = np.random.default_rng(0)
    for freq in (1.53, 1.87, 2.20):
        solvers = {j: ConstrainedLeastSquares() for j in JOINTS}
        gaps, printed, fits = [], 0, 0
        for _ in range(args.stances):
            for joint in JOINTS:
                stance = synthetic_stance(joint, freq, rng, realistic_noise=True)
                fit, wrote = fit_and_capture(stance, options, None if args.fresh else solvers[joint])
                printed += wrote
                fits += 1
                if fit.ok:
                    gaps.append(slsqp_gap(stance, terms, fit))
        gaps = np.array(gaps)
        missed = gaps > 1e-6
        worst = gaps.max() if gaps.size else float("nan")
        print(f"{freq:.2f} Hz, terms {' '.join(terms)}: {fits} fits, {missed.sum()} above SLSQP's feasible SSE by > 1e-6 "
              f"(worst {100 * worst:.3f} %), {printed} printed on stdout", flush=True)
    print(f"CPU {time.process_time() - cpu0:.1f} s")


if __name__ == "__main__":
    main()
