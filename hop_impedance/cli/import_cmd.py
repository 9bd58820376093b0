"""``hop-impedance import``: a lab session (C3D, OpenSim TRC/MOT, force-only text) to a contract recording.

Examples::

    hop-impedance import SESSION.c3d --out REC.mcap
    hop-impedance import --trc MARKERS.trc --mot GRF.mot --mass-kg 60 --out REC.mcap
    hop-impedance import --force-txt jump1.txt --out REC.mcap
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HELP = "import a C3D, OpenSim TRC/MOT or force-only text session as a contract recording"


def _mass(text: str) -> float | str:
    if text == "auto":
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--mass-kg wants kilograms or 'auto', got {text!r}") from None


def _plates(text: str) -> list[int]:
    try:
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--plates wants 0-based numbers like 0,1, got {text!r}") from None


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``import`` sub-command."""
    p = subparsers.add_parser("import", help=HELP, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("session", nargs="?", type=Path, default=None, help="C3D file (markers + force plates)")
    p.add_argument("--trc", type=Path, default=None, help="OpenSim TRC marker file (with --mot)")
    p.add_argument("--mot", type=Path, default=None, help="OpenSim MOT ground-reaction-force file")
    p.add_argument("--force-txt", type=Path, default=None, help="force-only text file: time and vertical GRF columns")
    p.add_argument("--out", type=Path, required=True, help="output contract recording (.mcap)")
    p.add_argument(
        "--markers",
        default=None,
        help="marker mapping: shipped name (opencap_right, opencap_left, plugin_gait_right, plugin_gait_left, "
        "qualisys_isb_right, qualisys_isb_left, contract) or a YAML file (virtual markers: docs/importing.md); "
        "default: the first shipped mapping whose six markers are all present",
    )
    p.add_argument("--both-legs", action="store_true",
                   help="contract v2 (docs/contract_v2.md): keep each foot's plate and the left leg too "
                        "(--markers names the right-leg map; its _left twin is used for the left leg)")
    p.add_argument("--up", default=None, help="lab axis pointing up, e.g. +Z or +Y (default: from the file / detected)")
    p.add_argument(
        "--forward", default=None, help="lab axis the subject faces, e.g. +X or --forward=-Y (default: detected from the markers)"
    )
    p.add_argument("--mass-kg", type=_mass, default=None, help="body mass (kg), or 'auto' (quiet standing on the plates)")
    p.add_argument("--height-m", type=float, default=None, help="body height (m) (default: file, else leg markers)")
    p.add_argument("--sex", choices=("female", "male"), default="female", help="de Leva table (default female)")
    p.add_argument("--plates", type=_plates, default=None, help="0-based plates to sum, e.g. 0,1 (default: all)")
    p.add_argument("--rate-hz", type=float, default=None, help="sampling rate of a one-column --force-txt file")
    p.set_defaults(func=run)


def import_from_args(args: argparse.Namespace):
    """The Recording the arguments describe (no file written).

    Raises
    ------
    ValueError
        Conflicting or missing inputs, and every import error (named markers,
        no plate, rates, mass).
    """
    sources = [x for x in (args.session, args.mot, args.force_txt) if x is not None]
    if len(sources) != 1:
        raise ValueError("give exactly one input: SESSION.c3d, or --trc/--mot, or --force-txt")
    if args.trc is not None and args.mot is None:
        raise ValueError("--trc needs --mot (the ground reaction forces)")
    options = dict(up=args.up, forward=args.forward, mass_kg=args.mass_kg, height_m=args.height_m, sex=args.sex)
    if args.force_txt is not None:
        from hop_impedance.importers.force_only_import import import_force_only

        mass = None if args.mass_kg == "auto" else args.mass_kg
        return import_force_only(args.force_txt, mass_kg=mass, height_m=args.height_m, rate_hz=args.rate_hz, sex=args.sex)
    if getattr(args, "both_legs", False):
        from hop_impedance.importers.bilateral_import import import_c3d_bilateral, import_opensim_bilateral

        if args.mot is not None:
            if args.trc is None:
                raise ValueError("--both-legs needs markers (--trc) to tell the feet's plates apart")
            return import_opensim_bilateral(args.trc, args.mot, args.markers, plates=args.plates, **options)
        if args.session is None:
            raise ValueError("--both-legs needs markers and plates: a .c3d session or --trc/--mot")
        return import_c3d_bilateral(args.session, args.markers, plates=args.plates, **options)
    if args.mot is not None:
        from hop_impedance.importers.opensim_import import import_opensim

        return import_opensim(args.trc, args.mot, args.markers, plates=args.plates, **options)
    if args.session.suffix.lower() != ".c3d":
        raise ValueError(f"{args.session}: expected a .c3d file (use --trc/--mot or --force-txt for text files)")
    from hop_impedance.importers.c3d_import import import_c3d

    return import_c3d(args.session, args.markers, plates=args.plates, **options)


def summary(recording) -> list[str]:
    """One-line descriptions of what was imported."""
    import numpy as np

    f = recording.force
    lines = [f"force: {len(f)} samples at {1e9 / np.median(np.diff(f.stamp_ns)):.0f} Hz, peak Fz {f.force_n[:, 2].max():.0f} N"]
    if recording.markers is not None:
        m = recording.markers
        lines.append(f"markers: {len(m)} frames at {1e9 / np.median(np.diff(m.stamp_ns)):.0f} Hz ({', '.join(m.names)})")
    s = recording.subject
    lines.append(f"subject: {s.subject_id}, {s.body_mass_kg:.1f} kg, {s.body_height_m:.2f} m")
    return lines + [f"note: {w}" for w in recording.warnings]


def run(args: argparse.Namespace) -> int:
    """Import, write the recording, print what was done; errors become one line (exit 2)."""
    recording = import_from_args(args)
    from hop_impedance.bilateral import BilateralRecording, save_bilateral
    from hop_impedance.io.recording_io import save_recording

    if isinstance(recording, BilateralRecording):
        save_bilateral(args.out, recording)
        recording = recording.recording
    else:
        save_recording(args.out, recording)
    for line in summary(recording):
        print(line)
    print(f"wrote {args.out}")
    sys.stdout.flush()
    return 0
