"""The README's colcon instructions, run: a fresh workspace in a temp folder, colcon from PyPI
(requirements/test.txt) with the ROS 2 wheels of .venv standing in for a ROS 2 install.

The shell lines below are the ones README.md shows (the test fails if the README
drifts from them). colcon stops crawling at the repository root's package.xml, so
the three packages (hop_impedance, msg_defs/ = hop_impedance_msgs, mocap4r2_msgs/)
are given as --base-paths. After sourcing the install space the messages must
import from it, and every node's entry point must answer --help.
"""

import ast
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hop_impedance.child_env import child_env

ROOT = Path(__file__).resolve().parents[2]

#: Exactly as in README.md ("Using it inside a ROS 2 workspace (colcon)").
README_ENV = 'export AMENT_PREFIX_PATH="$VIRTUAL_ENV" CMAKE_PREFIX_PATH="$VIRTUAL_ENV"'
README_BUILD = ("colcon build --base-paths src/hop_impedance src/hop_impedance/msg_defs src/hop_impedance/mocap4r2_msgs"
                " --packages-up-to hop_impedance")
README_SOURCE = "source install/setup.bash"


def entry_modules() -> dict[str, str]:
    """setup.py's console_scripts (parsed, not imported): executable name -> module."""
    tree = ast.parse((ROOT / "setup.py").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            for k, v in zip(node.keys, node.values):
                if isinstance(k, ast.Constant) and k.value == "console_scripts":
                    pairs = [ast.literal_eval(e).split("=") for e in v.elts]
                    return {name.strip(): target.strip().split(":")[0] for name, target in pairs}
    raise AssertionError("setup.py has no console_scripts")


def console_scripts() -> list[str]:
    """Executable names of setup.py's console_scripts."""
    return list(entry_modules())


def test_readme_shows_the_commands_this_test_runs():
    readme = (ROOT / "README.md").read_text()
    for line in (README_ENV, README_BUILD, README_SOURCE):
        assert line in readme, f"README.md lacks: {line}"


@pytest.mark.slow
def test_fresh_colcon_workspace_builds_imports_and_runs_every_node(tmp_path):
    if shutil.which("colcon", path=str(Path(sys.executable).parent)) is None:
        pytest.fail("colcon is not in the venv: pip install -r requirements/test.txt")
    src = tmp_path / "ws" / "src" / "hop_impedance"
    src.mkdir(parents=True)
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                           capture_output=True, check=True).stdout.decode().split("\0")
    for f in filter(None, files):
        if (ROOT / f).is_file():
            (src / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, src / f)
    executables = console_scripts()
    checks = "\n".join(f"install/hop_impedance/lib/hop_impedance/{e} --help > help_{e}.txt" for e in executables)
    ws = tmp_path / "ws"
    build = f"set -euo pipefail\n{README_ENV}\n{README_BUILD}\n"
    check = f"""set -eo pipefail
{README_ENV}
{README_SOURCE}
python -c 'import hop_impedance, hop_impedance_msgs.msg as h, mocap4r2_msgs.msg as m; h.MarkerArray(); m.Markers()
print("modules", hop_impedance.__file__, h.__file__, m.__file__)'
{checks}
"""
    venv = Path(sys.prefix)
    env = child_env({"VIRTUAL_ENV": str(venv), "PATH": f"{venv / 'bin'}{os.pathsep}{os.environ['PATH']}"})
    for var in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "PYTHONPATH", "COLCON_PREFIX_PATH"):
        env.pop(var, None)
    t0 = time.monotonic()
    proc = subprocess.run(["bash", "-c", build], cwd=ws, env=env, capture_output=True, text=True, timeout=900)
    build_s = time.monotonic() - t0
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    assert "3 packages finished" in proc.stdout, proc.stdout[-2000:]
    proc = subprocess.run(["bash", "-c", check], cwd=ws, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    print(f"colcon build of 3 packages in a fresh workspace: {build_s:.1f} s; sourcing, imports and "
          f"{len(executables)} --help: {time.monotonic() - t0 - build_s:.1f} s")
    modules = next(line for line in proc.stdout.splitlines() if line.startswith("modules")).split()[1:]
    install = str(ws / "install")
    assert all(m.startswith(install) for m in modules), modules  # from the install space, not the venv
    for e in (e for e in executables if e != "hop-impedance"):  # the nodes print their module docstring
        text = (ws / f"help_{e}.txt").read_text()
        assert text.startswith(f"``{e}``"), f"{e} --help printed: {text[:200]!r}"
