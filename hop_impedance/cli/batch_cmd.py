"""``hop-impedance batch INPUT... --out DIR``: many recordings at once on Dask distributed.

The work is in :mod:`hop_impedance.batch` (see docs/batch.md); this module is
the command line.
"""

from __future__ import annotations

import argparse

from hop_impedance.cli.conventions import OptionDefault

OPTIONS = "hop_impedance.batch.task:BatchOptions"

def register(subparsers) -> None:
    """Add the ``batch`` parser."""
    p = subparsers.add_parser(
        "batch",
        help="analyse many recordings (one Dask task each) with population tables",
        description="Analyse many recordings, one task per recording on an embedded Dask cluster (default) or an "
                    "existing one (--scheduler): per-recording analyze JSON, a tidy stance x joint table "
                    "(Parquet, CSV), Table 1/2/3 layouts by condition with tests paired by subject, figures, "
                    "failures.csv. Re-running skips recordings whose output is up to date.",
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="MCAP recording, folder (searched recursively) or manifest CSV "
                        "(recording, subject, condition[, mass_kg, height_m, sex, ...])")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created; re-runs reuse it)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="worker processes of the embedded local cluster (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on an existing Dask cluster, e.g. tcp://HOST:8786 (workers must see the input paths)")
    where.add_argument("--serial", action="store_true", help="no Dask: one recording after the other in this process")
    p.add_argument("--group-by", metavar="KEY",
                   help="condition of each recording: condition (manifest), frequency (median hop frequency), "
                        "subject, recording, or another manifest column (default: condition if the manifest "
                        "gives one, else frequency)")
    p.add_argument("--force", action="store_true", help="redo every recording, even those up to date")
    p.add_argument("--cutoff-hz", type=float, default=OptionDefault(OPTIONS, "cutoff_hz"),
                   help="as analyze: low-pass cut-off (Hz, default %(default)s)")
    p.add_argument("--max-gap-s", type=float, default=OptionDefault(OPTIONS, "max_gap_s"),
                   help="as analyze: longest marker gap filled (s, default %(default)s)")
    p.add_argument("--segments", metavar="YAML", help="as analyze: per-segment overrides of the body model")
    p.add_argument("--indent", type=int, default=None, help="as analyze: pretty-print the JSON with this indent")
    p.add_argument("--detector", action="append", metavar="NAME=VALUE",
                   help="as analyze: stance detection setting (repeatable), e.g. takeoff_n=15")
    p.add_argument("--model-terms", metavar="T1,T2,...",
                   help="as analyze: fit this structure (e.g. k0,k1,b0) to every stance and joint")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Collect the recordings, run the batch, print the summary; exit 1 when a recording failed."""
    import sys
    from pathlib import Path

    from hop_impedance.batch.inputs import collect_items
    from hop_impedance.batch.runner import run_batch, summary_text
    from hop_impedance.batch.task import BatchOptions
    from hop_impedance.biomech.body_model import load_overrides

    if args.workers is not None and args.workers < 1:
        raise ValueError("--workers must be at least 1")
    if not args.cutoff_hz > 0:
        raise ValueError(f"--cutoff-hz must be > 0, got {args.cutoff_hz}")
    if not args.max_gap_s >= 0:
        raise ValueError(f"--max-gap-s must be >= 0, got {args.max_gap_s}")
    items = collect_items(args.inputs)
    if args.scheduler:  # remote workers do not share this process's working directory
        from dataclasses import replace

        items = [replace(i, path=str(Path(i.path).resolve())) for i in items]
    options = BatchOptions(
        cutoff_hz=args.cutoff_hz,
        max_gap_s=args.max_gap_s,
        segments=load_overrides(args.segments) if args.segments else None,
        indent=args.indent,
        detector=tuple(args.detector or ()),
        model_terms=tuple(t.strip() for t in (args.model_terms or "").split(",") if t.strip()),
    )
    # bad --detector / --model-terms: one line now, not one failure per recording
    options.analysis_options()
    if options.model_terms:
        from hop_impedance.impedance.recording_fits import given_structure

        given_structure(list(options.model_terms), "--model-terms")
    mode = "serial" if args.serial else args.scheduler or "local"
    summary = run_batch(items, args.out, options, mode=mode, workers=args.workers, group_by=args.group_by,
                        force=args.force)
    print(summary_text(summary, args.out), file=sys.stderr)
    return 1 if summary.failed else 0
