"""hop-impedance batch: 40 simulated recordings, serial vs the embedded Dask LocalCluster.

Generates 40 recordings once (10 subjects of different mass and height x 4 hop
frequencies, 10 hops each, realistic noise; ``hop-impedance simulate``) into a
cache folder with a manifest (subject, condition), then runs the same batch
twice with ``--force`` semantics:

1. serial (this process, one BLAS thread, exactly what a worker runs), and
2. on ``distributed.LocalCluster`` (one worker process per core, one thread
   each, 127.0.0.1), the cluster started before the clock starts;

and prints recordings per second, the speed-up, the load average (1 min)
before and after each phase, whether the two output folders are byte-equal,
the scheduler's overhead per task (a) from 400 no-op tasks and (b) in the
batch itself (workers x wall - time inside the tasks, per task), and what is
sent per task and what comes back (pickled bytes).

    .venv/bin/python bench/bench_batch.py                  # about 1-2 min after the first run
    .venv/bin/python bench/bench_batch.py --workers 2 --cache /tmp/hop_bench_batch

The first run simulates the 40 recordings (about 8 s each on one core, run
on all cores); later runs reuse them.
"""

from __future__ import annotations

import argparse
import io
import os
import pickle
import statistics
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

# id, mass kg, height m: 50-68 kg (the simulator's 1.53 Hz hops fail to take off above ~70 kg)
SUBJECTS = [(f"P{k:02d}", 50.0 + 3.0 * (k % 7), 1.55 + 0.025 * k) for k in range(10)]
FREQUENCIES_HZ = (1.53, 1.87, 2.03, 2.20)
HOPS = 10


def _simulate(argv: list[str]) -> int:
    from hop_impedance.cli.main import main

    return main(argv)


def generate(cache: Path) -> Path:
    """The 40 recordings and their manifest in ``cache`` (made once); returns the manifest."""
    manifest = cache / "manifest.csv"
    jobs, lines = [], ["recording,subject,condition"]
    for s, (sid, mass, height) in enumerate(SUBJECTS):
        for f, freq in enumerate(FREQUENCIES_HZ):
            name = f"{sid}_{freq:.2f}hz.mcap"
            lines.append(f"{name},{sid},{freq:.2f} Hz")
            if not (cache / name).exists():
                jobs.append(["simulate", "--freq", str(freq), "--hops", str(HOPS), "--seed", str(100 + 10 * s + f),
                             "--mass-kg", str(mass), "--height-m", str(height), "--out", str(cache / name)])
    if jobs:
        cache.mkdir(parents=True, exist_ok=True)
        print(f"simulating {len(jobs)} recordings into {cache} ...", file=sys.stderr)
        t0 = time.perf_counter()
        with ProcessPoolExecutor(max_workers=os.cpu_count()) as pool:
            codes = list(pool.map(_simulate, jobs))
        if any(codes):
            raise SystemExit(f"simulate failed for {sum(1 for c in codes if c)} recordings")
        print(f"  done in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    manifest.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return manifest


def _noop(i: int) -> int:
    return i


def _tree(out: Path) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and ".batch" not in p.parts}


def _load() -> str:
    return f"{os.getloadavg()[0]:.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count(), help="local cluster workers (default: cores)")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "hop_impedance_bench_batch"),
                        help="folder of the simulated recordings (made once)")
    args = parser.parse_args()

    from distributed import Client

    from hop_impedance.batch.inputs import collect_items
    from hop_impedance.batch.runner import local_cluster, run_batch
    from hop_impedance.batch.task import BatchOptions, analyze_item

    items = collect_items([str(generate(Path(args.cache)))])
    options = BatchOptions()
    n = len(items)
    print(f"{n} recordings ({len(SUBJECTS)} subjects x {len(FREQUENCIES_HZ)} frequencies, {HOPS} hops each), "
          f"{os.cpu_count()} cores, load average (1 min) at start {_load()}")

    with tempfile.TemporaryDirectory() as tmp:
        out_serial, out_cluster = Path(tmp) / "serial", Path(tmp) / "cluster"
        load0 = _load()
        t0 = time.perf_counter()
        serial = run_batch(items, out_serial, options, mode="serial", force=True, progress_stream=io.StringIO())
        wall_serial = time.perf_counter() - t0
        print(f"serial:  {serial.seconds:6.1f} s analysis ({n / serial.seconds:.2f} recordings/s), "
              f"{wall_serial:.1f} s with tables and figures; load {load0} -> {_load()}")

        t_start = time.perf_counter()
        with local_cluster(args.workers) as cluster, Client(cluster) as client:
            start_s = time.perf_counter() - t_start
            client.submit(_noop, -1, pure=False).result()  # workers warm
            load0 = _load()
            t0 = time.perf_counter()
            dist = run_batch(items, out_cluster, options, client=client, force=True, progress_stream=io.StringIO())
            wall_cluster = time.perf_counter() - t0
            load1 = _load()
            t0 = time.perf_counter()
            futures = [client.submit(_noop, i, pure=False) for i in range(400)]
            client.gather(futures)
            noop_ms = 1000 * (time.perf_counter() - t0) / len(futures)
        print(f"cluster: {dist.seconds:6.1f} s analysis ({n / dist.seconds:.2f} recordings/s) on {dist.workers} "
              f"workers, {wall_cluster:.1f} s with tables and figures, cluster start {start_s:.1f} s; "
              f"load {load0} -> {load1}")
        print(f"speed-up (analysis): {serial.seconds / dist.seconds:.2f}x; end to end incl. cluster start: "
              f"{wall_serial / (wall_cluster + start_s):.2f}x")
        a, b = _tree(out_serial), _tree(out_cluster)
        equal = sorted(a) == sorted(b) and all(a[k] == b[k] for k in a)
        print(f"outputs byte-equal (serial vs cluster, {len(a)} files): {'yes' if equal else 'NO'}")

        task_s = [o.seconds for o in dist.outcomes.values()]
        overhead_ms = 1000 * (dist.workers * dist.seconds - sum(task_s)) / n
        print(f"scheduler overhead per task: {noop_ms:.2f} ms (400 no-op tasks, {args.workers} workers); "
              f"in the batch {overhead_ms:.0f} ms per task = (workers x wall - time inside tasks) / tasks, "
              f"task time median {1000 * statistics.median(task_s):.0f} ms")

        sent = pickle.dumps((items[0], options), protocol=pickle.HIGHEST_PROTOCOL)
        back = [analyze_item(items[i], options) for i in (0, n - 1)]
        sizes = [len(pickle.dumps(o, protocol=pickle.HIGHEST_PROTOCOL)) for o in back]
        o = back[0]
        print(f"sent per task: {len(sent)} B (BatchItem: path and labels, BatchOptions; the worker reads the MCAP, "
              f"{os.path.getsize(items[0].path) / 1e6:.2f} MB, from the path)")
        print(f"back per task: {min(sizes) / 1e6:.2f}-{max(sizes) / 1e6:.2f} MB pickled (JSON text "
              f"{len(o.json_text) / 1e6:.2f} MB, fits {len(pickle.dumps(o.fits)) / 1e6:.2f} MB, "
              f"tidy rows {len(pickle.dumps(o.rows)) / 1e3:.0f} kB) for {HOPS} hops")
        print(f"load average (1 min) at the end {_load()}")


if __name__ == "__main__":
    main()
