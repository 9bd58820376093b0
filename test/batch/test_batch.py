"""hop-impedance batch on a real distributed.LocalCluster (2 worker processes, 127.0.0.1).

The bundled recordings plus two broken ones (an empty file, random bytes)
go through the serial path and the cluster; every output file must be equal
byte for byte, a worker killed mid-task must lose nothing, the broken files
must land in failures.csv while the rest complete, and a re-run must skip
what is up to date. The population statistics are checked against pyarrow +
scipy on the tidy table (each subject's mean, paired by subject).
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from hop_impedance.batch.inputs import collect_items  # noqa: E402
from hop_impedance.batch.runner import local_cluster, run_batch  # noqa: E402

REC_DIR = Path(__file__).resolve().parents[2] / "recordings"
BROKEN = ("empty", "noise")


def _tree(out: Path) -> dict[str, bytes]:
    """Every output file except the skip markers (they hold timings and pids)."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and ".batch" not in p.parts}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("batch_in")
    for p in sorted(REC_DIR.glob("*.mcap")):
        shutil.copy(p, d / p.name)
    (d / "empty.mcap").write_bytes(b"")
    (d / "noise.mcap").write_bytes(np.random.default_rng(7).bytes(50_000))
    return d


@pytest.fixture(scope="module")
def client():
    with local_cluster(2) as cluster, distributed.Client(cluster) as c:
        assert all(w.startswith("tcp://127.0.0.1:") for w in c.scheduler_info(n_workers=-1)["workers"])
        yield c


@pytest.fixture(scope="module")
def serial(inputs, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    summary = run_batch(collect_items([str(inputs)]), out, mode="serial", progress_stream=io.StringIO())
    return out, summary


def test_serial_json_is_the_analyze_json(serial, inputs, tmp_path):
    from hop_impedance.cli.main import main

    out, _ = serial
    rec = inputs / "sim_2p20hz_soft.mcap"
    assert main(["analyze", str(rec), "--json", str(tmp_path / "a.json")]) == 0
    assert (tmp_path / "a.json").read_bytes() == (out / "json" / "sim_2p20hz_soft.json").read_bytes()


def test_broken_recordings_in_failures_csv_others_complete(serial):
    out, summary = serial
    with open(out / "failures.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert sorted(r["recording"] for r in rows) == sorted(BROKEN)
    assert all(r["reason"] for r in rows)
    assert summary.analysed == 5 and summary.failed == 2
    assert sorted(p.stem for p in (out / "json").glob("*.json")) == sorted(p.stem for p in REC_DIR.glob("*.mcap"))
    # 5 recordings x 10 hops x 3 joints, all fitted
    import pyarrow.parquet as pq

    tidy = pq.read_table(out / "tidy.parquet").to_pylist()
    assert len(tidy) == 150 and summary.stances == 50 and summary.fits == 150
    assert {r["status"] for r in tidy} == {"solved"}


def test_cluster_outputs_equal_serial_exactly(serial, inputs, client, tmp_path):
    out, _ = serial
    summary = run_batch(collect_items([str(inputs)]), tmp_path, client=client, progress_stream=io.StringIO())
    assert summary.workers == 2 and summary.analysed == 5 and summary.failed == 2
    assert len({o.pid for o in summary.outcomes.values()} - {os.getpid()}) == 2  # both workers, not this process
    a, b = _tree(out), _tree(tmp_path)
    assert sorted(a) == sorted(b)
    assert [k for k in a if a[k] != b[k]] == []


def test_worker_killed_mid_run_loses_nothing(serial, inputs, client, tmp_path):
    out, _ = serial
    killed = {}

    def kill_a_busy_worker():
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            busy = {w: ks for w, ks in client.processing().items() if ks}
            if busy:
                worker, keys = next(iter(busy.items()))
                pid = client.run(os.getpid, workers=[worker])[worker]
                killed.update(pid=pid, keys=list(keys))  # running or queued on that worker
                os.kill(pid, signal.SIGKILL)
                return
            time.sleep(0.01)

    killer = threading.Thread(target=kill_a_busy_worker)
    killer.start()
    summary = run_batch(collect_items([str(inputs)]), tmp_path, client=client, progress_stream=io.StringIO())
    killer.join()
    assert killed, "no task was seen running"
    # the scheduler sent the killed worker's unfinished task(s) out a second time ...
    # (a task it held may have finished just before the kill: that result was delivered, and is not redone)
    story = client.run_on_scheduler(lambda dask_scheduler, keys=killed["keys"]: dask_scheduler.story(*keys))
    redone = [k for k in killed["keys"] if sum(1 for e in story if e[0] == k and e[2] == "processing") >= 2]
    assert redone, f"no task of the killed worker was sent out again: {killed['keys']}"
    # ... and nothing was lost: same outputs as serial, the redone ones computed by another worker
    assert summary.analysed == 5 and summary.failed == 2
    for key in redone:  # an analysed recording's result came from a live worker (a broken one's is in failures.csv)
        outcome = [o for name, o in summary.outcomes.items() if key.startswith(f"hop-impedance-batch-{name}-")]
        assert len(outcome) <= 1 and all(o.pid != killed["pid"] and o.error is None for o in outcome)
    a, b = _tree(out), _tree(tmp_path)
    assert [k for k in a if a.get(k) != b.get(k)] == [] and sorted(a) == sorted(b)
    client.wait_for_workers(2, timeout=60)  # the nanny restarted it


def test_rerun_skips_up_to_date_and_redoes_changed(inputs, tmp_path):
    names = [str(inputs / n) for n in ("sim_2p20hz_hard.mcap", "sim_1p87hz_hard.mcap", "noise.mcap")]
    items = collect_items(names)
    first = run_batch(items, tmp_path, mode="serial", progress_stream=io.StringIO())
    before = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "json").glob("*.json")}
    tree = _tree(tmp_path)
    again = run_batch(items, tmp_path, mode="serial", progress_stream=io.StringIO())
    assert (first.analysed, first.skipped, first.failed) == (2, 0, 1)
    assert (again.analysed, again.skipped, again.failed) == (0, 2, 1)  # a failure is always retried
    assert {p.name: p.stat().st_mtime_ns for p in (tmp_path / "json").glob("*.json")} == before
    assert _tree(tmp_path) == tree  # tables and figures rebuilt from the stored results, identical
    # one input's content changes: only that one is redone
    changed = inputs / "copy_changes.mcap"
    shutil.copy(REC_DIR / "sim_1p87hz_hard.mcap", changed)
    items = collect_items(names + [str(changed)])
    run_batch(items, tmp_path, mode="serial", progress_stream=io.StringIO())
    shutil.copy(REC_DIR / "sim_2p20hz_hard.mcap", changed)
    try:
        third = run_batch(items, tmp_path, mode="serial", progress_stream=io.StringIO())
    finally:
        changed.unlink()
    assert (third.analysed, third.skipped) == (1, 2)
    original = (tmp_path / "json" / "sim_2p20hz_hard.json").read_bytes()
    assert (tmp_path / "json" / "copy_changes.json").read_bytes() == original.replace(
        b"sim_2p20hz_hard.mcap", b"copy_changes.mcap")
    # another option: everything is redone
    from hop_impedance.batch.task import BatchOptions

    fourth = run_batch(collect_items(names), tmp_path, BatchOptions(cutoff_hz=10.0), mode="serial",
                       progress_stream=io.StringIO())
    assert (fourth.analysed, fourth.skipped) == (2, 0)


