"""What analysing each stance on a short window after take-off costs in accuracy (issue 15, "low latency by default").

The low-latency plan: declare a take-off provisionally after a few samples below the level
(<= 5 ms at 1 kHz), analyse and fit the stance at once on a window ending ``PAD`` s after the
take-off, and analyse offline on the same windows so live and offline agree. This runs the trials
of ``bench/recovery_errors.py`` (same arguments) once with the batch analysis and once per PAD with
``AnalysisOptions.post_takeoff_s = PAD`` (:func:`hop_impedance.biomech.analysis.analyze_short_window`:
the window and end-of-stance treatment the live stage runs too, test/biomech/test_short_windows.py),
prints each table and then the cells (frequency x clean/noisy x joint x k0/k1 median error, 36 by
default) that moved by more than 2 percentage points: issue 15 requires none.

    nice -n 10 .venv/bin/python bench/low_latency_windows.py 0.005
    nice -n 10 .venv/bin/python bench/low_latency_windows.py 0.005 0.01 0.05 --frequencies 2.2

``--hip-exclusion E`` changes the time before take-off a short window's hip fit leaves out
(``recording_fits.takeoff_exclusion_s``, default 0.02 s; 0 turns it off).

``--noise-repeat`` adds the batch analysis of the same simulated trials sampled with another sensor-noise
draw: how far the noisy cells move from the noise alone, the resolution of a 2 pp bound on them.

Besides the cells moved, it counts the cells whose |median error| grew by more than 2 pp (a move
towards zero is not a loss of accuracy).

Experiments on the treatment: ``--template N`` anchors the previous hop's post-take-off motion to the
last N frames (``analysis.MARKER_TEMPLATE_FRAMES``, default 2); ``--template 0`` uses the straight line
only; ``--exclude-takeoff E`` leaves the last E s before take-off out of the short windows' fit objective;
``--marker-fit DEGREE FRAMES`` changes the straight-line fallback
(``analysis.MARKER_FIT_DEGREE`` / ``MARKER_FIT_FRAMES``, default 1 2); ``--true-markers-s H`` gives
each short window the recorded marker frames up to ``H`` s past its end (not known live), e.g.
``0.005 --true-markers-s 0.3``: the force treatment alone, with markers as in batch.

``--stance-cost`` only times one stance's short-window analysis on the bundled 2.2 Hz recording
(CPU of this thread, straight line vs template): what the live stage spends per stance.

CPU: about 25 s per frequency per analysis (batch + each PAD), as recovery_errors.py.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from recovery_errors import print_table

import hop_impedance.biomech.analysis as analysis
import hop_impedance.validation.coefficient_recovery as coefficient_recovery
from hop_impedance.validation.coefficient_recovery import JOINTS, recover_pooled

#: The key of the batch analysis with another sensor-noise draw (``--noise-repeat``) among the PADs.
NOISE_REPEAT = -1.0
#: A cell "moves" when its median error changes by more than this (percentage points; issue 15).
BOUND_PP = 2.0


def medians(results) -> dict:
    """(label, joint) -> median [k0, k1] error (%) of one frequency's pooled results."""
    return {(label, j): np.median(100 * r.error_array(j), axis=0) for label, r in results.items() for j in JOINTS}


