"""One task of ``hop-impedance batch``: one recording, analysed exactly as ``analyze`` does.

:func:`analyze_item` is a plain function of (item, options): the serial path
calls it in the command's process, Dask workers call it remotely; nothing here
imports Dask. It runs the steps of ``hop-impedance analyze REC --json OUT``
through the same functions (``analyze_cmd.checked_recording``, ``analyze_cmd.analyze_and_fit``,
``json.dumps(..., allow_nan=False)``), so the JSON text is the same byte for
byte (test/batch checks it against the command), and returns it with the tidy stance x joint rows and
the usable fits (for the population tables and figures).

Numerical thread settings: every task runs with one BLAS/OpenMP thread
(threadpoolctl), in the serial path as on a worker, so the floating-point
operation order, and so every bit of the result, does not depend on where the
task ran. (A BLAS with several threads may sum in another order.)

What travels: to a worker the item (path and labels, ~0.3 kB) and the options;
back the JSON text (~0.1 MB per 10 hops) and the slim fits (arrays of each
usable stance x joint fit, without the reduction/diagnostic objects). The
recording itself is read by the worker from ``item.path``: on an existing
cluster the workers must see the same paths (a shared file system).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import time
from dataclasses import asdict, dataclass, field, replace
from types import SimpleNamespace

#: Version of the batch output layout (part of the skip key).
BATCH_FORMAT = "hop_impedance.batch/1"
#: Fit quantities of a tidy row (attributes of JointImpedanceFit).
FIT_METRICS: tuple[str, ...] = (
    "rho0", "omega0", "rmse", "r_squared", "sse_variable", "sse_constant", "table3_variable", "table3_constant",
    "overall_stiffness", "average_stiffness", "initial_stiffness", "max_stiffness",
)


def row_columns() -> tuple[str, ...]:
    """Column names of :func:`tidy_rows`, in order."""
    from hop_impedance.impedance.regression_model import PARAMETER_NAMES

    return (
        ("stance", "touchdown_s", "hop_frequency_hz", "contact_time_s", "peak_grf_bw", "hip_excursion_m",
         "stance_rejection", "joint", "range_of_flexion_rad", "max_moment_nm", "brake_work_j", "push_work_j",
         "status", "rejection_reason", "terms")
        + tuple(f"{k}_{p}" for p in PARAMETER_NAMES for k in ("coef", "se", "p"))
        + FIT_METRICS
    )


@dataclass(frozen=True)
class BatchOptions:
    """Analysis options of a batch (the ``analyze`` options that change the JSON).

    Attributes
    ----------
    cutoff_hz : float
        Low-pass cut-off of markers and forces (Hz), as ``analyze --cutoff-hz``.
    max_gap_s : float
        Longest marker gap filled (s), as ``analyze --max-gap-s``.
    segments : dict or None
        Per-segment overrides (``analyze --segments``), already read.
    indent : int or None
        JSON indent, as ``analyze --indent``.
    detector : tuple of str
        ``NAME=VALUE`` stance detection settings, as ``analyze --detector``.
    model_terms : tuple of str
        Fixed model structure, as ``analyze --model-terms`` (empty: chosen per joint from the F-tests).
    """

    cutoff_hz: float = 12.0
    max_gap_s: float = 0.05
    segments: dict | None = field(default=None, compare=False, hash=False)
    indent: int | None = None
    detector: tuple[str, ...] = ()
    model_terms: tuple[str, ...] = ()

    def analysis_options(self):
        """The :class:`AnalysisOptions` ``analyze`` builds from the same flags."""
        from hop_impedance.biomech.analysis import AnalysisOptions
        from hop_impedance.biomech.stance_detection import DetectorOptions

        return AnalysisOptions(
            marker_cutoff_hz=self.cutoff_hz,
            force_cutoff_hz=self.cutoff_hz,
            max_gap_s=self.max_gap_s,
            overrides=self.segments,
            detector=DetectorOptions.from_settings(list(self.detector) or None),
        )


def file_sha256(path: str) -> str:
    """Hex SHA-256 of a file's content."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def cache_key(item, options: BatchOptions, input_sha256: str) -> str:
    """Skip key of one recording: its content, the options that reach the task, the package version.

    Subject and condition labels are not in it: they only label rows, which the
    command re-attaches on every run.
    """
    from hop_impedance import __version__

    what = {
        "format": BATCH_FORMAT,
        "version": __version__,
        "input": input_sha256,
        "options": {k: v for k, v in asdict(options).items()},
        "subject": [item.mass_kg, item.height_m, item.sex],
    }
    return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()


@dataclass
class Outcome:
    """What one task sends back.

    Attributes
    ----------
    name : str
        The item's output name.
    error : str or None
        Why the recording could not be analysed (None: it was).
    json_text : str
        The ``analyze`` JSON document (without the final newline).
    subject_id : str
        The analysed subject's id (the recording's /subject).
    frequency_label : str
        ``analyze --report``'s condition label: median hop frequency, "2.20 Hz".
    rows : list of dict
        Tidy rows, one per stance x joint (labels added by the command).
    fits : list of dict
        Per stance ``{joint: JointImpedanceFit}`` of the usable fits, without
        ``reduction``/``diagnostics``.
    seconds : float
        Time spent in the task (s).
    version : str
        hop_impedance version that ran it.
    pid : int
        Process that ran it.
    """

    name: str
    error: str | None = None
    json_text: str = ""
    subject_id: str = ""
    frequency_label: str = ""
    rows: list = field(default_factory=list)
    fits: list = field(default_factory=list)
    seconds: float = 0.0
    version: str = ""
    pid: int = 0


