"""``hop-impedance view REC.mcap [--rrd OUT.rrd]``: the Rerun views of a recording, offline.

Runs the batch analysis and the impedance fits, then logs the same entities
and blueprint as the live ``rerun_bridge`` node (docs/rerun.md). Without
``--rrd`` or ``--connect`` a viewer is spawned (needs a display).
"""

from __future__ import annotations

import argparse
import os

from hop_impedance.cli.conventions import add_rrd_argument


def register(subparsers) -> None:
    """Add the ``view`` parser."""
    p = subparsers.add_parser(
        "view",
        help="Rerun views of a recording (stick figure, signals, per-stance fits)",
        description="Analyse a recording, fit the impedance model and show or save the Rerun views.",
    )
    p.add_argument("recording", help="contract recording (MCAP)")
    add_rrd_argument(p, "write an .rrd file (open it with `.venv/bin/rerun OUT.rrd`)", old=("--save",))
    p.add_argument("--connect", metavar="URL", help="stream to a running viewer, e.g. rerun+http://127.0.0.1:9876/proxy")
    p.add_argument("--spawn", action="store_true",
                   help="also spawn a viewer (the default when neither --rrd nor --connect is given)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Analyse, fit, log; print a one-line summary and how to open the file."""
    from pathlib import Path

    from hop_impedance.viz.session import view_recording

    if not Path(args.recording).exists():
        raise FileNotFoundError(f"{args.recording}: no such recording")
    spawn = args.spawn or (args.rrd is None and args.connect is None)
    if spawn and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise ValueError("no display to spawn a viewer on; use --rrd OUT.rrd (or --connect URL)")
    summary = view_recording(args.recording, save=args.rrd, connect_url=args.connect, spawn=spawn)
    rejected = "; ".join(f"{k}: {r}" for k, r in summary.rejected.items())
    print(
        f"{args.recording}: {summary.stances} stances, {summary.fitted_stances} fitted"
        + (f", rejected {rejected}" if rejected else "")
    )
    if args.rrd:
        print(f"wrote {args.rrd}; open it with: .venv/bin/rerun {args.rrd}")
    return 0
