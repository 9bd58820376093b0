"""Map ``pkg/msg/Type`` names (as in MCAP schemas) to rclpy message classes."""

from __future__ import annotations

import importlib


def message_class(type_name: str):
    """``'geometry_msgs/msg/WrenchStamped'`` -> the generated Python class.

    Raises ValueError naming the type when its Python package is not installed.
    """
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    package, kind, name = parts
    try:
        module = importlib.import_module(f"{package}.{kind}")
        return getattr(module, name)
    except (ImportError, AttributeError):
        raise ValueError(f"message type {type_name!r} is not available in this ROS 2 environment") from None
