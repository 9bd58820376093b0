"""Soak test of the node suite: looped replay at real time through ``--processes`` for N minutes.

Starts ``hop-impedance pipeline --processes --loop --rate 1`` on a bundled
recording (DDS on loopback), samples every node process's resident memory
(VmRSS) and CPU time (utime + stime) from /proc every ``--sample-s`` seconds,
stops the run with SIGINT after ``--minutes`` and prints, per node: RSS at
minute 2 and at the end, growth, mean CPU (% of one core) from minute 2 on, and
whether growth < 10 MB (issue 14). Also the stances the run printed and the
exit line. Figures go into docs/pipeline.md ("Soak").

Usage::

    nice -n 10 .venv/bin/python bench/bench_soak.py --minutes 10 [--csv soak.csv]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NODES = ("replay", "stance_detector", "inverse_dynamics", "impedance_estimator", "recorder")
PAGE = os.sysconf("SC_PAGE_SIZE")
TICK = os.sysconf("SC_CLK_TCK")


def children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def node_of(pid: int) -> str | None:
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return None
    for part in cmd:
        if part.startswith(b"hop_impedance.nodes."):
            return part.decode().rsplit(".", 1)[1]
    return None


def sample(pid: int) -> tuple[float, float] | None:
    """(RSS MB, CPU s) of a process, None if it is gone."""
    try:
        rss_kb = next(int(line.split()[1]) for line in Path(f"/proc/{pid}/status").read_text().splitlines()
                      if line.startswith("VmRSS:"))
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / TICK  # utime, stime (fields 14, 15 of stat)
    except (OSError, StopIteration, IndexError, ValueError):
        return None
    return rss_kb / 1024.0, cpu


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--recording", default=str(ROOT / "recordings" / "sim_2p20hz_hard.mcap"))
    ap.add_argument("--out", default="/tmp/hop_soak")
    ap.add_argument("--sample-s", type=float, default=5.0)
    ap.add_argument("--baseline-min", type=float, default=2.0, help="growth is measured from this minute [2]")
    ap.add_argument("--csv", help="write every sample (t_s, node, rss_mb, cpu_s) here")
    args = ap.parse_args()
    # loopback only, and a domain of its own so other pipelines on this machine do not cross-talk
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    env.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    total_s = args.minutes * 60.0
    cmd = [sys.executable, "-m", "hop_impedance.cli", "pipeline", args.recording, "--out", args.out,
           "--processes", "--loop", "--rate", "1", "--timeout", str(total_s + 120), "--tolerate-loss"]
    print("running:", " ".join(cmd), flush=True)
    Path(args.out).mkdir(parents=True, exist_ok=True)
    out_file = open(Path(args.out) / "soak_stdout.txt", "w")  # noqa: SIM115
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=out_file, stderr=subprocess.STDOUT)
    samples: list[tuple[float, str, float, float]] = []
    t_start = None
    try:
        while proc.poll() is None:
            pids = {node_of(c): c for c in children(proc.pid)}
            if t_start is None and "replay" in pids:
                t_start = time.monotonic()
            if t_start is not None:
                t = time.monotonic() - t_start
                for name in NODES:
                    s = sample(pids[name]) if name in pids else None
                    if s is not None:
                        samples.append((t, name, *s))
                if t >= total_s:
                    break
            time.sleep(args.sample_s if t_start is not None else 0.2)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        out_file.close()
    if args.csv:
        with open(args.csv, "w") as fh:
            fh.write("t_s,node,rss_mb,cpu_s\n")
            fh.writelines(f"{t:.1f},{n},{r:.2f},{c:.2f}\n" for t, n, r, c in samples)
    text = (Path(args.out) / "soak_stdout.txt").read_text(errors="replace")
    rows = sum(1 for line in text.splitlines() if line[:3].strip().isdigit() and "|" in line)
    accepted = sum(1 for line in text.splitlines() if line.rstrip().endswith("| accepted"))
    base_t = args.baseline_min * 60.0
    print(f"soak: {args.minutes:g} min looped real-time replay of {Path(args.recording).name} through --processes, "
          f"exit {proc.returncode}, {rows} stance rows ({accepted} accepted)")
    print(f"{'node':<20} {'RSS@' + format(args.baseline_min, 'g') + 'min MB':>13} {'RSS@end MB':>11} {'growth MB':>10} "
          f"{'max MB':>8} {'CPU %':>6}  < 10 MB")
    ok = True
    for name in NODES:
        mine = [(t, r, c) for t, n, r, c in samples if n == name]
        after = [x for x in mine if x[0] >= base_t]
        if len(after) < 2:
            print(f"{name:<20} (not enough samples after minute {args.baseline_min:g})")
            ok = False
            continue
        (t0, r0, c0), (t1, r1, c1) = after[0], after[-1]
        growth = r1 - r0
        cpu = 100.0 * (c1 - c0) / (t1 - t0) if t1 > t0 else float("nan")
        good = growth < 10.0
        ok &= good
        print(f"{name:<20} {r0:>13.1f} {r1:>11.1f} {growth:>10.2f} {max(r for _, r, _ in mine):>8.1f} {cpu:>6.1f}  "
              f"{'yes' if good else 'NO'}")
    last = [line for line in text.splitlines() if line.startswith("hop-impedance pipeline:")]
    for line in last[-3:]:
        print(line)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
