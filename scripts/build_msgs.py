#!/usr/bin/env python3
"""Generate and compile the interface packages (``hop_impedance_msgs``, ``mocap4r2_msgs``) into the venv.

Uses the PyPI ROS 2 wheels (ament_cmake, rosidl generators) with Debian's cmake
and g++. Installed into the virtual environment's prefix, so nothing needs to be
sourced at run time: ``from hop_impedance_msgs.msg import MarkerArray`` works in
rclpy. ``mocap4r2_msgs`` (``mocap4r2_msgs/``) is the Markers/Marker part of the
MOCAP4ROS2 drivers' package, rebuilt so the mocap4r2 adapter node can subscribe.

Two things make this work with the wheels (see shared/notes/ROS2_FROM_PYPI.md):

1. Some ``*Export.cmake`` files of the wheels name the wheel builder's Python
   and numpy include directories (``/opt/python/...``); cmake refuses
   non-existent include paths, so they are rewritten to this interpreter's.
2. ``AMENT_PREFIX_PATH`` and ``CMAKE_PREFIX_PATH`` point at the venv prefix.

Each package's build is skipped when its .msg files, CMakeLists.txt and
package.xml are unchanged since its last successful build (a hash stamp in
its build folder).

Usage: ``.venv/bin/python scripts/build_msgs.py [--force]``
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import subprocess
import sys
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: Interface packages: name -> source folder (built in this order; each into build/<name>).
PACKAGES = {"hop_impedance_msgs": ROOT / "msg_defs", "mocap4r2_msgs": ROOT / "mocap4r2_msgs"}
WHEEL_BUILDER_PATH = re.compile(
    r"/opt/python/cp3\d+-cp3\d+/(include/python3\.\d+|lib/python3\.\d+/site-packages/numpy/_core/include)")


def source_hash(pkg_dir: Path) -> str:
    """Hash of everything that defines the generated package."""
    h = hashlib.sha256()
    files = sorted(pkg_dir.glob("msg/*.msg")) + [pkg_dir / "CMakeLists.txt", pkg_dir / "package.xml"]
    for f in files:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    h.update(sys.prefix.encode())
    return h.hexdigest()


def fix_wheel_cmake_paths(prefix: Path) -> int:
    """Rewrite the wheel builder's include paths in the prefix's cmake files; returns files changed."""
    import numpy

    python_include = sysconfig.get_paths()["include"]
    numpy_include = numpy.get_include()

    def replace(match: re.Match) -> str:
        return python_include if match.group(1).startswith("include") else numpy_include

    changed = 0
    for path in (prefix / "share").glob("*/cmake/*.cmake"):
        text = path.read_text(encoding="utf-8", errors="surrogateescape")
        new = WHEEL_BUILDER_PATH.sub(replace, text)
        if new != text:
            path.write_text(new, encoding="utf-8", errors="surrogateescape")
            changed += 1
    return changed


def run(cmd: list[str], env: dict[str, str], build_dir: Path) -> None:
    """Run a build step; its output goes to build/<package>/build.log, shown on failure."""
    log = build_dir / "build.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, "a", encoding="utf-8") as fh:
        fh.write("+ " + " ".join(cmd) + "\n")
        fh.flush()
        proc = subprocess.run(cmd, env=env, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        tail = log.read_text(encoding="utf-8", errors="replace").splitlines()[-40:]
        print("\n".join(tail), file=sys.stderr)
        raise SystemExit(f"build_msgs: '{cmd[0]} {cmd[1]}' failed (exit {proc.returncode}); full log: {log}")


def build(prefix: Path, pkg_dir: Path, build_dir: Path) -> None:
    env = dict(os.environ)
    env["AMENT_PREFIX_PATH"] = str(prefix)
    env["CMAKE_PREFIX_PATH"] = str(prefix)
    jobs = str(max(1, os.cpu_count() or 1))
    run(
        [
            "cmake", "-S", str(pkg_dir), "-B", str(build_dir),
            f"-DCMAKE_PREFIX_PATH={prefix}",
            f"-DCMAKE_INSTALL_PREFIX={prefix}",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DCMAKE_BUILD_TYPE=Release",
            "-DBUILD_TESTING=OFF",
        ],
        env,
        build_dir,
    )
    run(["cmake", "--build", str(build_dir), "-j", jobs], env, build_dir)
    run(["cmake", "--install", str(build_dir)], env, build_dir)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="rebuild even if nothing changed")
    args = parser.parse_args()
    prefix = Path(sys.prefix)
    if prefix == Path(sys.base_prefix):
        print("build_msgs: run this with the project's virtual environment's python", file=sys.stderr)
        return 2
    fixed = False
    for name, pkg_dir in PACKAGES.items():
        build_dir = ROOT / "build" / name
        stamp = build_dir / ".source_hash"
        digest = source_hash(pkg_dir)
        # The stamp says the sources were built; the package must also still be installed in this environment (a
        # venv made again beside an old build/ has none: "up to date" then left `make demo` without its messages).
        installed = (prefix / "share" / name / "package.xml").exists()
        if not args.force and installed and stamp.exists() and stamp.read_text() == digest:
            print(f"{name}: up to date")
            continue
        if not fixed:
            n = fix_wheel_cmake_paths(prefix)
            if n:
                print(f"build_msgs: fixed wheel include paths in {n} cmake file(s)")
            fixed = True
        print(f"{name}: generating and compiling (cmake + g++, about 20-60 s) ...", flush=True)
        build(prefix, pkg_dir, build_dir)
        stamp.write_text(digest)
        print(f"{name}: built and installed into", prefix)
    return 0


if __name__ == "__main__":
    sys.exit(main())
