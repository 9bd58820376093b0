"""Pipeline benchmark: take-off-to-profile latency, CPU use and the highest loss-free replay rate.

Runs the node graph in one process (EventsExecutor) on a bundled recording:

1. real time (rate 1, 1 kHz force + 100 Hz markers), batch mode, low-latency mode and low-latency
   "tight" (post_pad 10 ms, reorder window 2 ms, 1 ms processing period):
   latency from the arrival of the first force sample at/after take-off at
   inverse_dynamics to the computed profile (p50, p99, from the estimator's
   ``latency_s``), and the process CPU time per second of recording;
2. fixed replay rates without flow control (2x, 5x, 10x, 20x, 40x): messages lost
   (file count minus received); the highest rate with zero loss is printed;
   with flow control (rate 0) nothing is lost by construction, its speed-up is printed too;
3. fixed rates 5x, 10x, 20x with one process per node (``--processes``, both cores).

Usage: .venv/bin/python bench/bench_pipeline.py [REC.mcap]
"""

import os
import resource
import sys
import tempfile
import time

import numpy as np

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

from hop_impedance.io.mcap_io import summarize  # noqa: E402
from hop_impedance.nodes.runner import PipelineConfig, run_pipeline  # noqa: E402


def cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run(rec: str, **kw):
    with tempfile.TemporaryDirectory() as out:
        c0, t0 = cpu_s(), time.monotonic()
        report = run_pipeline(PipelineConfig(rec, out, timeout_s=120, **kw))
        return report, cpu_s() - c0, time.monotonic() - t0


TIGHT = {"inverse_dynamics": {"post_pad_s": 0.01, "reorder_window_s": 0.002, "process_period_s": 0.001}}


def latency_line(name: str, report, cpu: float, wall: float) -> str:
    """Take-off -> profile p50/p99 (all stances and without the first, which waits for the body model),
    per-stance analysis and fit time (node diagnostics), CPU."""
    lat = np.array([p.latency_s for p in sorted(report.profiles, key=lambda p: p.stance_index) if p.joint == "ankle"]) * 1e3
    steady = lat[1:] if lat.size > 1 else lat
    d = report.diag
    return (f"{name:<34}: take-off->profile p50 {np.percentile(lat, 50):.0f} ms, p99 {np.percentile(lat, 99):.0f} ms "
            f"(n={lat.size}; without the first stance p50 {np.percentile(steady, 50):.0f}, p99 {np.percentile(steady, 99):.0f} ms); "
            f"analysis p50/p99 {d('/inverse_dynamics', 'analysis_p50_ms', '?')}/{d('/inverse_dynamics', 'analysis_p99_ms', '?')} ms, "
            f"fit p50/p99 {d('/impedance_estimator', 'fit_p50_ms', '?')}/{d('/impedance_estimator', 'fit_p99_ms', '?')} ms; "
            f"CPU {100 * cpu / wall:.0f} % of one core over {wall:.1f} s")


def main() -> None:
    rec = sys.argv[1] if len(sys.argv) > 1 else "recordings/sim_2p20hz_hard.mcap"
    infos = {i.topic: i for i in summarize(rec)}
    span = (infos["/force_plate/wrench"].last_ns - infos["/force_plate/wrench"].first_ns) * 1e-9
    counts = {t: i.count for t, i in infos.items()}
    print(f"recording {rec}: {span:.2f} s, {counts['/force_plate/wrench']} wrenches, {counts['/mocap/markers']} marker frames; "
          f"load average before: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    modes = (("real time, batch", {}), ("real time, low-latency (pad 50 ms)", {"low_latency": True}),
             ("real time, low-latency tight", {"low_latency": True, "overrides": TIGHT}))
    for name, kw in modes:
        report, cpu, wall = run(rec, rate=1.0, **kw)
        print(latency_line(name, report, cpu, wall))
    report, cpu, wall = run(rec, rate=0.0, publish_frames=True)
    print(f"rate 0 (flow control): {span / wall:.1f}x real time incl. start-up ({wall:.1f} s wall), "
          f"{span / report.replay_play_s:.1f}x from first message to end of stream, CPU {100 * cpu / wall:.0f} %, "
          f"lost {counts['/force_plate/wrench'] - report.received('/inverse_dynamics', '/force_plate/wrench')} wrenches")
    best = 0.0
    for rate in (2.0, 5.0, 10.0, 20.0, 40.0):
        report, cpu, wall = run(rec, rate=rate)
        lost = sum(counts[t] - report.received("/inverse_dynamics", t) for t in ("/force_plate/wrench", "/mocap/markers"))
        print(f"rate {rate:>4.0f}x: {lost} messages lost, {len(report.summaries)} stance summaries, finished={report.finished}, "
              f"CPU {100 * cpu / wall:.0f} %")
        if lost == 0 and report.finished:
            best = rate
    print(f"highest fixed replay rate with zero loss, one process: {best:.0f}x")
    best = 0.0
    for rate in (5.0, 10.0, 20.0):
        report, _, wall = run(rec, rate=rate, processes=True)
        lost = sum(counts[t] - report.received("/inverse_dynamics", t) for t in ("/force_plate/wrench", "/mocap/markers"))
        print(f"separate processes, rate {rate:>4.0f}x: {lost} messages lost, {len(report.summaries)} stance summaries, "
              f"finished={report.finished}")
        if lost == 0 and report.finished:
            best = rate
    print(f"highest fixed replay rate with zero loss, separate processes: {best:.0f}x; "
          f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
