"""Which per-stance fits leave OSQP's working-set path for the all-rows solve, and what it costs.

Session 14 found the short-window modes' p99 on recordings/sim_2p20hz_hard.mcap in one fit: after publishing a
stance's feed, ``impedance_estimator`` runs that stance's own per-stance fits (``fit_stance_joints``, the
diagnostics and F-tests beside the feed), and on a short window one of them (then stance 2's knee, full five-term
model; on session 32's recording the degenerate working set is stance 1's ankle, kept on it) leaves the
working set (``qp_fit`` module docstring) for :meth:`ConstrainedLeastSquares.solve_all_rows`.
This bench analyses the recording the way the live stage does (``AnalysisOptions.post_takeoff_s``), times every
per-stance fit, and for each fit that fell back prints why (each working-set round's rows and OSQP status), the
all-rows solve's iterations and the number of constraint rows active at its solution. Nothing is changed.

With ``--eps 1e-5,1e-4`` each fallen-back problem is solved again on all rows with
``ConstrainedLeastSquares(eps=E)`` (the last ADMM stage's tolerance) and its iterations, time, SSE and
coefficients are printed beside the default's: a lead for a fallback that does not cost 0.4 s.

Usage: .venv/bin/python bench/qp_fallback.py [REC.mcap] [--pads 0.005,0.003] [--slow-ms 30] [--eps 1e-5,1e-4]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

from hop_impedance.biomech.analysis import AnalysisOptions, analyze_recording
from hop_impedance.biomech.joint_angles import JOINT_NAMES
from hop_impedance.impedance import qp_fit
from hop_impedance.impedance.recording_fits import fit_stance_joints
from hop_impedance.io.recording_io import load_recording

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording", nargs="?", default=str(ROOT / "recordings" / "sim_2p20hz_hard.mcap"))
    ap.add_argument("--pads", default="0.005,0.003", help="post_takeoff_s of the short windows (s); 'batch' for none")
    ap.add_argument("--slow-ms", type=float, default=30.0, help="print fits slower than this")
    ap.add_argument("--eps", default="", help="also solve each fallen-back problem on all rows with these eps")
    args = ap.parse_args()
    rec = load_recording(args.recording)
    rounds: list[tuple[int, str, int]] = []
    all_rows: list[tuple[int, int, int]] = []  # (constraint rows, iterations, rows active at the solution)
    problems: list[tuple] = []  # the fallen-back problems and the default's solution
    solve_rows = qp_fit.ConstrainedLeastSquares._solve_rows
    solve_all = qp_fit.ConstrainedLeastSquares.solve_all_rows

    def traced_all(self, design, target, constraints):  # type: ignore[no-untyped-def]
        out = solve_all(self, design, target, constraints)
        all_rows.append((constraints.shape[0], out.iterations, out.n_active))
        problems.append((design.copy(), target.copy(), constraints.copy(), out))
        return out

    def traced(self, solver, p_upper, q, rows, x0, y0):  # type: ignore[no-untyped-def]
        out = solve_rows(self, solver, p_upper, q, rows, x0, y0)
        rounds.append((rows.shape[0], out[0], out[3]))
        return out

    qp_fit.ConstrainedLeastSquares._solve_rows = traced  # type: ignore[method-assign]
    qp_fit.ConstrainedLeastSquares.solve_all_rows = traced_all  # type: ignore[method-assign]
    for pad in args.pads.split(","):
        options = AnalysisOptions() if pad == "batch" else dataclasses.replace(AnalysisOptions(), post_takeoff_s=float(pad))
        analysis = analyze_recording(rec, options)
        solvers: dict = {}
        fell_back, total = 0, 0.0
        for i, stance in enumerate(analysis.stances):
            for joint in JOINT_NAMES:
                rounds.clear()
                all_rows.clear()
                t0 = time.perf_counter()
                fit = fit_stance_joints(stance, None, solvers, joints=(joint,))[joint]
                dt = time.perf_counter() - t0
                total += dt
                if all_rows:
                    fell_back += 1
                if dt * 1e3 >= args.slow_ms or all_rows:
                    print(f"window {pad}: stance {i} {joint}: {dt * 1e3:.0f} ms, status {fit.status}; working-set rounds "
                          f"(rows, status, iterations): {rounds}; all-rows solves (rows, iterations, rows active at the "
                          f"solution): {all_rows}")
        for design, target, constraints, default in problems if args.eps else []:
            print(f"  default eps: {default.iterations} iterations, SSE {default.sse:.4f}, {default.coefficients}")
            for eps in (float(e) for e in args.eps.split(",")):
                t0 = time.perf_counter()
                other = solve_all(qp_fit.ConstrainedLeastSquares(eps=eps), design, target, constraints)
                print(f"  eps {eps:g}: {other.iterations} iterations, {(time.perf_counter() - t0) * 1e3:.0f} ms, "
                      f"status {other.status}, SSE {other.sse:.4f}, {other.coefficients}")
        problems.clear()
        print(f"window {pad}: {len(analysis.stances)} stances, per-stance fits {total:.2f} s in all, "
              f"{fell_back} fell back to the all-rows solve")


if __name__ == "__main__":
    main()
