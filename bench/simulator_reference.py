"""Snapshot what the simulators produce, then check a refactor against it bit for bit.

``bench/analyze_json_reference.py`` checks the analysis of the bundled
recordings but never runs a simulator. A refactor of ``simulation/`` or
``validation/`` (issue 20) must leave every simulated number unchanged, so this
re-runs them and compares exactly (no tolerance: the same floating-point
operations in the same order give the same bits):

- every bundled recording, regenerated the way ``recordings/regenerate.sh``
  does (``hop-impedance simulate`` in a subprocess, into a temporary folder):
  the MCAP messages (topic, schema, log/publish time, sequence, payload
  bytes, read with the ``mcap`` reader, since a file header may carry library
  metadata) and the truth JSON;
- ``simulate_recording`` with issue 17's seed-like options and the
  energy-keeping flight (the calibration's fixed-point rounds, trunk balance,
  contact ahead of the toe);
- ``simulate_stance_set_recording`` (discovery's stance sets) with the default
  magnitudes on two surfaces, and with explicit ``EffectSizes``, every effect
  and a re-draw allowance;
- ``strict_recording`` (issue 16's strict family) with an angle-dependent
  stiffness, a plate offset and marker latency;
- ``recover_trial`` (issue 5's coefficient recovery) noisy, and noise-free with
  edges left out and the first stance skipped; ``recover_legs`` (issue 21's
  per-leg recovery, with the lumped one).

    .venv/bin/python bench/simulator_reference.py --save /tmp/simref/before   # before the change
    .venv/bin/python bench/simulator_reference.py --check /tmp/simref/before  # after

Each case is pickled as a canonical tree (dataclasses and objects as their
fields, arrays as dtype + shape + bytes, floats as ``float.hex``). ``--check``
prints one line per case (``equal`` or the first differing path) and exits 1
on any difference; ``--only NAME`` (repeatable) runs some cases.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import pathlib
import pickle
import shlex
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _bundled_commands() -> dict[str, list[str]]:
    """Recording stem -> ``hop-impedance simulate`` arguments, read from recordings/regenerate.sh."""
    out = {}
    text = (ROOT / "recordings" / "regenerate.sh").read_text().replace("\\\n", " ")
    for line in text.splitlines():
        if line.startswith("sim --"):
            argv = shlex.split(line)[1:]
            i = argv.index("--out")
            argv[i + 1] = pathlib.Path(argv[i + 1].replace('"', "").replace("$HERE/", "")).name
            out[pathlib.Path(argv[i + 1]).stem] = argv
    return out


def _mcap_messages(path: pathlib.Path) -> list:
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        return [(ch.topic, sch.name if sch else None, msg.log_time, msg.publish_time, msg.sequence, msg.data)
                for sch, ch, msg in make_reader(f).iter_messages(log_time_order=False)]


def _bundled(argv: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "hop_impedance.cli", "simulate", *argv]
        env = {**os.environ, "PYTHONPATH": str(ROOT), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
        subprocess.run(cmd, cwd=tmp, check=True, capture_output=True, env=env)
        out = pathlib.Path(tmp) / argv[argv.index("--out") + 1]
        truth = json.loads(out.with_suffix("").with_suffix(".truth.json").read_text())
        return {"messages": _mcap_messages(out), "truth": truth}


def _seed_like_energy_keeping():
    from hop_impedance.simulation.scenarios import seed_like_options
    from hop_impedance.simulation.simulate import simulate_recording

    return simulate_recording(1.87, "hard", 3, seed=2, flight="energy_keeping", **seed_like_options())


def _stance_set_default():
    from hop_impedance.simulation.stance_set import simulate_stance_set_recording

    return simulate_stance_set_recording(2.2, ("rigid", "soft"), 3, seed=1, rtol=1e-6)


def _stance_set_sized():
    from hop_impedance.simulation.scenarios import Effects
    from hop_impedance.simulation.stance_set import EffectSizes, simulate_stance_set_recording

    effects = Effects(rate_dependent_stiffness=True, time_activation=True)
    return simulate_stance_set_recording(1.87, ("hard",), 3, seed=4, effects=effects, sizes=EffectSizes(),
                                         rtol=1e-6, redraws=2)


def _strict():
    from hop_impedance.validation.strict_generator import StrictConfig, strict_recording

    return strict_recording(StrictConfig(hops=3, seed=5, angle_k1=0.5, force_offset_n=5.0, marker_latency_s=0.005))


def _recover(freq_hz: float, seed: int, noisy: bool, **kw):
    from hop_impedance.validation.coefficient_recovery import recover_trial

    with tempfile.TemporaryDirectory() as tmp:
        return recover_trial(freq_hz, seed, noisy, pathlib.Path(tmp), n_hops=3, **kw)


def _recover_legs():
    from hop_impedance.validation.bilateral_recovery import recover_legs

    results, _, _, lumped = recover_legs({"left": 2.2, "right": 1.53}, 11, n_hops={"left": 4, "right": 3}, lumped=True,
                                         edge_s=0.02)
    return {"per_leg": results, "lumped": lumped}


def cases() -> dict:
    """Case name -> callable producing what is compared."""
    out = {f"bundled_{stem}": (lambda a=argv: _bundled(a)) for stem, argv in _bundled_commands().items()}
    out.update({
        "seed_like_energy_keeping": _seed_like_energy_keeping,
        "stance_set_default": _stance_set_default,
        "stance_set_sized": _stance_set_sized,
        "strict": _strict,
        "recover_noisy_2p20": lambda: _recover(2.2, 11, True),
        "recover_clean_1p53_edges": lambda: _recover(1.53, 12, False, edge_s=0.02, skip_first=1),
        "recover_legs": _recover_legs,
    })
    return out


def canonical(obj, _stack: tuple = ()):
    """A picklable tree of ``obj`` whose equality means bit-identical content."""
    import numpy as np

    if id(obj) in _stack:
        return ("<cycle>", type(obj).__name__)
    stack = _stack + (id(obj),)
    if obj is None or isinstance(obj, (bool, str, bytes, int)) and not isinstance(obj, np.generic):
        return obj
    if isinstance(obj, float):
        return ("float", obj.hex()) if not math.isnan(obj) else ("float", "nan")
    if isinstance(obj, np.generic):
        return ("np", obj.dtype.str, obj.tobytes())
    if isinstance(obj, np.ndarray):
        if obj.dtype == object:
            return ("ndarray-obj", obj.shape, [canonical(v, stack) for v in obj.ravel()])
        return ("ndarray", obj.dtype.str, obj.shape, np.ascontiguousarray(obj).tobytes())
    if isinstance(obj, dict):
        return ("dict", [(canonical(k, stack), canonical(v, stack)) for k, v in obj.items()])
    if isinstance(obj, (list, tuple)):
        return (type(obj).__name__, [canonical(v, stack) for v in obj])
    if dataclasses.is_dataclass(obj):
        return (type(obj).__name__, [(f.name, canonical(getattr(obj, f.name), stack)) for f in dataclasses.fields(obj)])
    if hasattr(obj, "__dict__"):
        return (type(obj).__name__, [(k, canonical(v, stack)) for k, v in sorted(vars(obj).items())])
    return (type(obj).__name__, repr(obj))


def first_difference(a, b, path: str = "") -> str | None:
    """Path of the first place two canonical trees differ (None if equal)."""
    if a == b:
        return None
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            found = first_difference(x, y, f"{path}[{i}]")
            if found:
                return found
    return f"{path}: {str(a)[:120]} != {str(b)[:120]}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--save", metavar="DIR", help="write the reference pickles here")
    g.add_argument("--check", metavar="DIR", help="compare against the reference pickles here")
    ap.add_argument("--only", action="append", default=[], metavar="NAME", help="run only this case (repeatable)")
    args = ap.parse_args()
    folder = pathlib.Path(args.save or args.check)
    folder.mkdir(parents=True, exist_ok=True)
    todo = {k: v for k, v in cases().items() if not args.only or k in args.only}
    failed = 0
    for name, make in todo.items():
        tree = canonical(make())
        ref = folder / f"{name}.pkl"
        if args.save:
            ref.write_bytes(pickle.dumps(tree))
            print(f"{name}: saved")
            continue
        diff = first_difference(pickle.loads(ref.read_bytes()), tree)
        failed += diff is not None
        print(f"{name}: {'equal' if diff is None else 'DIFFERENT at ' + diff}", flush=True)
    if args.check:
        print("ALL EQUAL" if not failed else f"{failed} of {len(todo)} DIFFERENT")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
