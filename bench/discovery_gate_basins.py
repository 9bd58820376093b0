"""Where the stiffness gate's k0 search lands, scored with the net-work term at two weights (session 27).

Per fold of the held-out gate (``stiffness_gate.fold_indices``, 2 folds) one model's joint law is identified on the
fold's training stances; given k0 points (the regression's, and the shot k0 of ``discover --json`` documents) are
simulated on every stance and each stance's gap G is printed with the net-work term at ``WORK_SCALE`` = 1 and at
``--x`` (one simulation serves both: G's terms are kept over the X = 1 scale and the work term re-scaled), with the
net-work error (J), the samples reached (20: the run left the ground at the stance guard) and, with
``--two-sided``, the take-off error read two-sided (ms; positive: the simulation runs past the measured take-off).
``--lm X``: the gate's Levenberg-Marquardt search on each fold's training stances with the work term at X, started
from the regression and from each document's baseline shot (single process: the scales are switched in place).

Usage (session 27)::

    PYTHONPATH=. .venv/bin/python bench/discovery_gate_basins.py recordings/sim_2p20hz_hard.mcap \\
        --effects surface_compliance --doc def.json --doc flag.json --lm 1 --lm 0.25
    PYTHONPATH=. .venv/bin/python bench/discovery_gate_basins.py angle+offset \\
        --effects angle_dependent_stiffness,force_plate_offset --doc ao_def.json --doc ao_flag.json --final --two-sided

``angle+offset`` is test/discovery/test_hidden_effects.py's case (generated as the test does). ``--doc`` files are
``discover`` documents (``--json``); their round-0 gate (``--final``: ``final_gap_through_simulation``) gives the
points. ``--angle-hold`` (session 29): every point simulated with ``forward_selection.ANGLE_HOLD``.
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` is not needed (no rclpy).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery import stiffness_gate as sg
from hop_impedance.discovery.identify import identify
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec, feature_names


def recording(name: str):
    if name == "angle+offset":
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
        from test.discovery import test_hidden_effects as th

        return th.recording(name)[0]
    from hop_impedance.io.recording_io import load_recording

    return load_recording(name)


def gap_at(run: dict, x: float) -> float:
    """A stance's G with the net-work term over ``x`` times its X = 1 scale (inf: failed)."""
    if run["samples"] is None:
        return np.inf
    t = np.array(run["terms"], float)
    t[1] /= x
    return float((np.mean(run["samples"] ** 2, axis=0).sum() + (t**2).sum()) / 10)


def doc_points(docs: list[dict], final: bool, fold: int, reg: np.ndarray) -> dict[str, np.ndarray]:
    """k0 factors (on this fold's regression k0 ``reg``) of each document's shot models."""
    pts = {"regression": np.ones(3)}
    for k, d in enumerate(docs):
        if final:
            pts[f"doc{k} final shot"] = np.array(d["final_gap_through_simulation"]["k0_shot_nm_per_rad"][fold]) / reg
            continue
        g = d["selection"]["stiffness_through_simulation"][0]
        pts[f"doc{k} baseline shot"] = np.array(g["current"]["k0_shot_nm_per_rad"][fold]) / reg
        for eff, c in g["candidates"].items():
            pts[f"doc{k} {eff} shot"] = np.array(c["k0_shot_nm_per_rad"][fold]) / reg
    bad = [name for name, fac in pts.items() if not np.all(fac > 0)]
    for name in bad:  # a shot k0 of the other sign than the regression's (e.g. 1201's fold 1, a negative regression k0)
        print(f"  {name}: skipped, k0 factors {pts.pop(name)} on the regression k0 {reg} are not all > 0 "
              f"(the search moves log factors)")
    return pts


def in_order(ev, spec, coefs, indices: tuple[int, ...], fac: np.ndarray) -> list[dict]:
    """The runs of the stances ``indices`` at k0 factors ``fac``, in that order (a search keeps the trial's)."""
    runs = sg._Search(ev, spec, coefs, (), indices).points([np.log(fac)])[0].runs
    by_index = dict(zip([s.index for s in ev.trial.stances if s.index in indices], runs))
    return [by_index[i] for i in indices]


