"""One-off costs on the take-off -> controller path (issue 15), each against its fix, in CPU ms of this thread.

1. A stance's ``StanceKinetics`` message: its five ``float64[]`` fields set from numpy arrays vs from
   ``array.array`` (``nodes.common.float64_sequence``), and serialised (rclpy.serialization), as
   inverse_dynamics builds and publishes it on the bundled 2.2 Hz recording's first stance.
2. A full garbage collection with the objects rclpy, numpy, scipy and the nodes leave after import
   (``gc.collect()``), and again after ``gc.freeze()`` (``nodes.common.freeze_startup_objects``).
3. The first fit of 3 joints in a process, by a ``StructureSelector`` with the seed's k0, k1, b0 given,
   without and with ``warm_up()`` (fresh interpreters each, since a first call is what is measured),
   and the later stances' fits.

    .venv/bin/python bench/bench_path_costs.py
"""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
RECORDING = Path(__file__).resolve().parents[1] / "recordings" / "sim_2p20hz_hard.mcap"
REPEATS = 50


def _cpu_ms(fn, repeats: int = REPEATS) -> float:
    """Median CPU time (ms, this thread) of ``fn()``."""
    out = []
    for _ in range(repeats):
        c0 = time.thread_time()
        fn()
        out.append(time.thread_time() - c0)
    return 1e3 * float(np.median(out))


def message_costs() -> None:
    from hop_impedance_msgs.msg import StanceKinetics
    from rclpy.serialization import serialize_message

    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.io.recording_io import load_recording
    from hop_impedance.nodes.common import float64_sequence

    stance = next(s for s in analyze_recording(load_recording(RECORDING)).stances if s.joints is not None)
    j = stance.joints
    arrays = {"time_s": j.time_s, "angle_rad": j.angle_rad, "angular_velocity_rad_s": j.angular_velocity_rad_s,
              "moment_nm": j.moment_nm, "power_w": j.power_w}
    for name, convert in (("numpy arrays", lambda a: np.ascontiguousarray(a, float).ravel()),
                          ("array.array", float64_sequence)):
        def build(convert=convert):
            msg = StanceKinetics()
            for field, values in arrays.items():
                setattr(msg, field, convert(values))
            return msg

        msg = build()
        print(f"StanceKinetics of {j.time_s.size} samples, fields from {name}: set {_cpu_ms(build):.3f} ms, "
              f"serialise {_cpu_ms(lambda msg=msg: serialize_message(msg)):.3f} ms")


def gc_costs() -> None:
    import rclpy  # noqa: F401  (what a node process holds)
    import scipy.signal  # noqa: F401

    import hop_impedance.nodes.impedance_estimator  # noqa: F401
    import hop_impedance.nodes.inverse_dynamics  # noqa: F401
    import hop_impedance.nodes.runner  # noqa: F401

    before = len(gc.get_objects())
    full = _cpu_ms(gc.collect, 5)
    gc.freeze()
    frozen = _cpu_ms(gc.collect, 5)
    print(f"full collection with {before} tracked objects: {full:.2f} ms; after gc.freeze() "
          f"({len(gc.get_objects())} left): {frozen:.2f} ms")


def first_fit(warm: bool) -> list[float]:
    from hop_impedance.biomech.analysis import analyze_recording
    from hop_impedance.impedance.recording_fits import SEED_TERMS, StructureSelector, default_fit_options
    from hop_impedance.io.recording_io import load_recording

    analysis = analyze_recording(load_recording(RECORDING))
    selector = StructureSelector(default_fit_options(analysis.options), dict.fromkeys(("ankle", "knee", "hip"), SEED_TERMS))
    if warm:
        selector.warm_up()
    out = []
    for stance in analysis.stances:
        if stance.joints is not None:
            c0 = time.thread_time()
            selector.fit(stance)
            out.append(1e3 * (time.thread_time() - c0))
    return out


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--first-fit":
        print(" ".join(f"{x:.3f}" for x in first_fit(sys.argv[2] == "warm")))
        return
    message_costs()
    for warm in ("cold", "warm"):
        runs = [subprocess.run([sys.executable, __file__, "--first-fit", warm], capture_output=True, text=True,
                               check=True).stdout.split() for _ in range(3)]
        firsts = [float(r[0]) for r in runs]
        later = np.concatenate([np.array(r[1:], float) for r in runs])
        print(f"first fit of 3 joints in a process, {'after warm_up()' if warm == 'warm' else 'no warm-up'}: "
              + ", ".join(f"{x:.2f}" for x in firsts) + f" ms (3 processes); later stances median {np.median(later):.2f} ms")
    gc_costs()


if __name__ == "__main__":
    main()
