"""What ``hop-impedance batch`` analyses: recordings and their labels.

INPUT arguments are MCAP files, folders (searched recursively for ``*.mcap``)
or manifest CSV files. A manifest has one row per recording with the columns
``recording, subject, condition`` and optionally ``mass_kg, height_m, sex``;
any further column is kept as a label (usable with ``--group-by``). A relative
``recording`` path is relative to the manifest's folder.

Each recording gets an output name (the JSON is ``json/<name>.json``): the
file stem, or for a folder input the path below the folder with ``/`` as
``__``; two recordings with the same name get a suffix from a hash of their
absolute paths, so the names do not depend on the order of the inputs.
"""

from __future__ import annotations

import csv
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

#: Manifest columns every row must have.
MANIFEST_REQUIRED: tuple[str, ...] = ("recording", "subject", "condition")
#: Manifest columns that override the recording's /subject message.
MANIFEST_SUBJECT: tuple[str, ...] = ("mass_kg", "height_m", "sex")


@dataclass(frozen=True)
class BatchItem:
    """One recording to analyse.

    Attributes
    ----------
    path : str
        The MCAP file as the input named it (a folder input's path joined with
        the file's path below it; a manifest's relative path joined with the
        manifest's folder), so the JSON's ``recording.source`` is what
        ``analyze`` writes for the same path. Workers open this path.
    name : str
        Output name, unique in the job.
    subject : str or None
        Manifest subject (pairing key); None: the recording's /subject id.
    condition : str or None
        Manifest condition; None: decided by ``--group-by``.
    mass_kg, height_m : float or None
        Manifest body mass / height overriding the recording's.
    sex : str or None
        ``female`` or ``male`` (de Leva table), overriding the recording's.
    labels : tuple of (str, str)
        Further manifest columns.
    """

    path: str
    name: str
    subject: str | None = None
    condition: str | None = None
    mass_kg: float | None = None
    height_m: float | None = None
    sex: str | None = None
    labels: tuple[tuple[str, str], ...] = field(default=())


def _float(value: str | None, column: str, where: str) -> float | None:
    if value is None or value.strip() == "":
        return None
    try:
        return float(value)
    except ValueError:
        raise ValueError(f"{where}: {column} {value!r} is not a number") from None


def read_manifest(path: Path) -> list[tuple[Path, dict]]:
    """Rows of a manifest CSV as ``(recording path, fields)``; raises ValueError on a bad manifest."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        reader = csv.DictReader(fh)
        columns = [c.strip() for c in (reader.fieldnames or [])]
        missing = [c for c in MANIFEST_REQUIRED if c not in columns]
        if missing:
            raise ValueError(f"{path}: manifest lacks column(s) {', '.join(missing)} (needs {', '.join(MANIFEST_REQUIRED)})")
        rows = []
        for line, raw in enumerate(reader, start=2):
            row = {(k or "").strip(): (v or "").strip() for k, v in raw.items()}
            where = f"{path}:{line}"
            if not row["recording"]:
                raise ValueError(f"{where}: empty recording")
            sex = row.get("sex") or None
            if sex is not None and sex not in ("female", "male"):
                raise ValueError(f"{where}: sex must be female or male, got {sex!r}")
            fields = {
                "subject": row["subject"] or None,
                "condition": row["condition"] or None,
                "mass_kg": _float(row.get("mass_kg"), "mass_kg", where),
                "height_m": _float(row.get("height_m"), "height_m", where),
                "sex": sex,
                "labels": tuple((k, v) for k, v in row.items() if k not in MANIFEST_REQUIRED + MANIFEST_SUBJECT),
            }
            rec = Path(row["recording"])
            rows.append((rec if rec.is_absolute() else path.parent / rec, fields))
    return rows


def collect_items(inputs: list[str]) -> list[BatchItem]:
    """Every recording named by ``inputs``, in input order (folders sorted), each once.

    Raises
    ------
    FileNotFoundError
        An input (or a manifest's recording) does not exist.
    ValueError
        A folder holds no ``.mcap``, or a manifest is malformed.
    """
    found: list[tuple[Path, str, dict]] = []  # (path as named, base name, fields)
    for text in inputs:
        p = Path(text)
        if not p.exists():
            raise FileNotFoundError(f"{text}: no such file or folder")
        if p.is_dir():
            recs = sorted(q for q in p.rglob("*.mcap") if q.is_file())
            if not recs:
                raise ValueError(f"{text}: no .mcap recordings in this folder")
            for q in recs:
                found.append((q, "__".join(q.relative_to(p).with_suffix("").parts), {}))
        elif p.suffix.lower() == ".csv":
            for rec, fields in read_manifest(p):
                if not rec.exists():
                    raise FileNotFoundError(f"{text}: recording {rec} does not exist")
                found.append((rec, rec.stem, fields))
        else:
            found.append((p, p.stem, {}))
    seen: dict[Path, int] = {}
    unique: list[tuple[Path, str, dict]] = []
    for path, base, fields in found:
        real = path.resolve()
        if real in seen:
            if fields and not unique[seen[real]][2]:  # a manifest's labels win over a bare listing
                unique[seen[real]] = (path, base, fields)
            continue
        seen[real] = len(unique)
        unique.append((path, base, fields))
    counts: dict[str, int] = {}
    for _, base, _ in unique:
        counts[base] = counts.get(base, 0) + 1
    items = []
    for path, base, fields in unique:
        name = base if counts[base] == 1 else f"{base}-{hashlib.sha1(str(path.resolve()).encode()).hexdigest()[:8]}"
        items.append(BatchItem(path=str(path), name=name, **fields))
    return items


__all__ = ["BatchItem", "MANIFEST_REQUIRED", "MANIFEST_SUBJECT", "collect_items", "read_manifest"]
