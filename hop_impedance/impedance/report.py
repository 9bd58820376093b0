"""Report of impedance fits: Table 2/3 layouts (CSV + Markdown) and figures (PNG).

Layout follows the seed paper: Table 2 (overall, average, k0, k1 per joint,
mean (SD) per condition), Table 3 (variable vs constant model error per
condition and joint), and figures in the spirit of Figs. 4-7 (moment-angle
loops with the variable- and constant-stiffness fits, K(t), maximal vs initial
stiffness). A condition is one recording's label (e.g. its hop frequency).
Figures use matplotlib's Agg backend (no display).
"""

from __future__ import annotations

import csv
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from hop_impedance.impedance.stance_fit import JointImpedanceFit
from hop_impedance.impedance.statistics import (
    StanceFitRecord,
    markdown_table,
    table2,
    table3,
    wilcoxon_between_conditions,
    wilcoxon_variable_vs_constant,
)

if TYPE_CHECKING:  # matplotlib is imported only when figures are drawn
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    Rgba = tuple[float, float, float, float]  # a colormap's colour

JOINTS = ("ankle", "knee", "hip")


def fit_records(fits: list[dict[str, JointImpedanceFit]], condition: str, subject_id: str) -> list[StanceFitRecord]:
    """Usable fits of one recording as :class:`StanceFitRecord` (rejected fits are left out)."""
    return [
        StanceFitRecord(condition, subject_id, joint, stance[joint])
        for stance in fits
        for joint in JOINTS
        if joint in stance and stance[joint].ok
    ]


def _write_csv(path: Path, header: list[str], rows: list[list[str]]) -> None:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def write_tables(records: list[StanceFitRecord], conditions: list[str], out_dir: Path) -> dict[str, Path]:
    """Write table2.csv, table3.csv and report.md (both tables, counts, Wilcoxon tests).

    Parameters
    ----------
    records : list of StanceFitRecord
    conditions : list of str
        Column order (e.g. frequencies ascending).
    out_dir : Path
        Created if missing.

    Returns
    -------
    dict
        ``{"table2": path, "table3": path, "markdown": path}``.

    Notes
    -----
    Wilcoxon signed-rank tests: variable vs constant model SSE per condition
    and joint (paired by stance), and between consecutive conditions per
    joint and Table 2 quantity, paired by stance order (``pair_by="stance"``:
    one subject, several stances; with several subjects pair by subject).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    h2 = ["joint", "quantity"] + conditions
    h3 = ["condition", "model"] + list(JOINTS)
    t2, t3 = table2(records, conditions), table3(records, conditions)
    paths = {"table2": out_dir / "table2.csv", "table3": out_dir / "table3.csv", "markdown": out_dir / "report.md"}
    _write_csv(paths["table2"], h2, t2)
    _write_csv(paths["table3"], h3, t3)
    counts = [[c] + [str(sum(r.condition == c and r.joint == j for r in records)) for j in JOINTS] for c in conditions]
    tests = []
    for c in conditions:
        for j in JOINTS:
            n, p = wilcoxon_variable_vs_constant(records, j, c)
            tests.append([c, j, "SSE variable vs constant", str(n), f"{p:.3g}"])
    for a, b in zip(conditions, conditions[1:]):
        for j in JOINTS:
            for name in ("average_stiffness", "k0"):
                n, p = wilcoxon_between_conditions(records, j, name, a, b, pair_by="stance")
                tests.append([f"{a} vs {b}", j, name, str(n), f"{p:.3g}"])
    text = (
        "# Impedance fits\n\n## Usable fits per condition and joint\n\n"
        + markdown_table(["condition"] + list(JOINTS), counts)
        + "\n## Table 2 layout: stiffness, mean (SD) over stances\n\n"
        + markdown_table(h2, t2)
        + "\n## Table 3 layout: error SSE * 1e-3 / N * FR, mean (SD)\n\n"
        + markdown_table(h3, t3)
        + "\n## Wilcoxon signed-rank tests (two-sided)\n\n"
        + markdown_table(["conditions", "joint", "quantity", "pairs", "p"], tests)
    )
    paths["markdown"].write_text(text, encoding="utf-8")
    return paths


def write_figures(records: list[StanceFitRecord], conditions: list[str], out_dir: Path) -> list[Path]:
    """PNG figures: moment-angle loops (Figs. 4-5 spirit), K(t) (Fig. 6), max vs initial stiffness (Fig. 7).

    Parameters
    ----------
    records : list of StanceFitRecord
    conditions : list of str
    out_dir : Path

    Returns
    -------
    list of Path
        ``moment_angle.png``, ``stiffness_time.png``, ``max_vs_initial_stiffness.png``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    colors = {c: plt.cm.viridis(i / max(len(conditions) - 1, 1)) for i, c in enumerate(conditions)}
    figures = (
        ("moment_angle.png", _plot_moment_angle, 6),
        ("stiffness_time.png", _plot_stiffness_time, 7),
        ("max_vs_initial_stiffness.png", _plot_max_vs_initial, 7),
    )
    paths = []
    for name, plot, legend_size in figures:
        fig, axes = plt.subplots(1, 3, figsize=(12, 4))
        for ax, joint in zip(axes, JOINTS):
            plot(ax, [r for r in records if r.joint == joint], conditions, colors)
            ax.set_title(joint)
        axes[0].legend(fontsize=legend_size)
        paths.append(_save(fig, out_dir / name, plt))
    return paths


