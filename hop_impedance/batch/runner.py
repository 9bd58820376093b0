"""The ``hop-impedance batch`` job: skip rule, execution (serial or Dask distributed), progress, outputs.

Output folder::

    json/<name>.json      the analyze JSON of each recording (bit-identical to ``analyze``)
    tidy.parquet, tidy.csv one row per stance x joint, with recording, subject, condition
    report/               table1/2/3.csv, tests.csv, counts.csv, report.md, PNG figures
    failures.csv          recording, path, reason: one line per recording not analysed
    .batch/<name>.pkl     what the task sent back, with its skip key (the "done" marker)

Skip rule: a recording is skipped when ``.batch/<name>.pkl`` holds the same
key (:func:`~hop_impedance.batch.task.cache_key`: SHA-256 of the recording's
bytes, the options, the subject overrides, the package version and the batch
format) and ``json/<name>.json`` still has the SHA-256 recorded with it. The
marker is written after the JSON, so an interrupted run redoes what it had not
finished. Failed recordings are never skipped. Tables, figures and the tidy
table are rebuilt from all recordings on every run (cheap; labels may change).

Execution: ``mode="serial"`` runs :func:`analyze_item` in this process;
otherwise one Dask task per recording on an embedded ``distributed.LocalCluster``
(``mode="local"``: processes, one thread each, everything bound to 127.0.0.1) or
on the scheduler at ``mode="tcp://HOST:PORT"``. A worker that dies mid-task
makes the scheduler run the task again elsewhere (up to
``distributed.scheduler.allowed-failures`` times, default 3); a recording that
keeps killing workers becomes a failure line.
"""

from __future__ import annotations

import csv
import hashlib
import math
import os
import pickle
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from hop_impedance.batch.inputs import BatchItem
from hop_impedance.batch.task import BatchOptions, Outcome, analyze_item, cache_key, file_sha256

#: ``--group-by`` keys besides the manifest's extra columns.
GROUP_KEYS: tuple[str, ...] = ("condition", "frequency", "subject", "recording")


@dataclass
class BatchSummary:
    """What a run did.

    Attributes
    ----------
    total, analysed, skipped, failed : int
        Recordings named, analysed in this run, skipped as up to date, failed.
    stances, fits : int
        Stances and usable joint fits in the tables (all recordings, skipped included).
    seconds : float
        Wall time of the analysis phase (s).
    workers : int
        Worker processes (1 for serial).
    outcomes : dict
        name -> Outcome (without JSON text) of every recording analysed or skipped.
    failures : list of (name, path, reason)
    files : list of Path
        Every file written besides the per-recording JSON.
    """

    total: int = 0
    analysed: int = 0
    skipped: int = 0
    failed: int = 0
    stances: int = 0
    fits: int = 0
    seconds: float = 0.0
    workers: int = 1
    outcomes: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)
    files: list = field(default_factory=list)


class Progress:
    """One status line on ``stream``: done / failed / remaining and time left.

    On a terminal the line is redrawn in place; otherwise (a log file) a line
    is written at most every ``every_s`` seconds and at the end.
    """

    def __init__(self, todo: int, skipped: int, stream=None, every_s: float = 5.0):
        self.todo, self.skipped = todo, skipped
        self.done = self.failed = 0
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every_s = every_s
        self.t0 = time.perf_counter()
        self.last = -math.inf

    def line(self) -> str:
        n = self.done + self.failed
        elapsed = time.perf_counter() - self.t0
        left = self.todo - n
        eta = "-" if n == 0 else _clock(elapsed / n * left)
        width = 24
        fill = width if self.todo == 0 else round(width * n / self.todo)
        return (f"[{'#' * fill}{'.' * (width - fill)}] {self.done} done, {self.failed} failed, {left} remaining"
                f" ({self.skipped} up to date), {_clock(elapsed)} elapsed, ~{eta} left")

    def update(self, ok: bool) -> None:
        if ok:
            self.done += 1
        else:
            self.failed += 1
        self.show()

    def show(self, final: bool = False) -> None:
        now = time.perf_counter()
        if self.tty:
            self.stream.write("\r" + self.line() + ("\n" if final else ""))
        elif final or now - self.last >= self.every_s:
            self.stream.write(self.line() + "\n")
        else:
            return
        self.stream.flush()
        self.last = now


