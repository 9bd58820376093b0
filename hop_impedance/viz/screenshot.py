"""Deterministic screenshot of an .rrd in the headless viewer (no GPU needed).

Runs the real viewer binary shipped with rerun-sdk (``rerun_cli/rerun``)
headless through :class:`rerun.experimental.ViewerClient`, opens the file,
waits for it to load, pauses the time cursor at a chosen time and saves a PNG.
Rendering uses Vulkan; on a machine without a GPU that is Mesa's CPU driver
(Debian ``mesa-vulkan-drivers``, installed by ``scripts/screenshot.sh``). The
viewer listens on loopback only. Usage analytics are disabled first.

Usage: ``python -m hop_impedance.viz.screenshot IN.rrd OUT.png [--time-s T]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from hop_impedance.viz.analytics import ensure_analytics_disabled
from hop_impedance.viz.style import TIMELINE


def viewer_executable() -> str:
    """Path of the real viewer binary inside the installed ``rerun_cli`` package."""
    import rerun_cli

    path = Path(rerun_cli.__file__).with_name("rerun")
    if not path.exists():
        raise FileNotFoundError(f"{path}: rerun viewer binary not found (is rerun-sdk installed?)")
    return str(path)


def save_screenshot(rrd_path: str | Path, png_path: str | Path, time_s: float, settle_s: float = 4.0, port: int = 9877) -> Path:
    """Open ``rrd_path`` in a headless viewer, pause at ``time_s`` and save ``png_path``.

    Parameters
    ----------
    rrd_path, png_path : str or Path
    time_s : float
        Time cursor on the ``time`` timeline (s since the recording's start).
    settle_s : float
        Wait after opening and after moving the cursor, for loading and painting (s).
    port : int
        Loopback port of the spawned viewer.

    Returns
    -------
    Path
        The PNG written.
    """
    from rerun.experimental import ViewerClient

    ensure_analytics_disabled()
    rrd, png = Path(rrd_path).resolve(), Path(png_path).resolve()
    if not rrd.exists():
        raise FileNotFoundError(f"{rrd}: no such .rrd")
    png.parent.mkdir(parents=True, exist_ok=True)
    client = ViewerClient.spawn(headless=True, port=port, hide_welcome_screen=True, executable_path=viewer_executable())
    try:
        client.open(str(rrd))
        time.sleep(settle_s)
        client.set_time(TIMELINE, duration=float(time_s), play_state="paused")
        time.sleep(settle_s)
        client.save_screenshot(str(png))
    finally:
        client.quit()
    return png


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``IN.rrd OUT.png [--time-s T]``."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("rrd")
    p.add_argument("png")
    p.add_argument("--time-s", type=float, default=2.35, help="time cursor (s) [2.35]")
    p.add_argument("--port", type=int, default=9877, help="loopback port of the headless viewer [9877]")
    args = p.parse_args(argv)
    print(save_screenshot(args.rrd, args.png, args.time_s, port=args.port))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
