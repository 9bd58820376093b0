"""``hop-impedance simulate``: a simulated hopping trial as a contract recording plus its truth file."""

from __future__ import annotations

import argparse
import sys

from hop_impedance.cli.conventions import DeprecatedAlias, OptionDefault

SURFACES = ("hard", "soft", "rigid")
SIMULATE = "hop_impedance.simulation.simulate:simulate_recording"
SUBJECT = "hop_impedance.simulation.scenarios:SEED_SUBJECT"
EFFECTS = "hop_impedance.simulation.scenarios:Effects"
SENSORS = "hop_impedance.simulation.sensors:SensorConfig"
#: The hoppers of scenarios.HOPPERS (named here so that building the parser imports no simulation module;
#: test/simulation/test_sim_seed_like_hopper.py checks the two agree).
HOPPERS = ("default", "seed-like")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "simulate",
        help="simulate hopping and write a contract MCAP recording plus REC.truth.json",
        description="Forward-dynamics hopping of the four-segment model with the seed paper's joint "
        "stiffness (Table 2, interpolated in frequency) on a chosen surface. Writes OUT (MCAP) and "
        "OUT's stem + .truth.json with every parameter, per-stance events, true joint moments and "
        "impedance coefficients. Every law and sensor effect can be switched on or off.",
    )
    p.add_argument("--freq", type=float, default=OptionDefault(SIMULATE, "freq_hz"),
                   help="target hop frequency, Hz (default %(default)s)")
    p.add_argument("--surface", choices=SURFACES, default=OptionDefault(SIMULATE, "surface_name"),
                   help="surface under the hops (default %(default)s)")
    p.add_argument("--hops", type=int, default=OptionDefault(SIMULATE, "n_hops"), help="number of hops (default %(default)s)")
    p.add_argument("--seed", type=int, default=OptionDefault(SIMULATE, "seed"),
                   help="seed of variability and noise (default %(default)s)")
    p.add_argument("--out", required=True, help="output recording, .mcap")
    p.add_argument("--hopper", choices=HOPPERS, default="default",
                   help="default: the four-segment hopper with the Table 2 law; seed-like: issue 17's hopper that hops "
                   "like the seed's subjects (scenarios.seed_like_hopper_options: toe-tip contact, flexed landing, "
                   "bell activation, push-off lasting to take-off, trunk balance, shoe pad; law calibrated so its fit "
                   "returns Table 2), calibrated on the force plate: use it with --surface rigid (default %(default)s)")
    p.add_argument("--tuned-for", choices=SURFACES, default=None,
                   help="surface the law is tuned (calibrated) for; default --surface. "
                   "--tuned-for soft --surface hard = unexpected hard surface (seed 001)")
    p.add_argument("--unexpected", choices=SURFACES, default=None,
                   help="surface swapped in, without re-tuning, on the hops of --unexpected-hops")
    p.add_argument("--unexpected-hops", default="", help="comma-separated 0-based hop indices, e.g. 5,6")
    p.add_argument("--mass-kg", type=float, default=OptionDefault(SUBJECT, "body_mass_kg"),
                   help="body mass, kg (default: seed mean %(default)s)")
    p.add_argument("--height-m", type=float, default=OptionDefault(SUBJECT, "body_height_m"),
                   help="body height, m (default: seed mean %(default)s)")
    p.add_argument("--mass", type=float, dest="mass_kg", action=DeprecatedAlias, new="--mass-kg")
    p.add_argument("--height", type=float, dest="height_m", action=DeprecatedAlias, new="--height-m")
    p.add_argument("--no-variability", action="store_true", help="identical hops (no hop-to-hop variability)")
    law = p.add_argument_group("impedance law effects (each on/off)")
    law.add_argument("--law", choices=("seed", "constant"), default="seed",
                     help="seed: k0 + k1 (rho - rho0) (Eq. 10); constant: k0 only")
    for flag, field, text in EFFECT_FLAGS:
        law.add_argument(f"--{flag}", dest=field, action=argparse.BooleanOptionalAction,
                         default=OptionDefault(EFFECTS, field), help=f"{text} (default: %(default)s)")
    sens = p.add_argument_group("sensors")
    sens.add_argument("--noise", choices=("realistic", "none"), default="realistic",
                      help="realistic: SensorConfig's noise (2 N force, 0.5 N m torque, 1 mm markers); none: noise-free")
    sens.add_argument("--force-rate", type=float, default=OptionDefault(SENSORS, "force_rate_hz"),
                      help="force-plate rate, Hz (default %(default)s)")
    sens.add_argument("--marker-rate", type=float, default=OptionDefault(SENSORS, "marker_rate_hz"),
                      help="marker rate, Hz (default %(default)s)")
    sens.add_argument("--force-noise", type=float, default=None, help="force noise SD, N (overrides --noise)")
    sens.add_argument("--marker-noise", type=float, default=None, help="marker noise SD, m (overrides --noise)")
    sens.add_argument("--force-offset", type=float, default=OptionDefault(SENSORS, "force_offset_n"),
                      help="constant Fz offset, N (default %(default)s)")
    sens.add_argument("--marker-delay", type=float, default=OptionDefault(SENSORS, "marker_time_offset_s"),
                      help="marker stream time offset, s: a marker stamped t shows the body at t - delay (default %(default)s)")
    sens.add_argument("--occlusions", type=float, default=OptionDefault(SENSORS, "occlusions_per_s"),
                      help="occlusions per second (default %(default)s)")
    p.set_defaults(func=run)


