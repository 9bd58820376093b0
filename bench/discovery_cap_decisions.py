"""Would ``forward_selection.LOG_RATIO_CAP`` change any decision of these discover documents? (session 16)

Reads discover documents written WITHOUT the cap (e.g. ``discovery_hit_rates.py --json-dir DIR`` with the default):
every test a run made is in them with its per-stance log ratios (``per_stance_log_gap_ratio``, rounded to 1e-4):
the screen of every round (admissible candidates with pooled shrink >= MIN_SHRINK) and the stiffness gate of every
candidate that reached it (shrink >= MIN_SHRINK). For each it computes the one-sided t-test's p without and with
the ratios clipped to +-``--cap`` and prints the tests whose decision at ALPHA / (the round's candidates) differs.
If none differs in a document, the run with the cap makes the same decisions step by step (each round's inputs are
the previous round's decisions), so its names are the document's: a replay, exact up to the ratios' rounding. A
document with a changed decision must be re-run with the cap (a candidate that newly passes the screen reaches a
gate never run). Session 15's ``bench/discovery_capped_t.py`` (the round-0 screen only) is folded into this bench
(session 16): its figures are this bench's round-0 lines (angle + offset p 0.0332 -> 0.000961).

Usage: .venv/bin/python bench/discovery_cap_decisions.py DOC.json [DOC.json ...] [--cap 2.3026]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from hop_impedance.discovery import forward_selection as fs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("docs", nargs="+")
    ap.add_argument("--cap", type=float, default=float(np.log(10.0)))
    args = ap.parse_args()
    fs.LOG_RATIO_CAP = args.cap  # what fs.capped clips to, in this process
    docs, tests, changed, changed_docs = 0, 0, 0, 0
    for path in args.docs:
        sel = json.loads(Path(path).read_text())["selection"]
        docs += 1
        checks = []
        for r, rnd in enumerate(sel["rounds"]):
            checks += [(r, "screen", e, c["per_stance_log_gap_ratio"],
                        c["physics"]["admissible"] and c["held_out_shrink"] >= fs.MIN_SHRINK) for e, c in rnd.items()]
        for g in sel["stiffness_through_simulation"]:
            checks += [(g["round"], "gate", e, c["per_stance_log_gap_ratio"], c["shrink_against_shot"] >= fs.MIN_SHRINK)
                       for e, c in g["candidates"].items()]
        here = 0
        for r, test, effect, ratios, relevant in checks:
            tests += 1
            level = fs.ALPHA / len(sel["rounds"][r])
            d = np.asarray(ratios, float)
            p_raw = fs.one_sided_t(d)
            p_cap = fs.one_sided_t(fs.capped(d))
            if relevant and (p_raw < level) != (p_cap < level):
                here += 1
                print(f"{Path(path).name}: round {r} {test} {effect}: p uncapped {p_raw:.3g}, capped {p_cap:.3g} "
                      f"(level {level:.4f})")
        changed += here
        changed_docs += here > 0
    print(f"{docs} documents, {tests} tests, {changed} decisions changed by the cap in {changed_docs} documents")


if __name__ == "__main__":
    main()
