"""The baseline's held-out gap of each stance of a recording, term by term, with and without the touchdown-velocity fit.

Each stance left out once: the strict baseline identified on the others and the stance simulated as discovery does
(``forward_selection.HeldOutEvaluator.run``, so every stance is simulated whatever ``--stances`` prints), once from the
measured touchdown state and once with ``forward_selection.TOUCHDOWN_VELOCITY_FIT_S`` = W (the velocities corrected on
the stance's first W s). Printed per
stance: the gap G, the seven RMS terms over their scales (GRF, ankle / knee / hip angle, ankle / knee / hip moment),
the duration error, the simulated and measured net joint work and the end reason.

Why (session 19): with the fit as the default ``make test``'s bundled 2.2 Hz trial (``recordings/sim_2p20hz_hard.mcap``,
stances on the seed-like hopper's shoe pad) named nothing where it names the surface without it; its baseline's
held-out gap was 2.96 against 0.92, from three stances that take off far too early with the fitted velocities.

``--discover``: also ``discover`` on the recording with and without the fit, printing the effects named, every
round's held-out screen (p, pooled shrink) and the stiffness gate's p.

``--accept-step`` (session 20): the fit's sub-option ``forward_selection.VELOCITY_FIT_ACCEPT`` on the runs with the
fit. (Session 20's ``--own-ground-jacobian`` / ``--shared`` and session 21's ``--paired candidate|current``, the
sub-options measured and not adopted, were removed in session 23; they run at commit a93ac09.)
``--fit-only``: skip the runs without the fit (the default's, known).

``--simulate-from D`` (session 22): ``forward_selection.SIMULATE_FROM_S`` = D instead of the fit in the runs "with"
(every held-out stance simulated from the measured state D s after its touchdown and compared from there; the fit
column then reads ``from D``). ``--two-segment`` (session 23, with ``--simulate-from``):
``forward_selection.TWO_SEGMENT`` too (the touchdown run compared before the start sample, the late run from it; the
column reads ``2seg D``); ``--two-segment-flight``: ``forward_selection.TWO_SEGMENT_FLIGHT`` too (a run from the
touchdown that takes off before the start sample compared as in flight up to it).

Usage: .venv/bin/python bench/discovery_stance_terms.py REC.mcap [--touchdown-velocity-fit 0.06] [--stances 5,6,8]
       [--discover] [--accept-step] [--fit-only]
       [--simulate-from 0.06 [--two-segment]]
"""

from __future__ import annotations

import argparse

import numpy as np
from two_segment_flags import add_two_segment_arguments, check_two_segment

from hop_impedance.discovery import forward_selection as fs
from hop_impedance.discovery.measurement import measure_trial
from hop_impedance.discovery.model import ModelSpec
from hop_impedance.io.recording_io import load_recording


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording")
    ap.add_argument("--touchdown-velocity-fit", type=float, default=0.06, metavar="W")
    ap.add_argument("--stances", default="", help="positions in the measured trial, e.g. 5,6,8 (default: all)")
    ap.add_argument("--discover", action="store_true", help="also discover with and without the fit")
    ap.add_argument("--accept-step", action="store_true", help="forward_selection.VELOCITY_FIT_ACCEPT")
    ap.add_argument("--fit-only", action="store_true", help="only the runs with the fit")
    ap.add_argument("--simulate-from", type=float, default=None, metavar="D",
                    help="forward_selection.SIMULATE_FROM_S = D instead of the fit (session 22)")
    add_two_segment_arguments(ap, "--simulate-from")
    args = ap.parse_args()
    check_two_segment(ap, args, "--simulate-from", args.simulate_from is not None)
    fs.VELOCITY_FIT_ACCEPT = args.accept_step  # module options: set before any evaluator forks its workers
    rec = load_recording(args.recording)
    trial = measure_trial(rec)
    scales = fs.gap_scales(trial)
    picked = [int(k) for k in args.stances.split(",") if k] or range(len(trial.stances))
    print("stance  fit     G       GRF  ang_a ang_k ang_h mom_a mom_k mom_h  duration ms  work sim / measured J  end")
    means = {}
    with_fit = f"from {args.simulate_from}" if args.simulate_from is not None else args.touchdown_velocity_fit
    if args.two_segment:
        with_fit = f"2seg{'F' if args.two_segment_flight else ''} {args.simulate_from}"
    windows = (with_fit,) if args.fit_only else (None, with_fit)

    def configure(window) -> None:  # before the evaluator forks its workers, which read it
        late = isinstance(window, str)
        fs.TOUCHDOWN_VELOCITY_FIT_S = None if late else window
        fs.SIMULATE_FROM_S = args.simulate_from if late else None
        fs.TWO_SEGMENT = late and args.two_segment

    for window in windows:
        configure(window)
        with fs.HeldOutEvaluator(rec, trial) as ev:  # discovery's own leave-one-out runs of the baseline
            r = ev.run(ModelSpec(), [None])[0]
        measured = fs.measured_net_works_j(trial, compared=True)  # over the samples the simulated work is over
        for k in picked:
            terms = " ".join(f"{v:5.2f}" for v in r.rms[k] / scales[:7])
            print(f"{k:>6}  {str(window):<6} {r.gaps[k]:7.3f}  {terms}  {1e3 * r.duration_error_s[k]:+8.0f}  "
                  f"{r.net_work_j[k]:+8.1f} / {measured[k]:+6.1f}  {r.end_reasons[k]}", flush=True)
        means[window] = float(np.mean(r.gaps[list(picked)]))
    print("mean G: " + ", ".join(f"fit {w}: {g:.3f}" for w, g in means.items()))
    if args.discover:
        from hop_impedance.discovery.workflow import discover

        for window in windows:
            configure(window)
            doc = discover(rec)
            print(f"discover, fit {window}: named {doc['effects_found'] or 'nothing'}, baseline gap "
                  f"{doc['baseline_gap']['total']:.3f}, {doc['timing']['total_s']:.0f} s")
            for r, rnd in enumerate(doc["selection"]["rounds"]):
                print(f"  round {r} screen: " + ", ".join(f"{e} p {v['p_value']:.2g} shrink {100 * v['held_out_shrink']:+.0f} %"
                                                          for e, v in rnd.items() if v["held_out_shrink"] > 0))
            for g in doc["selection"]["stiffness_through_simulation"]:
                print(f"  round {g['round']} gate: current shot, mean per-stance gap "
                      f"{np.mean(g['current']['per_stance_gap_shot']):.3f}; "
                      + ", ".join(f"{e} p {v['p_value']:.2g} passes {v['passes']}, shot "
                                  f"{np.mean(v['per_stance_gap_shot']):.3f}"
                                  + _per_signal(v)
                                  for e, v in g["candidates"].items()))


def _per_signal(gate: dict) -> str:
    """The stiffness gate's per-signal test in one phrase: passes, the best signal's p and the worst signal's."""
    per = gate.get("per_signal")
    if per is None:
        return ""
    best, b = min(per["signals"].items(), key=lambda kv: kv[1]["p_better"])
    worst, w = min(per["signals"].items(), key=lambda kv: kv[1]["p_worse"])
    return (f", per signal passes {per['passes']} (best {best} p {b['p_better']:.2g} at level {per['level']:.2g}; "
            f"worse on {worst} p {w['p_worse']:.2g})")


if __name__ == "__main__":
    main()
