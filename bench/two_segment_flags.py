"""The two-segment shooting flags of the discovery benches (session 23's ``forward_selection`` options), declared
and checked in one place: ``--two-segment`` (``forward_selection.TWO_SEGMENT``: the run from the touchdown compared
before the start sample, the late run from it) and ``--two-segment-flight`` (``forward_selection.TWO_SEGMENT_FLIGHT``:
a run from the touchdown that takes off before the start sample compared as in flight up to it). Both need the
bench's late-start flag (``--simulate-from`` or ``--start-after``)."""

from __future__ import annotations

import argparse

from hop_impedance.discovery import forward_selection as fs


def add_two_segment_arguments(ap: argparse.ArgumentParser, late_flag: str) -> None:
    """Declare ``--two-segment`` and ``--two-segment-flight`` on ``ap``; ``late_flag`` names the bench's late start."""
    ap.add_argument("--two-segment", action="store_true",
                    help=f"with {late_flag}: forward_selection.TWO_SEGMENT = True (session 23's option): the run "
                         "from the touchdown compared before the start sample, the late run from it")
    ap.add_argument("--two-segment-flight", action="store_true",
                    help="with --two-segment: forward_selection.TWO_SEGMENT_FLIGHT = True (session 23's option): a run "
                         "from the touchdown that takes off before the start sample compared as in flight up to it")


def check_two_segment(ap: argparse.ArgumentParser, args: argparse.Namespace, late_flag: str, late_given: bool) -> None:
    """Exit with a one-line error if a two-segment flag lacks what it builds on; then set
    ``forward_selection.TWO_SEGMENT_FLIGHT`` (in this process, before any evaluator forks its workers)."""
    if args.two_segment and not late_given:
        ap.error(f"--two-segment needs {late_flag}")
    if args.two_segment_flight and not args.two_segment:
        ap.error("--two-segment-flight needs --two-segment")
    fs.TWO_SEGMENT_FLIGHT = args.two_segment_flight