def _plot_moment_angle(ax: Axes, records: list[StanceFitRecord], conditions: list[str], colors: dict[str, Rgba]) -> None:
    """Measured, variable-K and constant-K moment against rho - rho0 of a middle stance per condition (one joint)."""
    for c in conditions:
        sel = [r.fit for r in records if r.condition == c]
        if not sel:
            continue
        f = sel[len(sel) // 2]  # a middle stance of the condition
        d = f.angle_rad - f.rho0
        ax.plot(d, f.moment_nm, color=colors[c], lw=1.5, label=f"{c} measured")
        ax.plot(d, f.moment_fit, color=colors[c], ls="--", lw=1, label=f"{c} variable K")
        ax.plot(d, f.moment_constant, color=colors[c], ls=":", lw=1, label=f"{c} constant K")
    ax.set(xlabel="rho - rho0 (rad, flexion +)", ylabel="moment (N m, extensor +)")


def _plot_stiffness_time(ax: Axes, records: list[StanceFitRecord], conditions: list[str], colors: dict[str, Rgba]) -> None:
    """K(t) of every stance, coloured by condition (one joint)."""
    for c in conditions:
        for i, r in enumerate(r for r in records if r.condition == c):
            ax.plot(r.fit.time_s, r.fit.stiffness, color=colors[c], lw=0.8, label=c if i == 0 else None)
    ax.set(xlabel="time since touchdown (s)", ylabel="K (N m/rad)")


def _plot_max_vs_initial(ax: Axes, records: list[StanceFitRecord], conditions: list[str], colors: dict[str, Rgba]) -> None:
    """Maximal against initial stiffness per stance with the identity line (one joint)."""
    top = 0.0
    for c in conditions:
        sel = [r.fit for r in records if r.condition == c]
        x = [f.initial_stiffness for f in sel]
        y = [f.max_stiffness for f in sel]
        ax.scatter(x, y, s=12, color=colors[c], label=c)
        top = max([top] + [v for v in x + y if np.isfinite(v)])
    ax.plot([0, top], [0, top], color="0.6", lw=0.8)
    ax.set(xlabel="initial stiffness k0 (N m/rad)", ylabel="maximal stiffness (N m/rad)")


def _save(fig: Figure, path: Path, plt: ModuleType) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def write_report(records: list[StanceFitRecord], conditions: list[str], out_dir: str | Path) -> list[Path]:
    """Tables and figures into ``out_dir``; returns every file written."""
    out = Path(out_dir)
    return list(write_tables(records, conditions, out).values()) + write_figures(records, conditions, out)


__all__ = ["fit_records", "write_figures", "write_report", "write_tables"]