#: (flag, Effects field, help) of each switchable law effect; the default is the field's.
EFFECT_FLAGS = (
    ("quadratic-stiffness", "quadratic_stiffness", "k2 term of Eq. 3"),
    ("rate-stiffness", "rate_dependent_stiffness", "k3 term of Eq. 3 (rate-dependent stiffness)"),
    ("damping", "damping", "b0 damping (0.5 N m s/rad)"),
    ("nonlinear-damping", "nonlinear_damping", "b1 term of Eq. 3"),
    ("activation", "time_activation", "time-based activation scaling the stiffness (seed 001)"),
    ("push-off", "push_off", "active extensor push-off late in stance"),
)


def _hops(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise ValueError(f"--unexpected-hops must be comma-separated integers, got {text!r}") from None


def run(args: argparse.Namespace) -> int:
    from hop_impedance.recording import Subject
    from hop_impedance.simulation.scenarios import HOPPERS as HOPPER_OPTIONS
    from hop_impedance.simulation.scenarios import Effects
    from hop_impedance.simulation.sensors import SensorConfig
    from hop_impedance.simulation.simulate import simulate_recording, write_simulated_recording

    if args.hops < 1:
        raise ValueError(f"--hops must be at least 1, got {args.hops}")
    effects = Effects(angle_dependent_stiffness=args.law == "seed",
                      **{field: getattr(args, field) for _, field, _ in EFFECT_FLAGS})
    realistic = SensorConfig()  # its noise levels are the realistic ones
    noisy = args.noise == "realistic"
    sensors = SensorConfig(
        force_rate_hz=args.force_rate,
        marker_rate_hz=args.marker_rate,
        force_noise_n=args.force_noise if args.force_noise is not None else (realistic.force_noise_n if noisy else 0.0),
        torque_noise_nm=realistic.torque_noise_nm if noisy else 0.0,
        force_offset_n=args.force_offset,
        marker_noise_m=args.marker_noise if args.marker_noise is not None else (realistic.marker_noise_m if noisy else 0.0),
        occlusions_per_s=args.occlusions,
        marker_time_offset_s=args.marker_delay,
    )
    subject = Subject("sim", args.mass_kg, args.height_m, "female")
    rec, truth = simulate_recording(
        args.freq, args.surface, args.hops, args.seed, effects, sensors, subject=subject,
        tuned_for=args.tuned_for, unexpected_surface=args.unexpected, unexpected_hops=_hops(args.unexpected_hops),
        variability=not args.no_variability, generator={"argv": sys.argv[1:], "hopper": args.hopper},
        **HOPPER_OPTIONS[args.hopper](subject),
    )
    tpath = write_simulated_recording(args.out, rec, truth)
    n = len(truth["stances"])
    durations = [s["duration_s"] for s in truth["stances"]]
    print(f"wrote {args.out} ({n} stances, {truth['recording']['duration_s']:.2f} s, "
          f"stance {min(durations):.3f}-{max(durations):.3f} s) and {tpath}")
    for note in truth["notes"] + ([truth["stop_reason"]] if truth["stop_reason"] else []):
        print(f"note: {note}")
    return 0
