"""scripts/check_function_length.py, the issue-20 rule `make lint` enforces: at most 3 functions over 60 lines in
the package, each with its reason written above it. Checked on scratch files of known lengths, then on the package."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "check_function_length.py"


def _function(name: str, lines: int, reason: str = "") -> str:
    """Source of a function exactly ``lines`` lines long (def line included), with an optional comment above it."""
    body = "".join(f"    x{i} = {i}\n" for i in range(lines - 2))
    return (f"# {reason}\n" if reason else "") + f"def {name}():\n{body}    return 0\n\n\n"


def _check(tmp_path, source: str, *args: str) -> subprocess.CompletedProcess:
    pkg = tmp_path / "pkg"
    pkg.mkdir(exist_ok=True)
    (pkg / "mod.py").write_text(source)
    return subprocess.run([sys.executable, str(SCRIPT), str(pkg), *args], capture_output=True, text=True, timeout=60)


def test_sixty_lines_pass_sixty_one_need_a_reason(tmp_path):
    assert _check(tmp_path, _function("ok", 60)).returncode == 0
    run = _check(tmp_path, _function("long", 61))
    assert run.returncode == 1 and "mod.py:1: long is 61 lines (no '# Longer than 60 lines because" in run.stdout
    reasoned = _function("long", 61, "Longer than 60 lines because an integrator's loop reads best whole")
    run = _check(tmp_path, reasoned)
    assert run.returncode == 0 and "long is 61 lines" in run.stdout and "no '#" not in run.stdout


def test_at_most_three_even_with_reasons(tmp_path):
    reason = "Longer than 60 lines because of a test"
    three = "".join(_function(f"f{i}", 70, reason) for i in range(3))
    assert _check(tmp_path, three).returncode == 0
    run = _check(tmp_path, three + _function("f3", 70, reason))
    assert run.returncode == 1 and "4 functions over 60 lines" in run.stderr


def test_the_package_holds_to_it():
    run = subprocess.run([sys.executable, str(SCRIPT), str(ROOT / "hop_impedance")], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
