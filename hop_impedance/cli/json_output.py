"""Where a command's JSON document goes: a file, or stdout kept free of anything else.

``--json -`` puts the document on stdout for a pipe (``... --json - | jq``).
Libraries may write to file descriptor 1 as well: OSQP 1.1's C polish prints
"Polishing not needed - no active set detected at optimal point" whatever its
``verbose`` setting (the fit avoids it where it can, not in every case), and
any ``print`` would do the same. One such line ahead of the document makes it
unparseable. So while the command runs, descriptor 1 points at stderr, and
only the document itself goes to the real stdout.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path


@contextlib.contextmanager
def json_output(path: str) -> Iterator[Callable[[str], None]]:
    """Yield ``write(text)`` for the command's JSON text; ``path`` ``-`` means stdout.

    For a file, the file is written only when ``write`` is called (a command
    that fails earlier leaves no empty file). For ``-``, everything written to
    file descriptor 1 inside the block (C libraries, ``print``) goes to stderr
    instead, and ``write`` writes to the original stdout.
    """
    if path != "-":

        def write_file(text: str) -> None:
            Path(path).write_text(text + "\n", encoding="utf-8")

        yield write_file
        return
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:

        def write(text: str) -> None:
            with os.fdopen(os.dup(saved), "w", encoding="utf-8") as stdout:
                stdout.write(text + "\n")

        with contextlib.redirect_stdout(sys.stderr):  # Python-level writes, also where sys.stdout is not fd 1
            yield write
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