def stance_cost(pad: float, repeats: int = 5) -> None:
    """CPU time (this thread) of one short-window analysis, straight line vs template, on the bundled 2.2 Hz recording."""
    from hop_impedance.biomech.stance_detection import Stance
    from hop_impedance.io.recording_io import load_recording

    rec = load_recording(Path(__file__).resolve().parents[1] / "recordings" / "sim_2p20hz_hard.mcap")
    batch = analysis.analyze_recording(rec)
    data, options = analysis.recording_span(rec), analysis.AnalysisOptions(post_takeoff_s=pad)
    stances = [Stance(s.touchdown_s, s.takeoff_s, s.complete) for s in batch.stances]
    for template in (False, True):
        analysis.MARKER_TEMPLATE, cpu = template, []
        for _ in range(repeats):
            for k in range(1, len(stances)):
                c0 = time.thread_time()
                analysis.analyze_short_window(data, stances, k, batch.model, rec.subject.body_mass_kg, options)
                cpu.append(time.thread_time() - c0)
        print(f"PAD {pad * 1e3:g} ms, {'template' if template else 'straight line'}: analysis of one stance "
              f"(filters, kinematics, inverse dynamics) CPU p50 {np.median(cpu) * 1e3:.2f} ms, "
              f"p99 {np.percentile(cpu, 99) * 1e3:.2f} ms over {len(cpu)}")
    analysis.MARKER_TEMPLATE = True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pads", type=float, nargs="*", metavar="PAD", help="window end after take-off (s)")
    parser.add_argument("--frequencies", type=float, nargs="+", default=[1.53, 1.87, 2.20])
    parser.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13, 14])
    parser.add_argument("--hops", type=int, default=4)
    parser.add_argument("--clean-cutoff", type=float, default=40.0)
    parser.add_argument("--noisy-cutoff", type=float, default=12.0)
    parser.add_argument("--marker-fit", type=int, nargs=2, metavar=("DEGREE", "FRAMES"),
                        help="marker extrapolation polynomial (default: analysis' constants)")
    parser.add_argument("--true-markers-s", type=float, default=0.0, metavar="H",
                        help="give each short window the recorded markers up to H s past its end")
    parser.add_argument("--template", type=int, metavar="FRAMES",
                        help="anchor the previous hop's post-take-off motion to the last FRAMES frames (0: straight line only)")
    parser.add_argument("--exclude-takeoff", type=float, default=0.0, metavar="E",
                        help="short windows only: leave the last E s before take-off out of the fit's objective")
    parser.add_argument("--hip-exclusion", type=float, metavar="E",
                        help="short windows: the hip's time before take-off left out of the fit "
                             "(recording_fits.SHORT_WINDOW_HIP_EXCLUSION_S, default 0.02 s)")
    parser.add_argument("--noise-repeat", action="store_true",
                        help="also the batch analysis of the same trials with another sensor-noise draw: the cells' "
                             "repeatability, against which a 2 pp move of a noisy cell is read")
    parser.add_argument("--stance-cost", action="store_true",
                        help="only time one stance's short-window analysis (straight line vs template) and stop")
    args = parser.parse_args()
    if args.stance_cost:
        stance_cost(args.pads[0])
        return
    if args.hip_exclusion is not None:
        import hop_impedance.impedance.recording_fits as recording_fits

        recording_fits.SHORT_WINDOW_HIP_EXCLUSION_S = args.hip_exclusion  # takeoff_exclusion_s reads it at call time
    if args.template is not None:
        analysis.MARKER_TEMPLATE, analysis.MARKER_TEMPLATE_FRAMES = args.template > 0, max(args.template, 1)
    if args.marker_fit:
        analysis.MARKER_FIT_DEGREE, analysis.MARKER_FIT_FRAMES = args.marker_fit
    if args.true_markers_s > 0:
        known_span = analysis.window_span

        def window_span(data, start_s, end_s):
            span, later = known_span(data, start_s, end_s), known_span(data, start_s, end_s + args.true_markers_s)
            span.marker_t_s, span.markers_xz = later.marker_t_s, later.markers_xz
            return span

        analysis.window_span = window_span  # analyze_short_window looks it up at call time
    template = (f"previous hop's template anchored to {analysis.MARKER_TEMPLATE_FRAMES} frames, else "
                if analysis.MARKER_TEMPLATE else "")
    print(f"marker extrapolation: {template}degree {analysis.MARKER_FIT_DEGREE}, {analysis.MARKER_FIT_FRAMES} frames"
          + (f"; recorded markers up to {args.true_markers_s * 1e3:g} ms past each window's end" if args.true_markers_s else ""))
    cpu0 = time.process_time()
    cutoffs = {"clean": args.clean_cutoff, "noisy": args.noisy_cutoff}
    batch_analyze = analysis.analyze_recording
    batch_fit_options = coefficient_recovery.law_fit_options
    cells: dict[float | None, dict] = {}
    with tempfile.TemporaryDirectory() as folder:
        for pad in [None] + args.pads + ([NOISE_REPEAT] if args.noise_repeat else []):
            draw = 2 if pad == NOISE_REPEAT else 1
            pad = None if pad == NOISE_REPEAT else pad
            # recover_trial imports analyze_recording from the module at call time: it gets this one
            analysis.analyze_recording = (batch_analyze if pad is None else
                                          lambda rec, options=None, pad=pad: batch_analyze(
                                              rec, replace(options or analysis.AnalysisOptions(), post_takeoff_s=pad)))
            coefficient_recovery.law_fit_options = (batch_fit_options if pad is None or not args.exclude_takeoff else
                                                    lambda o, e: replace(batch_fit_options(o, e),
                                                                         exclude_takeoff_s=args.exclude_takeoff))
            print(("batch analysis (whole record)" + (", sensor noise draw 2" if draw == 2 else "")) if pad is None else
                  f"short windows: post_takeoff_s = {pad * 1e3:g} ms after take-off", flush=True)
            key = NOISE_REPEAT if draw == 2 else pad
            cells[key] = {}
            for freq in args.frequencies:
                results = recover_pooled(freq, args.seeds, Path(folder), cutoff_hz=cutoffs, n_hops=args.hops,
                                         noise_stream=draw)
                print_table(freq, results)
                cells[key].update({(freq,) + key: value for key, value in medians(results).items()})
    analysis.analyze_recording = batch_analyze
    batch = cells.pop(None)
    print(f"\ncells moved by more than {BOUND_PP:g} pp against batch (median errors, %):")
    for pad, table in cells.items():
        moved, largest, worse = [], {"clean": 0.0, "noisy": 0.0}, 0
        for key, value in table.items():
            for name, b, s in zip(("k0", "k1"), batch[key], value):
                largest[key[1]] = max(largest[key[1]], abs(s - b))
                worse += abs(s) - abs(b) > BOUND_PP
                if abs(s - b) > BOUND_PP:
                    moved.append(f"  {key[0]:4.2f} Hz {key[1]:5s} {key[2]:5s} {name}: {b:+6.1f} -> {s:+6.1f} ({s - b:+.1f} pp)")
        name = "batch, noise draw 2" if pad == NOISE_REPEAT else f"PAD {pad * 1e3:g} ms"
        print(f"{name}: {len(moved)} of {2 * len(table)} cells moved; "
              f"largest move clean {largest['clean']:.1f} pp, noisy {largest['noisy']:.1f} pp; "
              f"{worse} cells' |error| grew by more than {BOUND_PP:g} pp")
        print("\n".join(moved))
    print(f"CPU {time.process_time() - cpu0:.1f} s")


if __name__ == "__main__":
    main()