def _clock(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _up_to_date(marker: Path, json_path: Path, key: str) -> Outcome | None:
    """The stored outcome when ``marker`` holds ``key`` and the JSON is the one written with it."""
    if not marker.exists() or not json_path.exists():
        return None
    try:
        with open(marker, "rb") as fh:
            stored = pickle.load(fh)
    except Exception:  # noqa: BLE001  an unreadable marker (old format, cut short) means: redo
        return None
    if stored.get("key") != key:
        return None
    if hashlib.sha256(json_path.read_bytes()).hexdigest() != stored.get("json_sha256"):
        return None
    return stored["outcome"]


def _store(out: Path, outcome: Outcome, key: str) -> Outcome:
    """Write the JSON (as ``analyze --json`` does), then the marker; return the outcome without its JSON text."""
    from hop_impedance.cli.json_output import json_output

    json_path = out / "json" / f"{outcome.name}.json"
    with json_output(str(json_path)) as write:
        write(outcome.json_text)
    slim = replace(outcome, json_text="")
    marker = {"key": key, "json_sha256": hashlib.sha256(json_path.read_bytes()).hexdigest(), "outcome": slim}
    _atomic_write(out / ".batch" / f"{outcome.name}.pkl", pickle.dumps(marker, protocol=pickle.HIGHEST_PROTOCOL))
    return slim


def local_cluster(workers: int | None = None):
    """An embedded ``distributed.LocalCluster``: ``workers`` processes (default: one per core), one thread
    each, scheduler, workers and the scheduler's HTTP endpoint (dashboard, if bokeh is installed) on
    127.0.0.1, quiet logs."""
    import logging

    from distributed import LocalCluster

    return LocalCluster(
        n_workers=workers or os.cpu_count() or 1,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        scheduler_port=0,
        dashboard_address="127.0.0.1:0",  # scheduler's HTTP server on loopback, any free port (never 8787)
        silence_logs=logging.ERROR,
    )


def _run_distributed(client, todo, options, handle) -> None:
    """Submit one task per item and hand each outcome (or the reason it has none) to ``handle``."""
    from distributed import as_completed

    futures = {}
    for item, key in todo:
        fut = client.submit(analyze_item, item, options, key=f"hop-impedance-batch-{item.name}-{key[:16]}",
                            pure=False)
        futures[fut] = (item, key)
    for fut in as_completed(list(futures)):
        item, key = futures[fut]
        try:
            outcome = fut.result()
        except Exception as exc:  # noqa: BLE001  KilledWorker after repeated worker deaths, lost connection, ...
            msg = " ".join(str(exc).split())
            outcome = Outcome(name=item.name, error=f"{type(exc).__name__}: {msg}" + (
                " (the workers running this recording died; see distributed.scheduler.allowed-failures)"
                if type(exc).__name__ == "KilledWorker" else ""))
        fut.release()
        handle(item, key, outcome)


def run_batch(
    items: list[BatchItem],
    out_dir: str | Path,
    options: BatchOptions | None = None,
    *,
    mode: str = "local",
    workers: int | None = None,
    client=None,
    group_by: str | None = None,
    force: bool = False,
    progress_stream=None,
) -> BatchSummary:
    """Analyse ``items`` and write the batch outputs into ``out_dir``.

    Parameters
    ----------
    items : list of BatchItem
    out_dir : str or Path
    options : BatchOptions, optional
    mode : str
        ``"serial"``, ``"local"`` (embedded LocalCluster) or a scheduler address ``tcp://HOST:PORT``.
    workers : int, optional
        Worker processes of the embedded cluster (default: one per core).
    client : distributed.Client, optional
        Use this client instead (tests, or a caller that keeps a cluster).
    group_by : str, optional
        Condition of each recording: ``condition`` (the manifest's), ``frequency`` (median hop
        frequency, as ``analyze --report``), ``subject``, ``recording`` or another manifest column.
        Default: ``condition`` when the manifest gives one, else ``frequency``.
    force : bool
        Redo every recording (ignore the skip rule).
    progress_stream : file, optional
        Where the progress line goes (default stderr).

    Returns
    -------
    BatchSummary
    """
    options = options or BatchOptions()
    _check_group_by(items, group_by)
    run = _BatchRun(Path(out_dir), BatchSummary(total=len(items)))
    todo = run.plan(items, options, force)
    run.start_progress(len(todo), progress_stream)
    t0 = time.perf_counter()
    if todo and mode == "serial":
        for item, key in todo:
            run.handle(item, key, analyze_item(item, options))
    elif todo:
        run.summary.workers = _with_client(mode, workers, client, lambda c: _run_distributed(c, todo, options, run.handle))
    return run.finish(items, group_by, time.perf_counter() - t0)


def _check_group_by(items: list[BatchItem], group_by: str | None) -> None:
    """``--group-by`` must be one of :data:`GROUP_KEYS` or a column of the manifest (ValueError naming them)."""
    labels = {k for i in items for k, _ in i.labels}
    if group_by is not None and group_by not in GROUP_KEYS and group_by not in labels:
        raise ValueError(f"--group-by {group_by!r}: expected one of {', '.join(GROUP_KEYS)} or a manifest column"
                         + (f" ({', '.join(sorted(labels))})" if labels else ""))


@dataclass
class _BatchRun:
    """One run's bookkeeping in ``out``: what is to do, what came back, what failed, the progress line."""

    out: Path
    summary: BatchSummary
    #: name -> (name, path, reason) of the recordings not analysed
    failures: dict[str, tuple[str, str, str]] = field(default_factory=dict)
    progress: Progress | None = None

    def plan(self, items: list[BatchItem], options: BatchOptions, force: bool) -> list[tuple[BatchItem, str]]:
        """Make the output folders; return (item, skip key) of each recording to analyse. Up-to-date ones
        (the module docstring's skip rule; none with ``force``) go straight into the summary, unreadable
        inputs into the failures."""
        (self.out / "json").mkdir(parents=True, exist_ok=True)
        (self.out / ".batch").mkdir(exist_ok=True)
        todo = []
        for item in items:
            try:
                key = cache_key(item, options, file_sha256(item.path))
            except OSError as exc:
                self.failures[item.name] = (item.name, item.path, f"{type(exc).__name__}: {exc.strerror or exc}")
                continue
            stored = None if force else _up_to_date(self.out / ".batch" / f"{item.name}.pkl",
                                                    self.out / "json" / f"{item.name}.json", key)
            if stored is not None:
                self.summary.outcomes[item.name] = stored
                self.summary.skipped += 1
            else:
                todo.append((item, key))
        return todo

    def start_progress(self, n_todo: int, stream) -> None:
        """Show the progress line (``stream``: default stderr)."""
        self.progress = Progress(n_todo, self.summary.skipped, stream)
        self.progress.show()

    def handle(self, item: BatchItem, key: str, outcome: Outcome) -> None:
        """Store one task's outcome (JSON, then the skip marker) or record its failure, removing any stale
        output of an earlier run; a worker running another package version counts as a failure."""
        from hop_impedance import __version__

        if outcome.error is None and outcome.version != __version__:
            outcome = Outcome(name=item.name, error=f"worker runs hop_impedance {outcome.version}, "
                                                     f"this command {__version__}")
        if outcome.error is not None:
            self.failures[item.name] = (item.name, item.path, outcome.error)
            # no stale output of an earlier run of a recording that now fails
            (self.out / ".batch" / f"{item.name}.pkl").unlink(missing_ok=True)
            (self.out / "json" / f"{item.name}.json").unlink(missing_ok=True)
        else:
            self.summary.outcomes[item.name] = _store(self.out, outcome, key)
            self.summary.analysed += 1
        assert self.progress is not None  # started before any task runs
        self.progress.update(outcome.error is None)

    def finish(self, items: list[BatchItem], group_by: str | None, seconds: float) -> BatchSummary:
        """Close the progress line, list the failures in ``items`` order, write tables and figures."""
        summary = self.summary
        summary.seconds = seconds
        assert self.progress is not None  # started by run_batch
        self.progress.show(final=True)
        summary.failures = [self.failures[i.name] for i in items if i.name in self.failures]
        summary.failed = len(summary.failures)
        summary.files = _write_outputs(items, summary, self.out, group_by)
        return summary

def _with_client(mode: str, workers: int | None, client, job) -> int:
    """Run ``job(client)`` on the given client, an embedded cluster or the scheduler at ``mode``;
    return the number of workers it had."""
    from distributed import Client

    if client is not None:
        job(client)
        return len(client.scheduler_info(n_workers=-1)["workers"])
    if mode == "local":
        with local_cluster(workers) as cluster, Client(cluster) as c:
            job(c)
            return len(c.scheduler_info(n_workers=-1)["workers"])
    try:
        c = Client(mode, timeout="20s")
    except OSError as exc:
        raise OSError(f"cannot reach the Dask scheduler at {mode}: {exc}") from None
    with c:
        if not c.scheduler_info(n_workers=-1)["workers"]:
            c.wait_for_workers(1, timeout=60)
        n = len(c.scheduler_info(n_workers=-1)["workers"])
        job(c)
        return n


def cluster_map(func, args_list: list[tuple], mode: str = "local", workers: int | None = None) -> list:
    """``[func(*args) for args in args_list]`` with one task per call, results in input order.

    The same execution path as the batch: ``mode`` ``"serial"`` (this process),
    ``"local"`` (embedded LocalCluster, :func:`local_cluster`) or a scheduler
    address. For sweeps (``bench/recovery_errors.py --scheduler``); ``func``
    must be importable or picklable by value on the workers.
    """
    if mode == "serial":
        return [func(*args) for args in args_list]
    results: list = [None] * len(args_list)

    def job(client) -> None:
        futures = [client.submit(func, *args, pure=False) for args in args_list]
        for i, fut in enumerate(futures):
            results[i] = fut.result()
            fut.release()

    _with_client(mode, workers, None, job)
    return results


def _condition(item: BatchItem, outcome: Outcome, group_by: str) -> str:
    labels = dict(item.labels)
    if group_by == "condition":
        return item.condition or outcome.frequency_label
    if group_by == "frequency":
        return outcome.frequency_label
    if group_by == "subject":
        return item.subject or outcome.subject_id
    if group_by == "recording":
        return item.name
    return labels.get(group_by) or "(none)"


def _write_outputs(items: list[BatchItem], summary: BatchSummary, out: Path, group_by: str | None) -> list[Path]:
    """Tidy table, population report and failures.csv from every recording analysed or up to date."""
    from hop_impedance.batch.population import write_population_report
    from hop_impedance.batch.tidy import write_tidy
    from hop_impedance.impedance.report import fit_records

    if group_by is None:
        group_by = "condition" if any(i.condition for i in items) else "frequency"
    extra = tuple(dict.fromkeys(k for i in items for k, _ in i.labels))
    rows, records = [], []
    for item in items:
        outcome = summary.outcomes.get(item.name)
        if outcome is None:
            continue
        subject = item.subject or outcome.subject_id
        condition = _condition(item, outcome, group_by)
        labels = dict(item.labels)
        head = {"recording": item.name, "subject": subject, "condition": condition}
        rows += [{**head, **r, **{k: labels.get(k) for k in extra}} for r in outcome.rows]
        records += fit_records(outcome.fits, condition, subject)
    summary.stances = len({(r["recording"], r["stance"]) for r in rows})
    summary.fits = len(records)
    files = list(write_tidy(rows, out, extra))
    files += write_population_report(rows, records, out / "report")
    failures = out / "failures.csv"
    with open(failures, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(["recording", "path", "reason"])
        writer.writerows(summary.failures)
    return files + [failures]


def summary_text(summary: BatchSummary, out: str) -> str:
    """The end-of-run summary (a few lines)."""
    rate = f" ({summary.analysed / summary.seconds:.2f} recordings/s)" if summary.analysed and summary.seconds else ""
    lines = [
        f"hop-impedance batch: {summary.total} recordings: {summary.analysed} analysed, {summary.skipped} up to date "
        f"(skipped), {summary.failed} failed",
        f"  {summary.stances} stances, {summary.fits} usable joint fits; {summary.seconds:.1f} s wall, cluster start "
        f"included{rate}, on {summary.workers} worker(s)",
        f"  outputs -> {out} (json/, tidy.parquet, tidy.csv, report/, failures.csv)",
    ]
    for name, _, reason in summary.failures[:5]:
        lines.append(f"  failed: {name}: {reason}")
    if summary.failed > 5:
        lines.append(f"  ... {summary.failed - 5} more in failures.csv")
    return "\n".join(lines)


__all__ = ["BatchSummary", "Progress", "cluster_map", "local_cluster", "run_batch", "summary_text"]
