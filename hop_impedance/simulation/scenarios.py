"""Named simulator configurations and the switchable effects.

Stiffness magnitudes are the seed paper's Table 2 means (k0, k1 per joint and
frequency); damping b0 = 0.5 N m s/rad ("below 0.72", seed text). Effects that
the seed did not quantify (k2, k3, b1..b3, activation, push-off) get
documented illustrative values, each switchable on its own (:class:`Effects`),
so that the discovery workflow can hide them one at a time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

import numpy as np
import yaml

from hop_impedance.biomech.body_model import DE_LEVA, body_model_from_stature
from hop_impedance.recording import GRAVITY_M_S2, Subject
from hop_impedance.seed_tables import JOINTS as TABLE2_JOINTS
from hop_impedance.seed_tables import TABLE2_EQ10
from hop_impedance.simulation.dynamics import Chain, chain_from_body_model, contact_ahead_of_toe_marker
from hop_impedance.simulation.ground import Ground, GroundLaw, lossless, surface, with_pad
from hop_impedance.simulation.hopping_trial import (
    HoppingConfig,
    LandingFeedback,
    joint_triple,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.impedance_laws import (
    BellActivation,
    BiarticularSpring,
    CompositeLaw,
    Eq3Law,
    ImpedanceLaw,
    PushOff,
    TimeActivation,
    TrunkBalance,
)
from hop_impedance.simulation.stance import simulate_stance

#: The seed's mean subject (8 women): 54.8 kg, 1.63 m.
SEED_SUBJECT = Subject("sim_seed_mean", 54.8, 1.63, "female")

#: Seed Table 2, k0 and k1 (N m/rad) for ankle, knee, hip at 1.53, 1.87, 2.20 Hz.
SEED_TABLE2: dict[float, dict[str, tuple[float, float, float]]] = {
    f: {name: tuple(getattr(row[j], name) for j in TABLE2_JOINTS) for name in ("k0", "k1")}
    for f, row in TABLE2_EQ10.items()
}  # the seed's Table 2 means, typed once in hop_impedance/seed_tables.py

#: Default touchdown joint angles (rad): ankle (sole-shank, 90 deg neutral,
#: plantarflexed below), knee and hip (pi + flexion).
DEFAULT_TOUCHDOWN_RHO = (1.45, np.pi + 0.50, np.pi + 0.20)

#: Illustrative magnitudes of effects the seed found insignificant.
DAMPING_B0 = 0.5  # N m s/rad, seed: "below 0.72"
EXTRA_K2 = (200.0, 200.0, 100.0)  # N m/rad^3
EXTRA_K3 = (3.0, 2.0, 1.0)  # N m s/rad^2 (larger values make the light foot whip: S grows as int omega^2)
EXTRA_B1 = (0.05, 0.05, 0.02)  # N m s^2/rad^2
#: Push-off shape over the joints (ankle-dominated) and default base amplitude (N m).
PUSH_OFF_WEIGHTS = (1.0, 0.6, 0.3)
PUSH_OFF_BASE_NM = 40.0
#: Push-off onset and duration as fractions of the passive calibration stance (:func:`hopping_config`).
PUSH_OFF_TIMING = (0.35, 0.6)
#: Time-based activation (seed 001 / Hurst): a_min and tau (s).
ACTIVATION = TimeActivation(a_min=0.3, tau_s=0.04)
#: Trunk balance (issue 17, hands on the waist): 800 N m/rad is about twice the trunk's
#: inverted-pendulum stiffness at 3.5 body weights (31.9 kg x 3.5 g x 0.38 m ~ 410 N m/rad), so the
#: trunk stays near its touchdown inclination; 40 N m s/rad damps its pitch (critical damping of the
#: HAT about the hip with I ~ 1.45 + 31.9 x 0.38^2 ~ 6 kg m^2 would be 2 sqrt(800 x 6) ~ 140).
TRUNK_BALANCE = TrunkBalance(800.0, 40.0)
#: Issue 17's lossless trial: the trunk held by a hip spring of the same 800 N m/rad instead (N m/rad;
#: :func:`hopping_config`'s ``hip_trunk_spring_nm_rad``). A moment at the hip is conservative only as a
#: function of the hip angle (any potential whose moments act at the hip alone depends on q4 - q3), so
#: :data:`TRUNK_BALANCE`, a moment on the trunk's absolute pitch q4, does work on the thigh that no
#: potential returns (bench/simulator_energy_budget.py --lossless measures it per hop).
HIP_TRUNK_SPRING_NM_RAD = 800.0


def shoe_pad(compression_m: float = 0.010, exponent: float = 2.0, at_body_weights: float = 3.0,
             subject: Subject = SEED_SUBJECT) -> GroundLaw:
    """Issue 17 candidate: the shoe's forefoot sole and the plantar soft tissue as one elastic pad ``F = k d^n``.

    ``k`` is chosen so that the pad compresses ``compression_m`` at ``at_body_weights`` x the subject's weight
    (default 10 mm at 3 BW, n = 2: a stiffening sole, soft at small force; the forefoot's plantar tissue,
    ~10 mm thick, and a shoe's forefoot midsole each compress a few millimetres under running loads). Passed as
    ``hopping_config(pad=...)``, in series with the trial's surface
    (:class:`~hop_impedance.simulation.ground.PaddedGround`). Not in :func:`seed_like_options`.
    """
    force = at_body_weights * subject.body_mass_kg * GRAVITY_M_S2
    return GroundLaw(f"shoe_pad_{1000 * compression_m:g}mm_n{exponent:g}", force / compression_m**exponent, exponent, 0.0)


def toe_tip_ahead_m(subject: Subject = SEED_SUBJECT) -> float:
    """Distance (m) from the toe marker (fifth metatarsal head) forward to the tip of the toe.

    The seed's foot touches the floor "through a virtual hinge located at the tip of the toe"
    (seed 000, Methods); our toe marker lies on the sole at 72 % of de Leva's heel..toe-tip foot
    length, so the tip is the rest of that length ahead of it (0.060 m for the seed's mean subject).
    Evidence that the seed's ground force acts that far forward: its Table 1 maximal ankle moment
    over peak GRF is 0.17-0.19 m at all three frequencies, more than the marker's 0.14-0.15 m
    horizontal distance from the ankle even with the foot flat.
    """
    model = body_model_from_stature(subject)
    return float(DE_LEVA[model.sex]["foot"].length_fraction * subject.body_height_m - model.foot_geometry.heel_toe_m)


#: Issue 17 candidate touchdown posture (rad): ankle rho1 1.24 (sole-shank 71 deg), knee and hip flexed
#: 0.68 and 0.42 rad; with the contact at the toe tip the shank leans forward enough that the force's
#: lever about the knee is 0.06-0.07 m at peak force, as the seed's Table 1 knee moment over peak GRF.
SEED_LIKE_TOUCHDOWN_RHO = (1.24, np.pi + 0.68, np.pi + 0.42)
#: Push-off late in stance (issue 17): from 50 % of the passive stance to its end, after maximal flexion.
LATE_PUSH_OFF_TIMING = (0.5, 0.5)
#: Issue 17 candidate: the bell activation's value at touchdown (:class:`BellActivation` over the passive stance;
#: ``hopping_config(bell_activation_min=...)``). 0.7: with 0.5 the 1.53 Hz ankle and knee flex and load too
#: much (bench/simulator_realism.py --seed-like --bell 0.5); docs/simulator.md.
SEED_LIKE_BELL_MIN = 0.7
#: Issue 17: factors on Table 2's (k0 per joint, k1 per joint) for the seed-like hopper, so that the per-stance
#: Eq. 3 fit (k0, k1, b0) of its noise-free trials returns Table 2 at the ankle and knee: the seed's Table 2 is
#: what its fit returned, and with the bell the fit reads a(t) K as more angle dependence (docs/simulator.md).
#: Found by one rule at every frequency, simulation/fit_calibration.calibrate_law_scale (printed by
#: bench/simulator_law_calibration.py); the hip stays Table 2. Between frequencies interpolated (law_scale_at).
#: 1.87 and 2.2 Hz converged (worst ankle/knee deviation 2.0 / 3.4 %); 1.53 Hz did not (its best measured step,
#: 50 %: nearby laws fit tens of percent apart or do not hop). Not in :func:`seed_like_options`: with it the
#: realism table has 10 binding cells out instead of 3 (bench/simulator_realism.py --seed-like --fit-law).
SEED_LIKE_LAW_SCALE: dict[float, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    1.53: ((1.428711, 1.19152, 1.0), (0.910115, 0.834152, 1.0)),
    1.87: ((1.612, 1.158, 1.0), (0.219, 0.702, 1.0)),
    2.2: ((1.621351, 1.228278, 1.0), (0.181142, 0.509091, 1.0)),
}


def seed_like_options(subject: Subject = SEED_SUBJECT) -> dict:
    """Keyword options of :func:`hopping_config` / ``simulate_recording`` for issue 17's candidate hopper.

    The mechanism (README, "Simulator realism"): the ground contact at the tip of the toe (the seed's
    virtual hinge, :func:`toe_tip_ahead_m`), which lengthens the force's lever about the ankle to the
    seed's 0.17-0.19 m and so softens the leg vertically; a touchdown posture with the knee and hip
    flexed (:data:`SEED_LIKE_TOUCHDOWN_RHO`); the trunk-balance moment (hands on the waist,
    :data:`TRUNK_BALANCE`); the push-off late in stance (:data:`LATE_PUSH_OFF_TIMING`); the extensors'
    activation bell-shaped over the stance (:data:`SEED_LIKE_BELL_MIN`: pre-activated to 0.7 at touchdown,
    full at mid-stance, :class:`~hop_impedance.simulation.impedance_laws.BellActivation`), which makes the
    force peak like the seed's rather than like a linear spring's. One set for all frequencies; the joint
    laws stay seed Table 2, scaled by the activation (the law whose fit returns Table 2,
    :data:`SEED_LIKE_LAW_SCALE`, is not in these options: it moves the realism cells, docs/simulator.md).
    Not the default (bench/simulator_realism.py --seed-like measures it against seed Table 1). A lossless
    trial leaves out ``push_timing`` and ``bell_activation_min`` (both active).
    """
    return {"touchdown_rho_rad": SEED_LIKE_TOUCHDOWN_RHO, "trunk_balance": TRUNK_BALANCE,
            "contact_ahead_m": toe_tip_ahead_m(subject), "push_timing": LATE_PUSH_OFF_TIMING,
            "bell_activation_min": SEED_LIKE_BELL_MIN}


#: Issue 17's seed-like hopper (:func:`seed_like_hopper_options`): factors on Table 2's (k0 per joint, k1 per joint)
#: so that the per-stance Eq. 3 fit (k0, k1, b0) of its noise-free 10-hop trials, analysed at the 12 Hz cut-off,
#: returns Table 2 at the ankle and knee; found by session 10's rule (``fit_calibration.calibrate_law_scale``) in
#: bench/simulator_issue17_search.py with the options of that hopper (session 32, the trunk-still flight, search
#: ``--iterations 12 --tolerance 0.05``: calibration worst ankle/knee deviation 12 / 4 / 3 % at 1.53 / 1.87 / 2.2 Hz;
#: the bench's ``trunk_still_km01_g05``; adopted in session 33). The hip stays Table 2.
SEED_LIKE_HOPPER_LAW_SCALE: dict[float, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    1.53: ((0.868092, 1.136027, 1.0), (1.096045, 0.692986, 1.0)),
    1.87: ((0.893389, 1.012641, 1.0), (1.058274, 0.913615, 1.0)),
    2.2: ((0.904032, 0.986182, 1.0), (1.039745, 0.931678, 1.0)),
}
#: The rest of that hopper on top of :func:`seed_like_options`: the bell's floor, the shoe pad (mm at 3 BW,
#: exponent), the push-off's onset and duration (fractions of the passive stance: lasting to take-off) and the
#: trunk balance (N m/rad, N m s/rad).
SEED_LIKE_HOPPER_BELL_MIN = 0.9
SEED_LIKE_HOPPER_PAD = (0.015, 3.0)
SEED_LIKE_HOPPER_PUSH_TIMING = (0.6, 0.8)
SEED_LIKE_HOPPER_TRUNK = TrunkBalance(500.0, 60.0)
#: Its flight (issue 17: the segments' motion and the springs' energy carried to the next touchdown, so the push-off
#: only replaces losses), the trunk landing at rest with all of the carried energy in the legs (session 32: with the
#: energy-keeping flight the trunk landed pitching at 0.3-0.8 rad/s and the balance braked it, the 1.53 Hz hip's
#: initial K 17 against its law's 95, the Fig. 7 outlier), landing along the direction of the prescribed flight's
#: landing motion (hopping_trial.HoppingConfig.flight / .landing; docs/simulator.md, sessions 21-23, 32 and 33).
SEED_LIKE_HOPPER_FLIGHT = ("trunk_still", "prescribed")
#: The push-off's shares per joint in units of PUSH_OFF_BASE_NM (ankle, knee, hip): the knee's slightly negative, the
#: gastrocnemius' knee flexor moment, which keeps the knee from taking off past its law (its K(t) bell, session 22).
SEED_LIKE_HOPPER_PUSH_WEIGHTS = (1.0, -0.1, 0.3)
#: The hop-by-hop push-off controller's gain (1: deadbeat): half a correction per hop steadies the 1.53 Hz push-off
#: under the energy-keeping flight (session 22: its swing between hops 13.4 -> 4.6 N m SD).
SEED_LIKE_HOPPER_PUSH_OFF_GAIN = 0.5
#: The surface it hops on and was calibrated on: the rigid force plate (the shoe is the pad in series).
SEED_LIKE_HOPPER_SURFACE = "rigid"


def seed_like_hopper_options(subject: Subject = SEED_SUBJECT) -> dict:
    """Keyword options of :func:`hopping_config` / ``simulate_recording`` for issue 17's seed-like hopper (session 12).

    :func:`seed_like_options` (toe-tip contact, flexed touchdown posture, late push-off, bell activation) with the
    bell's floor at :data:`SEED_LIKE_HOPPER_BELL_MIN`, a shoe pad in series with the surface (:func:`shoe_pad`,
    :data:`SEED_LIKE_HOPPER_PAD`: 15 mm at 3 BW, n 3; the seed's subjects hopped in shoes on a force plate), the
    push-off lasting to take-off (:data:`SEED_LIKE_HOPPER_PUSH_TIMING`) with its shares
    (:data:`SEED_LIKE_HOPPER_PUSH_WEIGHTS`) and half-gain control (:data:`SEED_LIKE_HOPPER_PUSH_OFF_GAIN`), the trunk
    balance 500 / 60 (:data:`SEED_LIKE_HOPPER_TRUNK`), the trunk-still flight (:data:`SEED_LIKE_HOPPER_FLIGHT`,
    since session 33) and the law Table 2 x :data:`SEED_LIKE_HOPPER_LAW_SCALE`. Meant for the rigid plate
    (:data:`SEED_LIKE_HOPPER_SURFACE`), on which its law was calibrated. Measured against the seed (docs/simulator.md,
    session 33): 3 binding Table 1 cells out in the 10-hop trials (the hip excursion at all three frequencies, each
    with its measured cause), fitted ankle/knee k0, k1 within 12 % of Table 2, k1 kept in 9-10 / 10 stances, 23 of
    bench/simulator_issue17.py's 25 rows. ``hop-impedance simulate --hopper seed-like`` uses it.
    """
    mm, exponent = SEED_LIKE_HOPPER_PAD
    return {**seed_like_options(subject), "bell_activation_min": SEED_LIKE_HOPPER_BELL_MIN,
            "pad": shoe_pad(mm, exponent, subject=subject), "push_timing": SEED_LIKE_HOPPER_PUSH_TIMING,
            "trunk_balance": SEED_LIKE_HOPPER_TRUNK, "law_scale": SEED_LIKE_HOPPER_LAW_SCALE,
            "flight": SEED_LIKE_HOPPER_FLIGHT[0], "landing": SEED_LIKE_HOPPER_FLIGHT[1],
            "push_weights": SEED_LIKE_HOPPER_PUSH_WEIGHTS, "push_off_gain": SEED_LIKE_HOPPER_PUSH_OFF_GAIN}


def default_hopper_options(subject: Subject = SEED_SUBJECT) -> dict:
    """The default hopper: no options, i.e. ``simulate_recording``'s own defaults (``subject`` unused)."""
    return {}


#: The hoppers ``hop-impedance simulate`` offers: name -> function of the subject giving ``simulate_recording``'s
#: keyword options.
HOPPERS: dict[str, Callable[[Subject], dict]] = {"default": default_hopper_options, "seed-like": seed_like_hopper_options}


@dataclass(frozen=True)
class Effects:
    """Switches for every simulated effect (True = present)."""

    angle_dependent_stiffness: bool = True  # k1 (Table 2)
    quadratic_stiffness: bool = False  # k2
    rate_dependent_stiffness: bool = False  # k3
    damping: bool = True  # b0
    nonlinear_damping: bool = False  # b1
    time_activation: bool = False  # stiffness scaled by a(t)
    push_off: bool = True  # active extensor pulse late in stance

    def to_dict(self) -> dict:
        """Plain booleans for the truth file."""
        return asdict(self)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Names of the switches."""
        return tuple(f.name for f in fields(cls))


def nearest_table2(freq_hz: float) -> float:
    """The Table 2 frequency closest to ``freq_hz``."""
    return min(SEED_TABLE2, key=lambda f: abs(f - freq_hz))


def seed_stiffness(freq_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """k0, k1 (N m/rad) per joint, linearly interpolated in frequency over Table 2 (clamped)."""
    freqs = np.array(sorted(SEED_TABLE2))
    k0 = np.array([SEED_TABLE2[f]["k0"] for f in freqs])
    k1 = np.array([SEED_TABLE2[f]["k1"] for f in freqs])
    f = float(np.clip(freq_hz, freqs[0], freqs[-1]))
    return (np.array([np.interp(f, freqs, k0[:, j]) for j in range(3)]),
            np.array([np.interp(f, freqs, k1[:, j]) for j in range(3)]))


def law_scale_at(law_scale: dict | None, freq_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Factors on Table 2's k0 and k1 per joint at ``freq_hz`` from a table ``{freq: (k0 factors, k1 factors)}``.

    Linearly interpolated in frequency and clamped at the table's ends, as :func:`seed_stiffness`
    interpolates Table 2; None: ones (the law is Table 2). E.g. :data:`SEED_LIKE_LAW_SCALE`.
    """
    if not law_scale:
        return np.ones(3), np.ones(3)
    freqs = np.array(sorted(law_scale))
    f = float(np.clip(freq_hz, freqs[0], freqs[-1]))
    table = np.array([np.asarray(law_scale[g], float).reshape(2, 3) for g in freqs])
    out = np.array([[np.interp(f, freqs, table[:, i, j]) for j in range(3)] for i in range(2)])
    return out[0], out[1]


def build_law(freq_hz: float, effects: Effects, push_onset_s: float, push_duration_s: float,
              hip_trunk_spring_nm_rad: float = 0.0, bell: BellActivation | None = None,
              law_scale: dict | None = None, push_weights=PUSH_OFF_WEIGHTS,
              biarticular: BiarticularSpring | None = None, push_lags=(0.0, 0.0, 0.0)) -> ImpedanceLaw:
    """The joint law for a frequency with the chosen effects (``hip_trunk_spring_nm_rad`` is added to the
    hip's k0: :data:`HIP_TRUNK_SPRING_NM_RAD`; ``bell`` scales the elastic moment, instead of
    :data:`ACTIVATION`, which it excludes; ``law_scale`` multiplies Table 2's k0 and k1, :func:`law_scale_at`;
    ``push_weights`` shares the push-off between ankle, knee and hip, :data:`PUSH_OFF_WEIGHTS`; ``biarticular``, a
    passive knee-ankle spring, is a part after the Eq. 3 one, None (default): none; ``push_lags``, the push-off's
    ``lag_fraction`` per joint, :class:`PushOff`, default none)."""
    if bell is not None and effects.time_activation:
        raise ValueError("one activation per law: the bell excludes Effects.time_activation")
    k0, k1 = seed_stiffness(freq_hz)
    s0, s1 = law_scale_at(law_scale, freq_hz)
    k0, k1 = k0 * s0, k1 * s1
    k0 = k0 + np.array([0.0, 0.0, hip_trunk_spring_nm_rad])
    eq3 = Eq3Law(
        k0=k0,
        k1=k1 if effects.angle_dependent_stiffness else np.zeros(3),
        k2=np.array(EXTRA_K2 if effects.quadratic_stiffness else 0.0),
        k3=np.array(EXTRA_K3 if effects.rate_dependent_stiffness else 0.0),
        b0=np.array(DAMPING_B0 if effects.damping else 0.0),
        b1=np.array(EXTRA_B1 if effects.nonlinear_damping else 0.0),
        activation=ACTIVATION if effects.time_activation else bell,
    )
    passive = (eq3,) if biarticular is None else (eq3, biarticular)
    if not effects.push_off:
        return CompositeLaw(passive)
    push = PushOff(PUSH_OFF_BASE_NM * np.asarray(push_weights, float), push_onset_s, push_duration_s, push_lags)
    return CompositeLaw((*passive, push))


def passive_law(freq_hz: float, effects: Effects, hip_trunk_spring_nm_rad: float = 0.0,
                law_scale: dict | None = None, biarticular: BiarticularSpring | None = None) -> ImpedanceLaw:
    """The law of the passive stance the push-off and the bell are timed by: ``effects`` without the push-off, no
    bell (:func:`build_law`'s other arguments; a biarticular spring is passive, so it is in)."""
    return build_law(freq_hz, Effects(**{**effects.to_dict(), "push_off": False}), 0.0, 1.0, hip_trunk_spring_nm_rad,
                     law_scale=law_scale, biarticular=biarticular)


def nominal_stance_s(chain: Chain, law: ImpedanceLaw, ground: Ground, rho_td, freq_hz: float) -> float:
    """Stance time (s) of one passive stance at a typical touchdown speed, to time the push-off."""
    q = touchdown_posture(chain, np.asarray(rho_td, float))
    speed = chain.gravity_m_s2 * 0.4 / freq_hz / 2.0
    st = simulate_stance(chain, law, ground, touchdown_state(chain, q, np.array([0.0, -speed]), 0.0),
                         t_max_s=2.0 / freq_hz, rtol=1e-6, atol=1e-8)
    return st.duration_s


def hopping_config(
    freq_hz: float = 2.2,
    surface_name: str = "hard",
    n_hops: int = 10,
    effects: Effects = Effects(),
    *,
    subject: Subject = SEED_SUBJECT,
    touchdown_rho_rad=DEFAULT_TOUCHDOWN_RHO,
    unexpected_surface: str | None = None,
    unexpected_hops: tuple[int, ...] = (),
    calibration_surface: str | None = None,
    variability: bool = True,
    contact_ahead_m: float = 0.0,
    push_timing: tuple[float, float] = PUSH_OFF_TIMING,
    hip_trunk_spring_nm_rad: float = 0.0,
    bell_activation_min: float | None = None, law_scale: dict | None = None,
    pad: GroundLaw | None = None, push_weights: tuple[float, float, float] = PUSH_OFF_WEIGHTS,
    biarticular: BiarticularSpring | None = None, push_lags: tuple[float, float, float] = (0.0, 0.0, 0.0),
    **config_options,
) -> tuple[Chain, HoppingConfig]:
    """A hopping configuration from a few high-level choices.

    The push-off is timed from a passive stance on the calibration surface: onset and duration are the fractions
    ``push_timing`` of that stance (default :data:`PUSH_OFF_TIMING`: 35 % and 60 %). ``calibration_surface``
    (default: the trial's surface) is the surface the law is tuned for; with ``unexpected_surface`` the listed hops
    land on that surface instead. ``config_options`` are passed to :class:`HoppingConfig` as they are (its defaults
    where not given): ``trunk_balance`` (e.g. :data:`TRUNK_BALANCE`; default none), ``flight``, ``landing``,
    ``push_off_gain``, ``passive_takeoff_s``, ``passive_landing_s``, ...
    ``contact_ahead_m`` moves the ground contact that far in front of the toe marker
    (:func:`contact_ahead_of_toe_marker`; e.g. :func:`toe_tip_ahead_m`, the seed's hinge at the tip of the toe; default 0).
    ``hip_trunk_spring_nm_rad`` (e.g. :data:`HIP_TRUNK_SPRING_NM_RAD`) holds the trunk by a hip spring
    about the touchdown hip angle, added to the Table 2 hip k0 (so the truth file's hip law is the whole
    hip law): the conservative alternative to ``trunk_balance`` (default 0, none). ``bell_activation_min``
    (:data:`SEED_LIKE_BELL_MIN`; None: none): a :class:`BellActivation` from it over the passive stance; ``law_scale``
    (:data:`SEED_LIKE_LAW_SCALE`; None: Table 2): factors on Table 2's k0, k1 (:func:`law_scale_at`), in the truth.
    ``pad`` (e.g. :data:`SHOE_PAD`; None: none): an elastic pad in series with every surface of the trial
    (:class:`~hop_impedance.simulation.ground.PaddedGround`), stated in the truth file's surface. ``push_weights``: the
    push-off's amplitude per joint in units of :data:`PUSH_OFF_BASE_NM` (default :data:`PUSH_OFF_WEIGHTS`).
    ``biarticular`` (None: none): a passive knee-ankle spring (:class:`~.impedance_laws.BiarticularSpring`), a part
    of the law and of its passive stance. ``push_lags``: the push-off's ``lag_fraction`` (:class:`~.impedance_laws.PushOff`).
    """
    chain = contact_ahead_of_toe_marker(chain_from_body_model(body_model_from_stature(subject)), contact_ahead_m)
    expected = with_pad(surface(calibration_surface or surface_name), pad)
    passive = passive_law(freq_hz, effects, hip_trunk_spring_nm_rad, law_scale, biarticular)
    ts = nominal_stance_s(chain, passive, expected, touchdown_rho_rad, freq_hz)
    bell = None if bell_activation_min is None else BellActivation(bell_activation_min, ts)
    law = build_law(freq_hz, effects, push_timing[0] * ts, push_timing[1] * ts, hip_trunk_spring_nm_rad, bell,
                    law_scale, push_weights, biarticular, push_lags)
    config = HoppingConfig(
        freq_hz=freq_hz, n_hops=n_hops, surface=expected, law=law,
        touchdown_rho_rad=joint_triple(touchdown_rho_rad),
        unexpected_surface=with_pad(surface(unexpected_surface), pad) if unexpected_surface else None,
        unexpected_hops=tuple(unexpected_hops),
        posture_sd_rad=0.01 if variability else 0.0, speed_sd=0.02 if variability else 0.0,
        push_sd=0.03 if variability else 0.0, **config_options,
    )
    if surface_name != (calibration_surface or surface_name):
        config = HoppingConfig(**{**config.__dict__, "unexpected_surface": with_pad(surface(surface_name), pad),
                                  "unexpected_hops": tuple(range(n_hops))})
    return chain, config


#: How :func:`lossless_hopper_config` holds the trunk: by a hip spring of the trunk balance's stiffness (conservative)
#: or by the balance itself (no potential: the hop gains or loses its work, docs/simulator.md).
TRUNK_HOLDS = ("hip_spring", "balance")


def lossless_hopper_config(freq_hz: float, n_hops: int, options: dict, surface_name: str = "rigid",
                           trunk: str = "hip_spring") -> tuple[Chain, HoppingConfig]:
    """Issue 17's lossless counterpart of the hopper that ``options`` describe (:func:`hopping_config` keyword options,
    e.g. :func:`seed_like_hopper_options`).

    Everything that does work on the hopper or takes it is removed, the rest kept: no push-off, no damping (b0 = 0),
    no bell activation (a stiffness that changes with time does work: the Eq. 3 springs at a(t) = 1, Table 2 x the
    options' ``law_scale``), the surface without its damper (an elastic shoe pad kept, :func:`~hop_impedance.
    simulation.ground.lossless`), no sliding (friction None), the energy-keeping flight with its own landing rule (the
    take-off rates reversed, or a stored hop's rates; the options' ``flight`` and ``landing`` are dropped), no noise.
    ``trunk`` "hip_spring" (default) holds the trunk by a hip spring of the options' trunk balance's stiffness about the
    touchdown hip angle (added to the hip's k0; ``hip_trunk_spring_nm_rad``), "balance" keeps the balance moment (on
    the trunk's absolute pitch: no potential, :data:`HIP_TRUNK_SPRING_NM_RAD`).
    """
    if trunk not in TRUNK_HOLDS:
        raise ValueError(f"trunk must be one of {TRUNK_HOLDS}, got {trunk!r}")
    kept = {k: v for k, v in options.items() if k not in ("push_timing", "bell_activation_min", "flight", "landing")}
    balance = kept.get("trunk_balance")
    if trunk == "hip_spring" and balance is not None:
        kept = {**kept, "trunk_balance": None, "hip_trunk_spring_nm_rad": balance.stiffness_nm_rad}
    chain, config = hopping_config(freq_hz, surface_name, n_hops, Effects(damping=False, push_off=False),
                                   variability=False, flight="energy_keeping", **kept)
    return chain, replace(config, surface=lossless(config.surface), friction_coefficient=None)


#: Issue 17: the periodic hops of the seed-like hopper's lossless counterpart (:func:`seed_like_lossless_config`), one
#: per seed frequency's law, with their landing feedback; written by ``bench/simulator_energy_budget.py --find-orbits
#: --write`` (continuation from 2.2 Hz, periodic_hop.periodic_hop and periodic_hop.landing_feedback).
SEED_LIKE_LOSSLESS_HOPS_FILE = Path(__file__).resolve().parent.parent / "data" / "seed_like_lossless_hops.yaml"


def seed_like_lossless_hops() -> dict[float, dict]:
    """{law frequency (Hz): periodic hop} from :data:`SEED_LIKE_LOSSLESS_HOPS_FILE`: its touchdown state ``state``
    (periodic_hop.STATE_NAMES), ``landing_rates_rad_s``, the placement reference ``com_ahead_m``, the feedback
    ``gain`` (5 x 7), its stance and flight (s) and the eigenvalue moduli with and without the feedback."""
    with open(SEED_LIKE_LOSSLESS_HOPS_FILE, encoding="utf-8") as fh:
        return {float(f): hop for f, hop in yaml.safe_load(fh)["hops"].items()}


#: Stance integration tolerances of the seed-like hopper's lossless counterpart (session 31). A stored periodic hop is
#: a fixed point of the hop map only to the stance integration's error, amplified along the hop's unstable direction:
#: 1.87 Hz's symmetric hop has max |P(x) - x| 3.7e-6 at the trials' rtol 1e-8 / atol 1e-10 and 6.1e-8 at these.
SEED_LIKE_LOSSLESS_TOLERANCES = (1e-10, 1e-12)


def seed_like_lossless_counterpart(freq_hz: float, n_hops: int = 30,
                                   extra: dict | None = None) -> tuple[Chain, HoppingConfig]:
    """:func:`lossless_hopper_config` of :func:`seed_like_hopper_options` at :data:`SEED_LIKE_LOSSLESS_TOLERANCES`: the
    hopper :func:`seed_like_lossless_config` starts on its stored periodic hop, and the one they are found for.
    ``extra``: hopping_config options added to the preset's (a probe's, e.g. a biarticular spring)."""
    chain, config = lossless_hopper_config(freq_hz, n_hops, {**seed_like_hopper_options(), **(extra or {})})
    rtol, atol = SEED_LIKE_LOSSLESS_TOLERANCES
    return chain, replace(config, rtol=rtol, atol=atol)


def seed_like_lossless_config(freq_hz: float, n_hops: int = 30, feedback: bool = True) -> tuple[Chain, HoppingConfig]:
    """Issue 17's lossless counterpart of the seed-like hopper (:func:`lossless_hopper_config` of
    :func:`seed_like_hopper_options`: no push-off, damping, bell or surface damper; the trunk held by a hip spring of
    the trunk balance's 500 N m/rad) at a seed frequency's law, started on its periodic hop
    (:func:`seed_like_lossless_hops`) and landing along that hop's rates; ``feedback`` (default) with the landing
    feedback that makes the hop attract (:class:`~hop_impedance.simulation.hopping_trial.LandingFeedback`), else the
    fixed landing rule and placement (the bare periodic hop, unstable at the lower frequencies' laws)."""
    hops = seed_like_lossless_hops()
    if freq_hz not in hops:
        raise ValueError(f"no lossless periodic hop stored for {freq_hz} Hz; stored: {sorted(hops)}")
    hop = hops[freq_hz]
    chain, config = seed_like_lossless_counterpart(freq_hz, n_hops)
    state, landing = tuple(float(v) for v in hop["state"]), tuple(float(v) for v in hop["landing_rates_rad_s"])
    rule = LandingFeedback(state, landing, float(hop["com_ahead_m"]),
                           tuple(tuple(float(v) for v in row) for row in hop["gain"])) if feedback else None
    return chain, replace(config, com_ahead_m=float(hop["com_ahead_m"]), first_touchdown=state,
                          landing_rates_rad_s=landing, landing_feedback=rule)
