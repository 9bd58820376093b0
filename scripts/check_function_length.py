"""Issue 20: at most ``--max-long`` functions in the package longer than ``--lines`` lines, each with its reason.

A function's length is its ``def`` statement's span (``end_lineno - lineno + 1``:
signature, docstring and body; decorators not counted). A function allowed to be
longer must say why on the line(s) directly above its ``def`` (or its decorators),
in a comment starting ``# Longer than 60 lines because``. Run by ``make lint``:

    .venv/bin/python scripts/check_function_length.py hop_impedance

Prints every long function (reasoned or not); exits 1 when one has no reason or
there are more than ``--max-long``.
"""

from __future__ import annotations

import argparse
import ast
import pathlib
import sys

REASON = "# Longer than 60 lines because"


def long_functions(root: pathlib.Path, limit: int) -> list[tuple[pathlib.Path, int, str, int, bool]]:
    """(file, line, name, length, has_reason) of every function longer than ``limit`` lines below ``root``."""
    out = []
    for path in sorted(root.rglob("*.py")):
        lines = path.read_text().splitlines()
        for node in ast.walk(ast.parse("\n".join(lines), str(path))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            length = node.end_lineno - node.lineno + 1
            if length <= limit:
                continue
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            above = first - 2  # index of the line above the def / decorators
            reasoned = False
            while above >= 0 and lines[above].lstrip().startswith("#"):
                reasoned |= lines[above].lstrip().startswith(REASON)
                above -= 1
            out.append((path, node.lineno, node.name, length, reasoned))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", type=pathlib.Path, help="package folder")
    parser.add_argument("--lines", type=int, default=60, help="longest function without a reason (default 60)")
    parser.add_argument("--max-long", type=int, default=3, help="most functions allowed above --lines (default 3)")
    args = parser.parse_args()
    found = long_functions(args.root, args.lines)
    for path, line, name, length, reasoned in found:
        print(f"{path}:{line}: {name} is {length} lines" + ("" if reasoned else f" (no '{REASON} ...' comment above it)"))
    bad = [f for f in found if not f[4]]
    if bad or len(found) > args.max_long:
        print(f"{len(found)} functions over {args.lines} lines ({len(bad)} without a reason); at most {args.max_long} "
              "allowed, each with its reason (issue 20)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
