"""Snapshot ``hop-impedance analyze``'s JSON of every bundled recording, then check a refactor against it.

Issue 20 asks that a refactor change no number: "the analyze JSON of every
bundled recording identical before and after, except fields deliberately
unified, with every coefficient within 1e-9 relative". This runs the real
command (``hop_impedance.cli.main``, in this process) on every
``recordings/*.mcap`` with its default options, and on the real OpenCap drop
jump of ``../shared/data_candidates`` (when it is beside the repository),
imported by ``hop-impedance import`` lumped and ``--both-legs`` (analysed
``--per-leg``).

    .venv/bin/python bench/analyze_json_reference.py --save /tmp/analyze_ref   # before the change
    .venv/bin/python bench/analyze_json_reference.py --check /tmp/analyze_ref  # after

``--check`` walks both documents: keys and list lengths must be equal, strings
and booleans equal, numbers within ``--rtol`` relative (``|a - b| <= rtol *
max(|a|, |b|)``; NaN equals NaN). ``--ignore KEY`` (repeatable) skips a key
wherever it occurs (a field deliberately changed; list them in the commit).
Prints one line per recording with the number of numbers compared and the
largest relative difference; exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


OPENCAP = ROOT.parent / "shared" / "data_candidates" / "opencap_dropjump"


def _inputs(work: pathlib.Path) -> list[tuple[str, list[str]]]:
    """(name, analyze arguments) of every bundled recording, and the real drop jump imported lumped and per leg."""
    out = [(p.stem, [str(p)]) for p in sorted((ROOT / "recordings").glob("*.mcap"))]
    trc, mot = OPENCAP / "Subject4_DJ1_markers_trc.txt", OPENCAP / "Subject4_DJ1_grf_mot.txt"
    if trc.exists():
        for name, extra, analyze_extra in (("opencap_dj1_lumped", [], []),
                                           ("opencap_dj1_per_leg", ["--both-legs"], ["--per-leg"])):
            path = work / f"{name}.mcap"
            _cli(["import", "--trc", str(trc), "--mot", str(mot), "--mass-kg", "60", *extra, "--out", str(path)])
            out.append((name, [str(path), *analyze_extra]))
    return out


def _cli(argv: list[str]) -> None:
    from hop_impedance.cli.main import main

    with contextlib.redirect_stderr(io.StringIO()) as err, contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"hop-impedance {' '.join(argv)} exited {code}: {err.getvalue().strip()}")


def _analyze(args: list[str], out: pathlib.Path) -> dict:
    _cli(["analyze", *args, "--json", str(out)])
    return json.loads(out.read_text())


def _compare(a, b, path: str, ignore: set[str], rtol: float, stats: dict) -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        diffs = []
        if set(a) - ignore != set(b) - ignore:
            return [f"{path}: keys differ: {sorted(set(a) ^ set(b))}"]
        for k in a:
            if k not in ignore:
                diffs += _compare(a[k], b[k], f"{path}.{k}", ignore, rtol, stats)
        return diffs
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} != {len(b)}"]
        diffs = []
        for i, (x, y) in enumerate(zip(a, b)):
            diffs += _compare(x, y, f"{path}[{i}]", ignore, rtol, stats)
        return diffs
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and not isinstance(b, bool):
        stats["n"] += 1
        if isinstance(a, float) and math.isnan(a) and isinstance(b, float) and math.isnan(b):
            return []
        scale = max(abs(a), abs(b))
        rel = 0.0 if a == b else abs(a - b) / scale
        stats["max_rel"] = max(stats["max_rel"], rel)
        return [] if rel <= rtol else [f"{path}: {a!r} != {b!r} (relative {rel:.3g})"]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--save", metavar="DIR", help="write the reference JSON documents here")
    g.add_argument("--check", metavar="DIR", help="compare against the reference documents here")
    ap.add_argument("--rtol", type=float, default=1e-9, help="relative tolerance of numbers (default 1e-9)")
    ap.add_argument("--ignore", action="append", default=[], metavar="KEY", help="a key to skip wherever it occurs")
    args = ap.parse_args()
    ref = pathlib.Path(args.save or args.check)
    ref.mkdir(parents=True, exist_ok=True)
    failed = False
    work = ref / "imported"  # the same path at --save and --check: the JSON names its source
    work.mkdir(exist_ok=True)
    for name, analyze_args in _inputs(work):
        if args.save:
            doc = _analyze(analyze_args, ref / f"{name}.json")
            print(f"{name}: saved, {len(doc.get('stances', []))} stances")
            continue
        tmp = ref / f"{name}.check.json"
        doc = _analyze(analyze_args, tmp)
        tmp.unlink()
        stats = {"n": 0, "max_rel": 0.0}
        diffs = _compare(json.loads((ref / f"{name}.json").read_text()), doc, name, set(args.ignore), args.rtol, stats)
        failed |= bool(diffs)
        print(f"{name}: {'EQUAL' if not diffs else f'{len(diffs)} DIFFERENCES'}, {stats['n']} numbers, "
              f"largest relative difference {stats['max_rel']:.3g}")
        for d in diffs[:20]:
            print("   ", d)
    if args.check:
        print("ALL EQUAL" if not failed else "DIFFERENT")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
