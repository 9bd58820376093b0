"""The tidy stance x joint table of a batch, as Parquet and CSV (pyarrow).

One row per stance and joint of every analysed recording. Columns: the labels
(``recording``, ``subject``, ``condition``), then the task's columns
(:func:`hop_impedance.batch.task.row_columns`: stance figures, fit status,
kept terms, ``coef_*``/``se_*``/``p_*`` of m0 and every Eq. 3 term (NaN where
the reduced model dropped it), fit metrics), then any further manifest labels.
The schema is fixed (text, ``stance`` int64, everything else float64), so the
tables of several batches concatenate.
"""

from __future__ import annotations

from pathlib import Path

#: Label columns in front of the task's columns.
LABEL_COLUMNS: tuple[str, ...] = ("recording", "subject", "condition")
#: Task columns that are text.
TEXT_COLUMNS: tuple[str, ...] = ("stance_rejection", "joint", "status", "rejection_reason", "terms")


def tidy_table(rows: list[dict], extra_labels: tuple[str, ...] = ()):
    """A ``pyarrow.Table`` of the rows with the fixed schema (``extra_labels`` as text columns at the end)."""
    import pyarrow as pa

    from hop_impedance.batch.task import row_columns

    fields = [pa.field(n, pa.string()) for n in LABEL_COLUMNS]
    for name in row_columns():
        kind = pa.string() if name in TEXT_COLUMNS else pa.int64() if name == "stance" else pa.float64()
        fields.append(pa.field(name, kind))
    fields += [pa.field(n, pa.string()) for n in extra_labels]
    return pa.Table.from_pylist(rows, schema=pa.schema(fields))


def write_tidy(rows: list[dict], out_dir: Path, extra_labels: tuple[str, ...] = ()) -> tuple[Path, Path]:
    """Write ``tidy.parquet`` and ``tidy.csv`` into ``out_dir``; returns both paths.

    CSV (pyarrow's writer): empty cells for missing text, ``nan`` for missing
    numbers, numbers with full float64 precision.
    """
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    table = tidy_table(rows, extra_labels)
    parquet, csv = out_dir / "tidy.parquet", out_dir / "tidy.csv"
    pq.write_table(table, parquet)
    pcsv.write_csv(table, csv)
    return parquet, csv


__all__ = ["LABEL_COLUMNS", "TEXT_COLUMNS", "tidy_table", "write_tidy"]