def test_manifest_labels_and_tests_paired_by_subject(tmp_path):
    """Three subjects, two conditions: Table 2 cells and Wilcoxon p from each subject's mean, checked
    against pyarrow + scipy on the tidy table."""
    import pyarrow.parquet as pq
    from scipy import stats

    plan = [("S1", "low", "sim_1p53hz_hard"), ("S1", "high", "sim_1p87hz_hard"),
            ("S2", "low", "sim_2p20hz_soft"), ("S2", "high", "sim_2p20hz_hard"),
            ("S3", "low", "sim_2p20hz_soft_unexpected_hard"), ("S3", "high", "sim_1p53hz_hard")]
    lines = ["recording,subject,condition,mass_kg,height_m,sex,session"]
    for k, (subject, condition, name) in enumerate(plan):
        dst = tmp_path / "in" / f"{subject}_{condition}.mcap"
        dst.parent.mkdir(exist_ok=True)
        shutil.copy(REC_DIR / f"{name}.mcap", dst)
        lines.append(f"in/{dst.name},{subject},{condition},{60 + k},,,s{k}")
    (tmp_path / "manifest.csv").write_text("\n".join(lines) + "\n")
    items = collect_items([str(tmp_path / "manifest.csv")])
    assert [i.mass_kg for i in items] == [60.0 + k for k in range(6)]
    out = tmp_path / "out"
    run_batch(items, out, mode="serial", progress_stream=io.StringIO())
    tidy = pq.read_table(out / "tidy.parquet").to_pylist()
    assert {(r["subject"], r["condition"], r["session"]) for r in tidy} == {
        (s, c, f"s{k}") for k, (s, c, _) in enumerate(plan)}
    usable = [r for r in tidy if r["status"] == "solved"]

    def subject_means(joint, condition, column):
        by = {}
        for r in usable:
            if r["joint"] == joint and r["condition"] == condition:
                by.setdefault(r["subject"], []).append(r[column])
        return [np.mean(by[s]) for s in sorted(by)]

    with open(out / "report" / "tests.csv", newline="") as fh:
        tests = {(r["conditions"], r["joint"], r["quantity"]): r for r in csv.DictReader(fh)}
    with open(out / "report" / "table2.csv", newline="") as fh:
        table2 = {(r["joint"], r["quantity"]): r for r in csv.DictReader(fh)}
    for joint in ("ankle", "knee", "hip"):
        hi, lo = subject_means(joint, "high", "overall_stiffness"), subject_means(joint, "low", "overall_stiffness")
        assert len(hi) == len(lo) == 3
        row = tests[("high vs low", joint, "overall_stiffness")]
        assert row["paired by"] == "subject" and row["pairs"] == "3"
        assert float(row["p"]) == pytest.approx(stats.wilcoxon(hi, lo).pvalue, rel=1e-3)
        cell = table2[(joint, "Overall (N m/rad)")]["high"]
        assert cell == f"{np.mean(hi):.1f} ({np.std(hi, ddof=1):.1f})"


