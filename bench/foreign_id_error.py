"""Our inverse-dynamics moments against the outside generator's true moments, per joint and stance phase.

For every ``../shared/foreign/*.mcap`` (or the cases given) the recording is measured as discovery measures it
(:func:`hop_impedance.discovery.measurement.measure_trial`, the truth's marker latency removed) and each stance's ID
moments (extensor positive, both legs) are compared with the truth's ``stance_truth`` moments interpolated at the plate
samples (the truth's hop nearest the detected touchdown). Printed per file, medians over stances, per joint: the RMS
error in % of the truth's RMS moment, the mean error (N m) and the RMS error (N m) in the stance's first 10 %, middle
80 % and last 10 % (by sample), and the truth's RMS moment. The edges are where the 12 Hz low-pass of plate and markers
runs across the impact and the take-off; the middle is what marker noise and the body table leave.

    .venv/bin/python bench/foreign_id_error.py [--folder DIR] [--cutoffs MARKER,FORCE] [--acc-cutoff HZ] [--mean]
                                               [CASE ...]

``--cutoffs``: the analysis' marker and force low-pass cut-offs (Hz; default 12,12); ``--acc-cutoff``: segment
accelerations (``Kinematics.qdd``, ``com_acc``) from markers low-passed at this cut-off instead, everything else as
before (session 31's probe of where the hip's mid-stance error comes from); ``--mean``: also the mean over the files.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from discovery_truth_gap import measured_outside, truth_hop  # bench/ is sys.path[0]

from hop_impedance.biomech.analysis import AnalysisOptions

REPO = Path(__file__).resolve().parents[1]
JOINTS = ("ankle", "knee", "hip")


def stance_errors(s, rows: np.ndarray, cols: list, t_offset_s: float) -> np.ndarray:
    """Per joint: RMS error (% of truth RMS), mean error, RMS error first 10 % / middle / last 10 % (N m), truth RMS."""
    t = t_offset_s + s.touchdown_s + s.t_s
    tt = rows[:, cols.index("t_s")]
    inside = (t >= tt[0]) & (t <= tt[-1])
    out = []
    for k, joint in enumerate(JOINTS):
        truth = np.interp(t[inside], tt, rows[:, cols.index(f"M_{joint}")])
        err = s.moment_nm[inside, k] - truth
        a, b = int(0.1 * err.size), int(0.9 * err.size)
        rms = float(np.sqrt(np.mean(truth**2)))
        out.append([np.sqrt(np.mean(err**2)) / rms * 100, err.mean(), *(np.sqrt(np.mean(e**2)) for e in
                                                                          (err[:a], err[a:b], err[b:])), rms])
    return np.array(out)


def file_errors(path: Path, options=None) -> np.ndarray:
    """:func:`stance_errors` of every stance of one outside recording, shape (stances, 3, 6); ``options``: the
    analysis' (:func:`measured_outside`)."""
    _, truth, trial, clock_ns = measured_outside(path, options)
    rows = np.asarray(truth["stance_truth"]["rows"], float)
    cols = truth["stance_truth"]["columns"]
    offset = (clock_ns - truth["recording"]["epoch_start_ns"]) * 1e-9
    out = []
    for s in trial.stances:
        hop = truth_hop(truth, clock_ns, s)
        out.append(stance_errors(s, rows[rows[:, cols.index("hop")] == hop["hop"]], cols, offset))
    return np.array(out)


def accelerations_at(acc_hz: float) -> None:
    """``--acc-cutoff``: the analysis takes segment accelerations from markers low-passed at ``acc_hz``, everything
    else at its own cut-offs (a probe, patched in here: the analysis has no such option)."""
    from hop_impedance.biomech import analysis

    kinematics = analysis.compute_kinematics

    def patched(marker_t, markers, t_out, model, cutoff_hz, max_gap_s):
        kin, gaps = kinematics(marker_t, markers, t_out, model, cutoff_hz, max_gap_s)
        low, _ = kinematics(marker_t, markers, t_out, model, acc_hz, max_gap_s)
        return dataclasses.replace(kin, qdd=low.qdd, com_acc=low.com_acc), gaps

    analysis.compute_kinematics = patched


def line(name: str, med: np.ndarray) -> str:
    return f"{name}: " + " | ".join(
        f"{j} {m[0]:.1f} % mean {m[1]:+.1f} edges/middle {m[2]:.1f}/{m[3]:.1f}/{m[4]:.1f} N m (RMS {m[5]:.0f})"
        for j, m in zip(JOINTS, med))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--folder", default=str(REPO.parent / "shared" / "foreign"))
    ap.add_argument("--cutoffs", default="12,12", metavar="MARKER,FORCE")
    ap.add_argument("--acc-cutoff", type=float, metavar="HZ")
    ap.add_argument("--mean", action="store_true")
    args = ap.parse_args()
    marker_hz, force_hz = (float(v) for v in args.cutoffs.split(","))
    options = AnalysisOptions(marker_cutoff_hz=marker_hz, force_cutoff_hz=force_hz)
    if args.acc_cutoff is not None:
        accelerations_at(args.acc_cutoff)
    folder = Path(args.folder)
    medians = []
    for case in args.cases or sorted(p.name[:-5] for p in folder.glob("*.mcap")):
        medians.append(np.median(file_errors(folder / f"{case}.mcap", options), axis=0))
        print(line(case, medians[-1]), flush=True)
    if args.mean:
        print(line(f"mean of {len(medians)} files", np.mean(medians, axis=0)))


if __name__ == "__main__":
    main()
