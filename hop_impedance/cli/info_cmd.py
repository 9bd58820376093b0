"""``hop-impedance info REC.mcap``: what a recording holds."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "info",
        help="list a recording's topics, counts, rates and time span",
        description="List the topics of an MCAP recording with message counts, rates and time span, "
        "and check the contract's inputs (force plate, markers, subject).",
    )
    p.add_argument("recording", help="MCAP file or rosbag2 folder")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hop_impedance.io.mcap_io import summarize
    from hop_impedance.io.recording_io import load_recording

    infos = summarize(args.recording)
    width = max([len(i.topic) for i in infos] + [5])
    print(f"{'topic':<{width}}  {'type':<40} {'count':>8} {'rate Hz':>9} {'span s':>8}")
    for i in infos:
        print(f"{i.topic:<{width}}  {i.schema_name:<40} {i.count:>8} {i.rate_hz:>9.1f} {(i.last_ns - i.first_ns) * 1e-9:>8.3f}")
    rec = load_recording(args.recording)
    if rec.subject:
        s = rec.subject
        print(f"subject: {s.subject_id}, {s.body_mass_kg:.1f} kg, {s.body_height_m:.2f} m")
    for w in rec.warnings:
        print(f"warning: {w}")
    return 0