def report_point(ev, spec, coefs, train, test, name: str, fac: np.ndarray, x: float, two_sided: bool) -> None:
    runs = in_order(ev, spec, coefs, train + test, fac)
    nt = len(train)
    print(f"  {name:36s} factors {fac}")
    for xs in (1.0, x):
        g = np.array([gap_at(r, xs) for r in runs])
        print(f"    X={xs}: train mean {np.mean(np.minimum(g[:nt], 10)):.4f} held-out mean "
              f"{np.mean(np.minimum(g[nt:], 10)):.4f}  train {g[:nt]}  held out {g[nt:]}")
    work = [np.nan if r["terms"] is None else r["terms"][1] * ev.scales[8] for r in runs]
    reached = [0 if r["samples"] is None else len(r["samples"]) for r in runs]
    print(f"    (train then held out) work error J {np.array(work)}  samples reached {reached}")
    if two_sided:
        fs.TWO_SIDED_DURATION = True
        late = in_order(ev, spec, coefs, train + test, fac)
        fs.TWO_SIDED_DURATION = False
        print(f"    take-off error (two-sided) ms {np.array([1e3 * r['terms'][0] * ev.scales[7] for r in late])}")


def lm_from_docs(ev, spec, trial, split, docs: list[dict], x: float) -> None:
    base = ev.scales.copy()
    ev.scales[8] = base[8] * x
    fs._CONTEXT["scales"] = ev.scales
    col = feature_names(spec).index("k0")
    for f, (train, _) in enumerate(split):
        _, c = identify(spec, trial, [s for s in trial.stances if s.index in train])
        starts = {"the regression alone": np.ones(3)}
        for k, d in enumerate(docs):
            shot = d["selection"]["stiffness_through_simulation"][0]["current"]["k0_shot_nm_per_rad"][f]
            starts[f"doc{k}'s baseline shot"] = np.array(shot) / c[:, col]
        for name, start in starts.items():  # as the gate: the better of the regression and the start
            search = sg._Search(ev, spec, c, (), train)
            x0 = min(search.points([np.zeros(3), np.log(start)]), key=lambda p: p.mean_gap)
            best, _ = sg._levenberg_marquardt(search, x0)
            print(f"LM at X={x} fold {f} from {name} {start} -> factors {np.exp(best.x)}, training mean G "
                  f"{best.mean_gap:.4f}")
    ev.scales[:] = base
    fs._CONTEXT["scales"] = ev.scales


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("recording", help="a .mcap, or angle+offset (test_hidden_effects' case)")
    ap.add_argument("--effects", default="", help="comma-separated effects of the model (in order)")
    ap.add_argument("--doc", action="append", default=[], help="discover --json document (repeatable)")
    ap.add_argument("--x", type=float, default=0.25, help="the second WORK_SCALE the points are scored at")
    ap.add_argument("--final", action="store_true", help="points of final_gap_through_simulation")
    ap.add_argument("--factors", action="append", default=[], metavar="A,K,H",
                    help="also k0 factors (ankle, knee, hip) on each fold's regression k0 (repeatable)")
    ap.add_argument("--two-sided", action="store_true", help="also the two-sided take-off error")
    ap.add_argument("--angle-hold", action="store_true",
                    help="forward_selection.ANGLE_HOLD (session 29): the angle terms held past each stance's angles")
    ap.add_argument("--lm", type=float, action="append", default=[], metavar="X",
                    help="LM search with the work term at X from the regression and each document's baseline shot")
    args = ap.parse_args(argv)
    fs.ANGLE_HOLD = args.angle_hold
    np.set_printoptions(precision=4, suppress=True, linewidth=220)
    rec = recording(args.recording)
    trial = measure_trial(rec)
    docs = [json.loads(Path(p).read_text()) for p in args.doc]
    with fs.HeldOutEvaluator(rec, trial, workers=1) as ev:
        spec = ModelSpec()
        for e in filter(None, args.effects.split(",")):
            spec, _ = identify(spec, fs.trial_for(spec), fs.trial_for(spec).stances, e)
        spec, _ = identify(spec, trial, trial.stances)
        split = sg.fold_indices([s.index for s in trial.stances], 2)
        col = feature_names(spec).index("k0")
        for f, (train, test) in enumerate(split):
            _, c = identify(spec, trial, [s for s in trial.stances if s.index in train])
            print(f"fold {f}: train {train}, held out {test}, regression k0 {c[:, col]}")
            points = doc_points(docs, args.final, f, c[:, col])
            points.update({f"factors {v}": np.array(v.split(","), float) for v in args.factors})
            for name, fac in points.items():
                report_point(ev, spec, c, train, test, name, fac, args.x, args.two_sided)
        for x in args.lm:
            lm_from_docs(ev, spec, trial, split, docs, x)


if __name__ == "__main__":
    main()
