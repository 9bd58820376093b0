"""Read an .rrd back with Rerun's own API (RrdReader -> ChunkStore -> DataFusion dataframe)."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader


def load_store(path):
    """All chunks of the first recording in ``path`` as a ``ChunkStore``."""
    return RrdReader(str(path)).stream().collect()


def column(store, index: str | None, entity: str, component: str) -> tuple[np.ndarray | None, list]:
    """Non-null rows of one component: (index values or None for static, values as Python lists)."""
    name = f"{entity}:{component}"
    table: pa.Table = store.reader(index=index, contents=entity).to_arrow_table()
    if name not in table.column_names:
        return None, []
    mask = table.column(name).is_valid()
    rows = table.filter(mask)
    idx = None
    if index is not None:
        raw = rows.column(index).to_numpy()
        idx = raw.astype("timedelta64[ns]").astype(np.int64) * 1e-9 if raw.dtype.kind == "m" else raw
    return idx, rows.column(name).to_pylist()


def scalars(store, index: str, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """(times or sequence, values) of a Scalars entity, one value per row."""
    t, values = column(store, index, entity, "Scalars:scalars")
    return t, np.array([v[0] if v else np.nan for v in values], float)


def entity_paths(store) -> set[str]:
    """Every entity path in the store's schema."""
    out = set()
    for col in store.schema():
        path = getattr(col, "entity_path", None)
        if path:
            out.add(path)
    return out
