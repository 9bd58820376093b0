"""JSON clean-up and PNG figures of a discovery document."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from hop_impedance.discovery.forward import GAP_SIGNALS


def to_json_ready(obj):
    """Recursively convert numpy scalars/arrays to Python and NaN/inf to None (strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): to_json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_json_ready(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_json_ready(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def gap_table(doc: dict) -> tuple[list[str], np.ndarray]:
    """Relative RMS gap per signal (columns) after baseline and each step (rows); NaN where missing."""
    labels = ["baseline"] + [st["effect"] for st in doc["steps"]]
    gaps = [doc["baseline_gap"]] + [st["gap_after"] for st in doc["steps"]]
    table = np.full((len(gaps), len(GAP_SIGNALS)), np.nan)
    for i, g in enumerate(gaps):
        for k, sig in enumerate(GAP_SIGNALS):
            if g and g.get(sig) and g[sig].get("relative_rms") is not None:
                table[i, k] = g[sig]["relative_rms"]
    return labels, table


def write_figures(doc: dict, out_dir: str | Path) -> list[Path]:
    """``gap_per_step.png`` (relative RMS per signal, baseline and each step) and
    ``selection.png`` (held-out forward-gap shrink of every candidate in each round). Returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    labels, table = gap_table(doc)
    fig, ax = plt.subplots(figsize=(9, 4))
    width = 0.8 / max(len(labels), 1)
    x = np.arange(len(GAP_SIGNALS))
    for i, lab in enumerate(labels):
        ax.bar(x + i * width, table[i], width, label=lab)
    ax.set_xticks(x + 0.4 - width / 2, GAP_SIGNALS, rotation=30, ha="right")
    ax.set_ylabel("held-out RMS gap / signal range")
    ax.set_title("Forward-simulation gap: baseline and after each named effect")
    ax.legend(fontsize=8)
    fig.tight_layout()
    p1 = out / "gap_per_step.png"
    fig.savefig(p1, dpi=100)
    plt.close(fig)
    rounds = doc["selection"]["rounds"]
    fig, ax = plt.subplots(figsize=(9, 4))
    for r, scores in enumerate(rounds):
        names = list(scores)
        ax.scatter(names, [max(scores[n]["held_out_shrink"], -1.0) for n in names], label=f"round {r + 1}")
    ax.axhline(doc["selection"]["min_shrink"], color="k", ls="--", lw=1, label="min shrink")
    ax.set_ylabel("held-out forward-gap shrink (share, clipped at -1)")
    ax.tick_params(axis="x", rotation=30)
    ax.legend(fontsize=8)
    fig.tight_layout()
    p2 = out / "selection.png"
    fig.savefig(p2, dpi=100)
    plt.close(fig)
    return [p1, p2]
