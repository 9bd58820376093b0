"""Keep the Rerun viewer's usage analytics off in everything the project starts.

The viewer (and the ``rerun`` CLI) read ``analytics.json`` in the Rerun config
folder: ``$XDG_CONFIG_HOME/rerun`` when that variable is set, else
``~/.config/rerun`` (Linux). :func:`ensure_analytics_disabled` checks that file
and, when analytics are not disabled there, runs Rerun's own
``rerun analytics disable`` (the bundled CLI, through ``python -m rerun_cli``)
instead of writing the file by hand. No network traffic is involved.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path


def analytics_config_path() -> Path:
    """Path of Rerun's ``analytics.json`` for the current environment."""
    base = os.environ.get("XDG_CONFIG_HOME")
    root = Path(base) if base else Path.home() / ".config"
    return root / "rerun" / "analytics.json"


def analytics_disabled() -> bool:
    """True when ``analytics.json`` exists and says ``"analytics_enabled": false``."""
    path = analytics_config_path()
    try:
        return json.loads(path.read_text()).get("analytics_enabled") is False
    except (OSError, ValueError):
        return False


def ensure_analytics_disabled() -> Path:
    """Disable the viewer's usage analytics (idempotent); return the config path.

    Raises
    ------
    RuntimeError
        When ``rerun analytics disable`` did not leave a disabled config behind.
    """
    if not analytics_disabled():
        subprocess.run(
            [sys.executable, "-m", "rerun_cli", "analytics", "disable"],
            check=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=60,
        )
    if not analytics_disabled():
        raise RuntimeError(f"could not disable Rerun analytics: {analytics_config_path()} not written")
    return analytics_config_path()
