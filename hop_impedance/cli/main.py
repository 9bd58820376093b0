"""The ``hop-impedance`` command: one entry point, one sub-command per workflow.

Each sub-command lives in its own module ``hop_impedance/cli/<name>_cmd.py``
exposing ``register(subparsers)``, which adds its parser and sets
``func=run``, following the conventions in :mod:`hop_impedance.cli.conventions`.
Heavy imports (rclpy, scipy, rerun) happen inside ``run``, so building the parser and
``hop-impedance --help`` import none of them (test/cli/test_conventions.py). A sub-command's
``--help`` imports the modules whose defaults it shows (``analyze --help``: the analysis, ~1-2 s).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from hop_impedance.cli.conventions import Parser

# Order shown in --help.
COMMAND_MODULES: tuple[str, ...] = (
    "demo",
    "analyze",
    "batch",
    "simulate",
    "discover",
    "view",
    "replay",
    "pipeline",
    "import",
    "info",
)

DESCRIPTION = """\
Stance-by-stance stiffness and damping of the ankle, knee and hip in hopping.

Typical use:
  hop-impedance info REC.mcap                 what a recording holds
  hop-impedance analyze REC.mcap --json OUT   stances, inverse dynamics and impedance fits
  hop-impedance batch DIR --out OUT           many recordings on Dask, population tables
  hop-impedance simulate --freq 2.2 --out REC.mcap
  hop-impedance pipeline REC.mcap             the ROS 2 node graph on a replayed recording
  hop-impedance view REC.mcap --rrd OUT.rrd   Rerun views of a session
  hop-impedance discover REC.mcap --json OUT  name the effect a simulation misses
  hop-impedance import SESSION.c3d --out REC.mcap
"""


def build_parser() -> argparse.ArgumentParser:
    """Parser with every sub-command whose module is present."""
    parser = Parser(
        prog="hop-impedance",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version="%(prog)s " + _version())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"hop_impedance.cli.{name}_cmd")
        except ModuleNotFoundError as exc:
            if exc.name == f"hop_impedance.cli.{name}_cmd":
                continue
            raise
        module.register(sub)
    return parser


def _version() -> str:
    from hop_impedance import __version__

    return __version__


def main(argv: list[str] | None = None) -> int:
    """Run a sub-command; expected problems print one line and exit 2."""
    # Network rule: DDS discovery stays on this machine unless the user says otherwise.
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        result = args.func(args)
    except (ValueError, FileNotFoundError, OSError) as exc:
        print(f"hop-impedance {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return int(result or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
