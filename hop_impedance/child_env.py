"""Environment for child processes that may start rclpy.

Two things go wrong with a plain copy of ``os.environ``:

- ``ros-wheels-bootstrapper`` (installed with the ROS 2 wheels) re-executes
  the interpreter once with ``LD_LIBRARY_PATH`` pointing at the wheels'
  libraries and marks that with ``_ROS_WHEELS_BOOTSTRAP_COMPLETE``. If
  anything in the parent changed ``LD_LIBRARY_PATH`` since (importing
  ``opensim`` overwrites it with ``PATH``), a child that inherits the marker
  skips the bootstrap and cannot load ``librcl*.so``. Dropping the marker lets
  the child bootstrap itself.
- The network rule: DDS discovery stays on this machine unless the caller
  explicitly set another range.
"""

from __future__ import annotations

import os

BOOTSTRAP_MARKER = "_ROS_WHEELS_BOOTSTRAP_COMPLETE"


def child_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """A copy of ``os.environ`` safe for spawning Python processes that use rclpy."""
    env = dict(os.environ)
    env.pop(BOOTSTRAP_MARKER, None)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if extra:
        env.update(extra)
    return env
