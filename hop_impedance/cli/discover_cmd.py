"""``hop-impedance discover REC.mcap --json OUT.json [--report DIR] [--rrd OUT.rrd]``.

Names the effect(s) the baseline spring-leg model misses in a recording
(issue 8). The JSON schema is documented in docs/discovery.md.
"""

from __future__ import annotations

from hop_impedance.cli.conventions import OptionDefault, add_rrd_argument


def register(subparsers) -> None:
    """Add the ``discover`` parser."""
    p = subparsers.add_parser(
        "discover",
        help="name the effect a simulation misses, add it, show the gap shrink",
        description="Compare a recording with the baseline model (constant joint stiffness, rigid ground, "
                    "streams in sync, no damping, no active moment), add the effects that shrink the held-out "
                    "gap significantly, and report them.",
    )
    p.add_argument("recording", help="contract recording (MCAP)")
    p.add_argument("--json", required=True, metavar="OUT", help="output JSON file ('-' for stdout)")
    p.add_argument("--report", metavar="DIR", help="write PNG figures (gap per step, residuals) into DIR")
    add_rrd_argument(p, "write a Rerun recording of the measured and simulated stances", old=("--rerun",))
    p.add_argument("--max-steps", type=int, default=OptionDefault("hop_impedance.discovery.workflow:discover", "max_steps"),
                   help="most effects added (default %(default)s)")
    p.add_argument("--indent", type=int, default=2, help="JSON indent (default 2)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Load, discover, write JSON (and figures / Rerun when asked)."""
    import json
    import sys

    from hop_impedance.cli.json_output import json_output
    from hop_impedance.discovery.report import to_json_ready
    from hop_impedance.discovery.workflow import discover
    from hop_impedance.io.recording_io import load_recording

    rec = load_recording(args.recording, require_markers=True)
    with json_output(args.json) as write_json:
        doc = discover(rec, max_steps=args.max_steps)
        doc["recording"] = str(args.recording)
        write_json(json.dumps(to_json_ready(doc), indent=args.indent, allow_nan=False))
    if args.report:
        from hop_impedance.discovery.report import write_figures

        write_figures(doc, args.report)
    if args.rrd:
        from hop_impedance.discovery.rerun_report import write_rrd

        write_rrd(rec, doc, args.rrd)
    found = ", ".join(doc["effects_found"]) or "none"
    print(f"effects found: {found}", file=sys.stderr)
    return 0
