"""What Rerun logging costs: offline view of a recording, and the live bridge's columnar flush.

Prints (no assertions):
- analysis + fits vs logging time of ``hop-impedance view`` for a bundled 10-hop trial;
- columnar (``send_columns``) vs row-by-row (``set_time`` + ``log``) for 1 s of 1 kHz GRF;
- the bridge's per-message cost: converting + logging one 0.1 s flush block
  (100 wrenches, 10 marker frames) relative to its 0.1 s period.
Sinks are .rrd files in a temporary folder.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from hop_impedance.io.recording_io import load_recording
from hop_impedance.viz.session import analyze_and_fit, log_session, new_recording_stream
from hop_impedance.viz.views import cop_x_from_wrench, log_body, log_ground_reaction, log_static_styles

TMP = tempfile.TemporaryDirectory()
REC = Path(__file__).resolve().parents[1] / "recordings" / "sim_2p20hz_hard.mcap"


def best_of(fn, repeat=5) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    rec = load_recording(REC)
    t = time.perf_counter()
    analysis, fits = analyze_and_fit(rec)
    t_analysis = time.perf_counter() - t

    def offline():
        stream = new_recording_stream()
        stream.save(Path(TMP.name) / "offline.rrd")
        log_session(stream, rec, analysis, fits)
        stream.flush()

    t_log = best_of(offline, 3)
    print(f"offline view of {REC.name} ({len(rec.force)} force, {len(rec.markers)} marker frames, "
          f"{len(analysis.stances)} stances):")
    print(f"  analysis + fits {t_analysis:.2f} s, Rerun logging {t_log:.3f} s ({100 * t_log / t_analysis:.1f} % of the analysis)")

    stream = new_recording_stream()
    stream.save(Path(TMP.name) / "blocks.rrd")
    log_static_styles(stream)
    bw = rec.subject.body_weight_n
    ts = (rec.force.stamp_ns[:1000] - rec.start_ns) * 1e-9
    f = rec.force.force_n[:1000]
    cop = cop_x_from_wrench(f, rec.force.torque_nm[:1000])
    t_col = best_of(lambda: log_ground_reaction(stream, ts, f[:, [0, 2]], cop, bw))

    import rerun as rr

    def rows():
        for k in range(len(ts)):
            stream.set_time("time", duration=ts[k])
            stream.log("signals/grf/vertical_bw", rr.Scalars(f[k, 2] / bw))

    t_row = best_of(rows, 2)
    print(f"1 s of 1 kHz GRF: columnar {1e3 * t_col:.2f} ms, row by row (scalar only) {1e3 * t_row:.1f} ms "
          f"({t_row / t_col:.0f}x)")

    from hop_impedance.biomech.kinematics import sagittal_markers

    xz = sagittal_markers(rec.markers)[:10]
    tm = (rec.markers.stamp_ns[:10] - rec.start_ns) * 1e-9

    def flush_block():
        log_ground_reaction(stream, ts[:100], f[:100, [0, 2]], cop[:100], bw)
        log_body(stream, tm, xz)

    t_flush = best_of(flush_block, 20)
    print(f"bridge flush of 0.1 s (100 wrenches + 10 marker frames): {1e3 * t_flush:.2f} ms = "
          f"{100 * t_flush / 0.1:.1f} % of one core")
    _message_conversion(rec)


def _message_conversion(rec) -> None:
    """Cost of turning 100 WrenchStamped messages into arrays (the bridge's only per-message work besides list.append)."""
    try:
        from geometry_msgs.msg import WrenchStamped

        from hop_impedance.nodes.rerun_bridge import wrench_block
    except ImportError as exc:
        print(f"message conversion: skipped ({exc})")
        return
    msgs = []
    for ns, f in zip(rec.force.stamp_ns[:100], rec.force.force_n[:100]):
        m = WrenchStamped()
        m.header.stamp.sec, m.header.stamp.nanosec = divmod(int(ns), 1_000_000_000)
        m.wrench.force.z = float(f[2])
        msgs.append(m)
    t = best_of(lambda: wrench_block(msgs), 20)
    print(f"bridge: 100 WrenchStamped -> arrays {1e3 * t:.2f} ms ({1e6 * t / 100:.1f} us per message)")


if __name__ == "__main__":
    main()
