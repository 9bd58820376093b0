"""The bundled recordings against their truth files: inverse-dynamics error and event offsets, per recording.

For each recording (default: the three Table 1 trials in recordings/), analysed as ``hop-impedance analyze`` does
(12 Hz), every truth stance is matched with the nearest detected touchdown and printed: the worst RMS error of the
analysed joint moment over the middle 80 % of the truth's stance, as a share of that joint's peak true moment (ankle,
knee, hip; test/biomech/test_analysis.py bounds it), and the detected minus the true touchdown and take-off (ms; on the
seed-like hopper's shoe pad the plate's force crosses the detector's level after the contact begins and before it
ends).

Usage::

    nice -n 19 .venv/bin/python bench/simulator_recordings_id.py [REC.mcap ...]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.io.recording_io import load_recording

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = [ROOT / "recordings" / f"sim_{f}hz_hard.mcap" for f in ("1p53", "1p87", "2p20")]


def recording_lines(path: Path) -> str:
    """One line: worst RMS share per joint and the event offsets of every stance."""
    truth = json.loads(path.with_name(path.name.replace(".mcap", ".truth.json")).read_text())
    analysed = [s for s in analyze_recording(load_recording(path)).stances if s.joints is not None]
    worst, touchdown, takeoff = np.zeros(3), [], []
    for ts in truth["stances"]:
        s = min(analysed, key=lambda s: abs(s.touchdown_s - ts["touchdown_s"]))
        touchdown.append(s.touchdown_s - ts["touchdown_s"])
        takeoff.append(s.takeoff_s - ts["takeoff_s"])
        t = np.asarray(ts["samples"]["t_s"]) - ts["touchdown_s"]
        true_m = np.asarray(ts["samples"]["moments_nm"])
        mid = slice(int(0.1 * len(t)), int(0.9 * len(t)))
        for j in range(3):
            m = np.interp(t, s.joints.time_s, s.joints.moment_nm[:, j])
            rms = np.sqrt(np.mean((m[mid] - true_m[mid, j]) ** 2))
            worst[j] = max(worst[j], rms / np.max(np.abs(true_m[:, j])))
    ms = 1000 * np.array([touchdown, takeoff])
    return (f"{path.name}: worst RMS / peak ankle {100 * worst[0]:.2f} %, knee {100 * worst[1]:.2f} %, hip "
            f"{100 * worst[2]:.2f} %; detected - true touchdown {ms[0].min():+.1f}..{ms[0].max():+.1f} ms, take-off "
            f"{ms[1].min():+.1f}..{ms[1].max():+.1f} ms ({len(truth['stances'])} stances)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="*", type=Path, default=DEFAULT)
    for path in parser.parse_args().recordings:
        print(recording_lines(path), flush=True)


if __name__ == "__main__":
    main()
