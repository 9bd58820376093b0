"""Stances ``hop-impedance analyze`` finds in the outside generator's recordings, against their truth.

For every ``../shared/foreign/*.mcap`` (or the folder given): runs
``hop-impedance analyze --no-fit`` and prints the truth's hop count
(``per_hop``), the stances found, those accepted (no rejection reason), how
many truth touchdowns (``per_hop[].t_td_ns``) have a found touchdown within
10 ms, and the largest |found - true| touchdown difference (ms).

    .venv/bin/python bench/foreign_stances.py [FOLDER]
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else REPO.parent / "shared" / "foreign"
    with tempfile.TemporaryDirectory() as tmp:
        for mcap in sorted(folder.glob("*.mcap")):
            truth = json.loads(mcap.with_suffix(".truth.json").read_text())
            out = Path(tmp) / "analyze.json"
            cmd = [sys.executable, "-m", "hop_impedance.cli", "analyze", "--no-fit", str(mcap), "--json", str(out)]
            run = subprocess.run(cmd, capture_output=True, text=True)
            if run.returncode:
                print(f"{mcap.name:72s} analyze failed: {run.stderr.strip().splitlines()[-1]}")
                continue
            stances = json.loads(out.read_text())["stances"]
            found = np.array([s["touchdown_stamp_ns"] for s in stances])
            true = np.array([h["t_td_ns"] for h in truth["per_hop"]])
            diff_ms = np.array([np.min(np.abs(found - t)) * 1e-6 if found.size else np.inf for t in true])
            accepted = sum(s["rejection_reason"] is None for s in stances)
            print(f"{mcap.name:72s} truth {true.size} found {len(stances)} accepted {accepted} "
                  f"matched within 10 ms {int(np.sum(diff_ms <= 10))} max |d touchdown| {diff_ms.max():.2f} ms")


if __name__ == "__main__":
    main()
