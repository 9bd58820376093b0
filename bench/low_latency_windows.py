"""What analysing each stance on a short window after take-off costs in accuracy (issue 15, "low latency by default").

The low-latency plan: declare a take-off provisionally after a few samples below the level
(<= 5 ms at 1 kHz), analyse and fit the stance at once on a window ending ``PAD`` s after the
take-off, and analyse offline on the same windows so live and offline agree. This runs
``bench/recovery_errors.py`` (same arguments, same simulated trials and table) with every
stance analysed by the live stage in low-latency mode
(:class:`hop_impedance.biomech.stages.StanceAnalysisStage` with ``post_pad_s=PAD``: the window ends
``PAD`` after take-off, the following flight's plate offset comes from what the window holds) instead
of the batch windows of :func:`hop_impedance.biomech.analysis.analyze_recording`. Compare its table
with ``recovery_errors.py``'s: the plan requires every cell within 2 percentage points.

    nice -n 10 .venv/bin/python bench/low_latency_windows.py 0.005
    nice -n 10 .venv/bin/python bench/low_latency_windows.py 0.05 --frequencies 2.2

The stage is fed the whole recording in one chunk: its windows depend on the event times only
(on sim_2p20hz_hard one chunk and 20 ms chunks gave identical joint moments at PAD = 5 ms), and
the stances must be the batch ones (checked).
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import hop_impedance.biomech.analysis as analysis
from hop_impedance.biomech.stages import StanceAnalysisStage

batch_analyze = analysis.analyze_recording


def analyze_on_low_latency_windows(rec, options=None, *, post_pad_s: float):
    """``analyze_recording`` with each stance's result from the low-latency stage (``post_pad_s`` after take-off)."""
    options = options or analysis.AnalysisOptions()
    result = batch_analyze(rec, options)  # model, subject, warnings and the batch stances to check against
    data = analysis.recording_span(rec)
    stage = StanceAnalysisStage(result.model, rec.subject.body_mass_kg, options, post_pad_s=post_pad_s)
    markers = (data.marker_t_s, data.markers_xz) if data.marker_t_s is not None else None
    stances = stage.push((data.force_t_s, data.wrench), markers) + stage.flush()
    if [s.touchdown_s for s in stances] != [s.touchdown_s for s in result.stances]:
        raise RuntimeError("the low-latency stage found other stances than the batch analysis")
    result.stances[:] = stances
    return result


def main() -> None:
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    pad = float(sys.argv.pop(1))
    print(f"every stance analysed on the low-latency window: post_pad_s = {pad * 1e3:g} ms after take-off", flush=True)
    # recovery_errors imports analyze_recording from this module at call time: it gets the low-latency one
    analysis.analyze_recording = lambda rec, options=None: analyze_on_low_latency_windows(rec, options, post_pad_s=pad)
    sys.argv = [str(Path(__file__).with_name("recovery_errors.py"))] + sys.argv[1:]
    runpy.run_path(sys.argv[0], run_name="__main__")


if __name__ == "__main__":
    main()
