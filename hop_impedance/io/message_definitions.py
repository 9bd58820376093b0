"""ROS 2 message definition texts for MCAP schemas, found on disk, never hand-copied.

rosbag2 stores each channel's schema as ``ros2msg`` text: the type's own
``.msg`` file followed by every type it depends on, each introduced by a line
of ``=`` and ``MSG: pkg/Type``. This module builds that text from the ``.msg``
files that the ROS 2 wheels install under ``<prefix>/share/<pkg>/msg/`` and
from this repository's ``msg_defs/msg/`` (for ``hop_impedance_msgs``), so a
recording we write can be decoded by any rosbag2-compatible reader.
"""

from __future__ import annotations

import os
import re
import sys
from functools import cache
from pathlib import Path

_REPO_MSG_DIR = Path(__file__).resolve().parents[2] / "msg_defs" / "msg"
_OWN_PACKAGE = "hop_impedance_msgs"
_PRIMITIVES = {
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring",
}
_SEPARATOR = "=" * 80


class UnknownMessageType(ValueError):
    """No ``.msg`` file was found for a message type."""

    def __init__(self, type_name: str, searched: list[Path]):
        places = ", ".join(str(p) for p in searched) or "(nowhere)"
        super().__init__(f"no message definition for {type_name!r}; searched {places}")


def normalize_type_name(type_name: str) -> tuple[str, str]:
    """``'geometry_msgs/msg/Point'`` or ``'geometry_msgs/Point'`` -> ``('geometry_msgs', 'Point')``."""
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "msg":
        return parts[0], parts[2]
    if len(parts) == 2:
        return parts[0], parts[1]
    raise ValueError(f"message type must look like 'pkg/msg/Type', got {type_name!r}")


def _search_dirs(package: str) -> list[Path]:
    dirs = []
    if package == _OWN_PACKAGE:
        dirs.append(_REPO_MSG_DIR)
    prefixes = [sys.prefix] + [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    dirs += [Path(p) / "share" / package / "msg" for p in prefixes]
    return dirs


@cache
def msg_file_text(type_name: str) -> str:
    """The ``.msg`` text of one type (comments kept, as rosbag2 does)."""
    package, name = normalize_type_name(type_name)
    searched = _search_dirs(package)
    for d in searched:
        path = d / f"{name}.msg"
        if path.is_file():
            return path.read_text(encoding="utf-8")
    raise UnknownMessageType(type_name, searched)


def _field_types(text: str, package: str) -> list[str]:
    """Complex field types (``pkg/Type``) referenced by a ``.msg`` text."""
    found = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        tokens = line.split()
        if len(tokens) < 2:
            continue
        if "=" in tokens[1] or (len(tokens) > 2 and tokens[2].startswith("=")):
            continue  # a constant
        base = re.sub(r"(\[[^\]]*\]|<=\d+)+$", "", tokens[0])
        base = re.sub(r"<=\d+$", "", base)
        if base in _PRIMITIVES:
            continue
        if base == "Header":
            base = "std_msgs/Header"
        elif "/" not in base:
            base = f"{package}/{base}"
        found.append(base)
    return found


@cache
def full_definition(type_name: str) -> str:
    """rosbag2-style ``ros2msg`` schema text: the type plus all dependencies, depth first."""
    package, name = normalize_type_name(type_name)
    root = f"{package}/{name}"
    order: list[str] = []
    stack = list(reversed(_field_types(msg_file_text(root), package)))
    seen = {root}
    while stack:
        dep = stack.pop()
        if dep in seen:
            continue
        seen.add(dep)
        order.append(dep)
        dep_pkg, _ = normalize_type_name(dep)
        stack.extend(reversed(_field_types(msg_file_text(dep), dep_pkg)))
    parts = [msg_file_text(root).rstrip("\n")]
    for dep in order:
        parts.append(f"{_SEPARATOR}\nMSG: {dep}\n{msg_file_text(dep).rstrip(chr(10))}")
    return "\n".join(parts) + "\n"


def schema_name(type_name: str) -> str:
    """Schema name as rosbag2 writes it: ``pkg/msg/Type``."""
    package, name = normalize_type_name(type_name)
    return f"{package}/msg/{name}"
