"""Rerun (.rrd) view of a discovery run: measured vertical force and the gap per step.

Uses rerun-sdk directly (a ``RecordingStream`` of its own, file sink only,
nothing spawned). Analytics are a viewer setting (``rerun analytics disable``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hop_impedance.discovery.forward import GAP_SIGNALS
from hop_impedance.discovery.report import gap_table
from hop_impedance.recording import Recording


def write_rrd(rec: Recording, doc: dict, path: str | Path) -> Path:
    """Write ``path``: ``force/fz_raw`` over recording time (s) and ``gap/<signal>`` (relative RMS) over ``step``."""
    import rerun as rr

    stream = rr.RecordingStream("hop_impedance_discover")
    stream.save(str(path))
    t = (rec.force.stamp_ns - rec.start_ns) * 1e-9
    stream.send_columns("force/fz_raw", indexes=[rr.TimeColumn("time", duration=t)],
                        columns=rr.Scalars.columns(scalars=rec.force.force_n[:, 2]))
    labels, table = gap_table(doc)
    steps = np.arange(len(labels))
    for k, sig in enumerate(GAP_SIGNALS):
        ok = np.isfinite(table[:, k])
        if ok.any():
            stream.send_columns(f"gap/{sig}", indexes=[rr.TimeColumn("step", sequence=steps[ok])],
                                columns=rr.Scalars.columns(scalars=table[ok, k]))
    stream.log("effects_found", rr.TextDocument(", ".join(doc["effects_found"]) or "none"), static=True)
    stream.flush()
    return Path(path)