def test_cli_on_an_existing_scheduler(serial, inputs, client, tmp_path, capsys):
    """``hop-impedance batch DIR --scheduler tcp://...``: the same outputs; exit 1 because two recordings failed."""
    from hop_impedance.cli.main import main

    out, _ = serial
    address = client.scheduler.address
    assert address.startswith("tcp://127.0.0.1:")
    assert main(["batch", str(inputs), "--out", str(tmp_path), "--scheduler", address]) == 1
    err = capsys.readouterr().err
    assert "7 recordings: 5 analysed, 0 up to date (skipped), 2 failed" in err and "on 2 worker(s)" in err
    a, b = _tree(out), _tree(tmp_path)
    assert sorted(a) == sorted(b) and [k for k in a if a[k] != b[k]] == []


def _blas_threads_in_a_task() -> list[int]:
    from threadpoolctl import threadpool_info

    from hop_impedance.batch.task import one_blas_thread

    with one_blas_thread():
        return sorted({lib["num_threads"] for lib in threadpool_info()})


def test_one_blas_thread_serial_and_on_workers(client):
    """The numerical thread setting every task runs with, here and on each worker process."""
    here = _blas_threads_in_a_task()
    there = client.run(_blas_threads_in_a_task)
    assert here == [1] and len(there) == 2 and all(v == [1] for v in there.values())


FOREIGN = Path(__file__).resolve().parents[3] / "shared" / "foreign"


@pytest.mark.skipif(not FOREIGN.is_dir(), reason="../shared/foreign not present")
def test_foreign_recordings_tidy_table_matches_their_json(tmp_path):
    """Recordings from the outside generator: every tidy row carries the numbers of its JSON fit object."""
    import json
    import math

    import pyarrow.parquet as pq

    names = ["none_1101", "angle_dependent_stiffness_1201", "force_plate_offset_1801"]
    summary = run_batch(collect_items([str(FOREIGN / f"{n}.mcap") for n in names]), tmp_path, mode="serial",
                        progress_stream=io.StringIO())
    assert (summary.analysed, summary.failed) == (3, 0)
    rows = {(r["recording"], r["stance"], r["joint"]): r for r in pq.read_table(tmp_path / "tidy.parquet").to_pylist()}
    checked = 0
    for n in names:
        doc = json.loads((tmp_path / "json" / f"{n}.json").read_text())
        for stance in doc["stances"]:
            for joint in ("ankle", "knee", "hip"):
                row = rows.pop((n, stance["index"], joint))
                fit = (stance["joints"] or {}).get(joint, {}).get("fit")
                if fit is None:
                    assert row["status"] is None
                    continue
                assert row["status"] == fit["status"] and row["terms"] == " ".join(fit["terms"])
                for key, prefix in (("coefficients", "coef_"), ("std_errors", "se_"), ("p_values", "p_")):
                    for term, value in fit[key].items():
                        assert row[prefix + term] == value or (value is None and math.isnan(row[prefix + term]))
                for key in ("rmse", "r_squared", "sse_variable", "sse_constant", "overall_stiffness", "average_stiffness"):
                    assert row[key] == fit[key] or (fit[key] is None and math.isnan(row[key]))
                checked += 1
    assert rows == {} and checked >= 3 * 20