@contextlib.contextmanager
def one_blas_thread():
    """Limit BLAS/OpenMP libraries to one thread inside the block (restored afterwards)."""
    import numpy  # noqa: F401  load every BLAS the task uses before limiting
    import osqp  # noqa: F401
    import scipy.linalg  # noqa: F401
    import scipy.stats  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


@contextlib.contextmanager
def quiet_stdout():
    """File descriptor 1 to /dev/null inside the block: OSQP's C polish prints there whatever
    its settings (see cli/json_output.py), which would break the progress line."""
    import sys

    sys.stdout.flush()
    saved = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    try:
        with contextlib.redirect_stdout(open(os.devnull, "w")) as sink:  # noqa: SIM115
            try:
                yield
            finally:
                sink.close()
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def tidy_rows(analysis, fits) -> list[dict]:
    """One row per stance x joint: stance figures (seed Table 1 quantities) and the fit.

    Stances without inverse dynamics give rows with ``status`` None and the
    stance's rejection reason; coefficient, standard-error and p-value columns
    of terms the reduced model did not keep are NaN (``terms`` lists the kept
    ones).
    """
    import math

    import numpy as np

    from hop_impedance.biomech.analysis import JOINT_NAMES
    from hop_impedance.impedance.regression_model import PARAMETER_NAMES

    nan = math.nan
    rows = []
    for stance, stance_fits in zip(analysis.stances, fits):
        base = {
            "stance": stance.index,
            "touchdown_s": float(stance.touchdown_s),
            "hop_frequency_hz": nan if stance.hop_frequency_hz is None else float(stance.hop_frequency_hz),
            "contact_time_s": float(stance.contact_time_s),
            "peak_grf_bw": float(stance.peak_grf_bw),
            "hip_excursion_m": float(stance.hip_excursion_m),
            "stance_rejection": stance.rejection_reason,
        }
        for j, joint in enumerate(JOINT_NAMES):
            row = dict(base, joint=joint)
            if stance.joints is not None:
                arrays = stance.joints.joint(joint)
                row["range_of_flexion_rad"] = float(arrays["angle_rad"].max() - arrays["angle_rad"][0])
                row["max_moment_nm"] = float(arrays["moment_nm"].max())
                row["brake_work_j"] = float(stance.brake_work_j[j])
                row["push_work_j"] = float(stance.push_work_j[j])
            else:
                row.update(range_of_flexion_rad=nan, max_moment_nm=nan, brake_work_j=nan, push_work_j=nan)
            fit = stance_fits.get(joint)
            row["status"] = None if fit is None else fit.status
            row["rejection_reason"] = stance.rejection_reason if fit is None else fit.rejection_reason
            row["terms"] = "" if fit is None else " ".join(fit.terms)
            for p in PARAMETER_NAMES:
                row[f"coef_{p}"] = nan if fit is None else float(fit.coefficients.get(p, nan))
                row[f"se_{p}"] = nan if fit is None else float(fit.std_errors.get(p, nan))
                row[f"p_{p}"] = nan if fit is None else float(fit.p_values.get(p, nan))
            for name in FIT_METRICS:
                row[name] = nan if fit is None else float(np.float64(getattr(fit, name)))
            rows.append(row)
    return rows


def _analyze(item, options: BatchOptions) -> Outcome:
    from hop_impedance import __version__
    from hop_impedance.cli.analyze_cmd import analyze_and_fit, checked_recording, condition_label

    # analyze's own steps: a recording analyze refuses fails here too, and the JSON is analyze's
    flags = SimpleNamespace(mass_kg=item.mass_kg, height_m=item.height_m, sex=item.sex)
    rec, _ = checked_recording(item.path, flags, options.cutoff_hz)
    analysis, doc, fits = analyze_and_fit(rec, options.analysis_options(), list(options.model_terms) or None)
    return Outcome(
        name=item.name,
        json_text=json.dumps(doc, indent=options.indent, allow_nan=False),
        subject_id=analysis.subject.subject_id,
        frequency_label=condition_label(analysis, item.path, []),
        rows=tidy_rows(analysis, fits),
        fits=[{j: replace(f, reduction=None, diagnostics=None) for j, f in s.items() if f.ok} for s in fits],
        version=__version__,
    )


def analyze_item(item, options: BatchOptions) -> Outcome:
    """Analyse one recording; a recording that cannot be analysed gives ``Outcome.error``, not an exception.

    Parameters
    ----------
    item : BatchItem
    options : BatchOptions

    Returns
    -------
    Outcome
    """
    t0 = time.perf_counter()
    try:
        with one_blas_thread(), quiet_stdout():
            out = _analyze(item, options)
    except Exception as exc:  # noqa: BLE001  any failure of one recording is that recording's failure row
        msg = " ".join(str(exc).split()) or "no message"
        out = Outcome(name=item.name, error=f"{type(exc).__name__}: {msg}")
    out.seconds = time.perf_counter() - t0
    out.pid = os.getpid()
    return out


__all__ = ["BATCH_FORMAT", "FIT_METRICS", "BatchOptions", "Outcome", "analyze_item", "cache_key", "file_sha256",
           "one_blas_thread", "row_columns", "tidy_rows"]
