"""Streaming stage: a stance that lost most of its force messages is rejected naming the loss.

Seen in an overloaded pipeline run (test/ros/test_pipeline_loss.py at 500x):
195 of ~200 force samples of a stance were lost, the window's own median
step was then a gap, no hole was seen, and the stance was rejected as "too
few force samples in stance: 4 < 10", a reason that hides the cause. The
stage now measures holes against the stream's nominal period (its first 50
steps, stages.NominalPeriod).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from biomech_synth import push_in_chunks

from hop_impedance.biomech.analysis import SpanData, analyze_recording, recording_span
from hop_impedance.biomech.stages import NominalPeriod, StanceAnalysisStage
from hop_impedance.io.recording_io import load_recording

RECORDING = Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap"


def test_nominal_period_comes_from_the_start_of_the_stream():
    period = NominalPeriod()
    period.update(np.arange(0.0, 0.020, 0.001))  # 19 steps of 1 ms: not yet enough
    assert period.value is None
    period.update(np.arange(0.020, 0.060, 0.001))
    assert period.value == pytest.approx(0.001)
    period.update(np.arange(0.060, 1.0, 0.050))  # later heavy loss does not move it
    assert period.value == pytest.approx(0.001)


@pytest.mark.skipif(not RECORDING.exists(), reason="bundled recording missing")
def test_stance_with_most_force_samples_lost_is_rejected_for_message_loss():
    rec = load_recording(RECORDING)
    batch = analyze_recording(rec)
    target = batch.stances[3]
    data = recording_span(rec)
    t = data.force_t_s
    # Lose 49 of every 50 force samples from the previous take-off to the next touchdown (the stance's
    # whole analysis window), so the window's own median step is a 50 ms gap, as under overload.
    before, after = batch.stances[2], batch.stances[4]
    region = np.flatnonzero((t >= before.takeoff_s - 0.1) & (t <= after.touchdown_s + 0.1))
    lost = region[np.arange(region.size) % 50 != 0]
    keep = np.setdiff1d(np.arange(t.size), lost)
    sparse = SpanData(t[keep], data.wrench[keep], data.marker_t_s, data.markers_xz)
    stage = StanceAnalysisStage(batch.model, rec.subject.body_mass_kg, batch.options)
    edges = np.arange(t[0], t[-1] + 0.02, 0.02)
    live = [s for _, emitted in push_in_chunks(stage, sparse, edges) for s in emitted] + stage.flush()
    hit = [s for s in live if s.touchdown_s < target.takeoff_s and s.takeoff_s > target.touchdown_s]
    assert len(hit) == 1
    reason = hit[0].rejection_reason
    # The loss is named, and first: here the stance edges fall between surviving samples.
    assert reason is not None and reason.startswith("force samples") and "(message loss)" in reason.split(";")[0], reason
    assert hit[0].joints is None
    t0, t1 = t[region[0]], t[region[-1]]
    for s in live:
        if s.touchdown_s < t1 and s.takeoff_s > t0:  # the neighbours' edges are in the lossy span too
            assert "message loss" in s.rejection_reason.split(";")[0], (s.index, s.rejection_reason)
        else:
            assert s.rejection_reason is None or "incomplete" in s.rejection_reason, (s.index, s.rejection_reason)
