"""Seed 001's unexpected hard surface: one stance on the expected soft surface against the same on hard.

Seed 001 (van der Krogt et al. 2009): the hopper prepared for the soft surface, with the same touchdown and the same
pre-programmed activation, meets an unexpected hard surface; leg stiffness falls compared with the expected soft
surface, the ankle and knee flex more and the hip less ("increased flexion in the ankle and knee joint and, to a
lesser extent, in the hip joint"), and "joint stiffness was lower at all joints ... most pronounced at the ankle".
:func:`unexpected_hard_vs_soft` measures those figures on one simulated stance pair; test/simulation and
bench/simulator_issue17.py use it.

Definitions (seed 001's Methods, "Definitions", following its refs. 12 and 23):

- Leg stiffness: "the ratio of the peak ground reaction force to the maximum vertical displacement of the center of
  mass", the displacement being the leg's compression, "calculated by subtracting the surface displacement from the
  vertical displacement of the COM" (:func:`~hop_impedance.simulation.hopping_trial.leg_stiffness_n_per_m`).
- Joint stiffness: "joint stiffness as the slope of the relationship between" joint moment and joint angle (the
  stored text drops the words after "between"; its Fig. 6B plots "ankle moment vs. ankle angle change from touch
  down to midstance", and "Midstance was defined as the instant that COM reached its lowest value"). So
  :func:`joint_stiffness_nm_rad` is the net moment's change over the angle's change from touchdown to midstance (the
  COM's lowest point), the hip's net moment including the trunk balance. Until session 20 it was read to each joint's
  maximal flexion instead, which is not the paper's quantity: the ankle and knee flex maximally near midstance, but
  the hip 3-13 % of the stance after it (docs/simulator.md, session 20). "Falls most" is read relatively
  (hard / soft - 1), since the three joints' stiffnesses differ several-fold.

What the hopper prepares before landing (session 20; ``anticipate`` and ``preprogrammed``, both on by default; both
off is sessions 12-19's experiment):

- ``anticipate``: seed 001's subjects, and its model fitted to them, prepared for the soft surface: "human hoppers
  and runners adjust leg stiffness when expecting a transition in surface stiffness (15, 16). This adjustment results
  in similar COM dynamics, regardless of surface stiffness", and their contact lasted 365 ms on the soft surface
  against 385 ms on the hard one (its model 368 / 376 ms). The hopper's law is the one it prepared for a hard
  surface (Table 2, seed 000's force plate); expecting the soft surface it scales its joint springs (k0 and k1 of
  every joint, one factor, :func:`anticipated_stiffening`) until its passive stance on the soft law is as long as
  that law's passive stance on seed 001's hard law. One rule at every frequency; the factor is what the rule gives
  there (1.16 / 1.42 / 1.88 at 1.53 / 1.87 / 2.2 Hz on the seed-like preset).
- ``preprogrammed``: the activation that seed 001 keeps the same on the unexpected surface ("without changing initial
  geometry, initial muscle stimulation, or STIM(t) during ground contact") is fixed in time, and the rise of force
  with it ("force rise ... mainly depends on the rise in q", q "fixed in time"). In Eq. 3 that rise is the
  angle-dependent k1 term; here it is pre-programmed along the expected soft stance
  (:class:`~hop_impedance.simulation.impedance_laws.PreparedStiffening`): the same moments on the expected surface,
  while a joint that flexes earlier on the hard surface meets the stiffness of the earlier time. The bell activation
  and the push-off were already fixed in time; the touchdown state, the trunk balance and the push-off's calibrated
  amplitude are the soft hop's on both surfaces.

``expected="hard"`` is seed 001's other transition (prepared for hard, landing on soft: "opposite effects"); the
hard law needs no anticipation (factor 1), and the figures stay hard against soft, so the same directions hold.

Contact (choice, issue 17 session 12; tested in test/simulation/test_sim_surface_surprise.py): seed 001's two surface
laws are the foot-surface interaction itself, not the surface alone. Its Methods: "The coefficients for these
equations were based on an optimized fit of the subject's fifth metatarsophalangeal joint (MTP5) movement after
touchdown as a function of the ground reaction force", with y "the vertical displacement (m) of the base of the model
(representing MTP5) relative to the initial surface position". Whatever compliance lies under that marker (shoe sole,
plantar soft tissue) is in the fitted law already, so a shoe pad in series (``hopping_config(pad=...)``, seed 000's
shoes on a force plate) would count it twice: :func:`unexpected_hard_vs_soft` drops the hopper's ``pad`` option and
meets seed 001's bare laws (``keep_pad=True``: the pad on both surfaces, session 11's comparison).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from hop_impedance.simulation.dynamics import Chain, body_com
from hop_impedance.simulation.ground import HARD, SOFT, PaddedGround, with_pad
from hop_impedance.simulation.hopping_trial import (
    calibrate,
    leg_stiffness_n_per_m,
    scale_push_off,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.impedance_laws import with_prepared_stiffening
from hop_impedance.simulation.scenarios import Effects, hopping_config, law_scale_at, nominal_stance_s, passive_law
from hop_impedance.simulation.stance import StanceSimulation, resample_stance, simulate_stance

#: Sampling step of the two stances (s) on which the figures are read (their dense solutions, not the solver's steps).
SAMPLE_STEP_S = 2.5e-4


def midstance_index(chain: Chain, stance: StanceSimulation) -> int:
    """Seed 001's midstance: the sample at which the body's COM is lowest."""
    return int(np.argmin([body_com(chain, g)[1] for g in stance.g]))


def joint_stiffness_nm_rad(chain: Chain, stance: StanceSimulation) -> np.ndarray:
    """Per joint (ankle, knee, hip): net moment change over angle change, touchdown to midstance (N m/rad).

    Seed 001: "joint stiffness as the slope of the relationship between" joint moment and joint angle, plotted in its
    Fig. 6B as "ankle moment vs. ankle angle change from touch down to midstance", midstance being "the instant that
    COM reached its lowest value" (:func:`midstance_index`). The net moment includes the trunk balance's at the hip.
    """
    i = midstance_index(chain, stance)
    return (stance.moments_nm[i] - stance.moments_nm[0]) / (stance.rho_rad[i] - stance.rho_rad[0])


@dataclass(frozen=True)
class SurfaceSurprise:
    """One stance on the expected soft and the unexpected hard surface (same prepared law, same touchdown)."""

    leg_soft: tuple[float, float, float]  # (stiffness N/m, peak Fz N, compression m), leg_stiffness_n_per_m
    leg_hard: tuple[float, float, float]
    extra_flexion_rad: np.ndarray  # (3,): range of flexion on hard minus on soft, ankle / knee / hip
    joint_stiffness_soft: np.ndarray  # (3,) N m/rad, joint_stiffness_nm_rad
    joint_stiffness_hard: np.ndarray
    soft: StanceSimulation | None = None  # the two stances themselves (bench/simulator_seed001_shape.py reads them)
    hard: StanceSimulation | None = None
    push_scale: float = float("nan")  # the soft hop's calibrated push-off scale
    stiffening: float = 1.0  # the factor on the law's k0, k1 the hopper prepared for the soft surface (anticipate)

    @property
    def leg_change(self) -> float:
        """Leg stiffness on hard over soft, minus 1."""
        return self.leg_hard[0] / self.leg_soft[0] - 1.0

    @property
    def joint_change(self) -> np.ndarray:
        """Joint stiffness on hard over soft, minus 1, per joint."""
        return self.joint_stiffness_hard / self.joint_stiffness_soft - 1.0

    def directions(self) -> dict[str, bool]:
        """Issue 17's reading of seed 001's directions, each True when it holds here."""
        extra, change = self.extra_flexion_rad, self.joint_change
        return {
            "leg stiffness falls": self.leg_change < 0.0,
            "ankle and knee flex more, the hip less": bool(extra[0] > 0 and extra[1] > 0 and extra[2] < min(extra[:2])),
            "joint stiffness falls most at the ankle": bool(change[0] < 0 and change[0] < min(change[1], change[2])),
        }


def seed001_options(options: dict, keep_pad: bool = False) -> dict:
    """The hopper's ``hopping_config`` options on seed 001's surfaces: without its shoe pad unless ``keep_pad``
    (module docstring: seed 001's laws were fitted at the MTP5 marker, so they hold the sole's compliance)."""
    return dict(options) if keep_pad else {k: v for k, v in options.items() if k != "pad"}


def with_stiffening(options: dict, freq_hz: float, factor: float) -> dict:
    """``options`` with its law's k0 and k1 (every joint, after its own ``law_scale``) times ``factor`` at ``freq_hz``."""
    s0, s1 = law_scale_at(options.get("law_scale"), freq_hz)
    return {**options, "law_scale": {freq_hz: (tuple(s0 * factor), tuple(s1 * factor))}}


def anticipated_stiffening(freq_hz: float, options: dict, effects: Effects = Effects(), expected=SOFT,
                           reference=HARD) -> float:
    """The factor on the law's k0 and k1 with which its passive stance on ``expected`` (seed 001's soft law) lasts as
    long as the unscaled law's on ``reference`` (seed 001's hard law): seed 001's "similar COM dynamics, regardless of
    surface stiffness" (module docstring). 1 when the expected surface's stance is already no longer. ``options``
    are :func:`~hop_impedance.simulation.scenarios.hopping_config`'s (without a pad: :func:`seed001_options`); the
    passive stance is the one ``hopping_config`` times the push-off by (no push-off, no bell, its touchdown speed)."""
    chain, cfg = hopping_config(freq_hz, "soft", 1, effects, variability=False, **options)

    def stance_s(ground, factor: float) -> float:
        scale = with_stiffening(options, freq_hz, factor)["law_scale"]
        passive = passive_law(freq_hz, effects, options.get("hip_trunk_spring_nm_rad", 0.0), scale,
                              options.get("biarticular"))
        return nominal_stance_s(chain, passive, ground, cfg.touchdown_rho_rad, freq_hz)

    target = stance_s(reference, 1.0)

    def excess(factor: float) -> float:
        return stance_s(expected, factor) - target

    if excess(1.0) <= 0.0:
        return 1.0
    return float(brentq(excess, 1.0, 8.0, xtol=1e-4))


def _dense(chain, law, ground, td, stance: StanceSimulation) -> StanceSimulation:
    """``stance`` resampled every :data:`SAMPLE_STEP_S` from its dense solution (and at its end)."""
    n = int(np.ceil(stance.duration_s / SAMPLE_STEP_S)) + 1
    return resample_stance(chain, law, ground, td, stance, np.linspace(0.0, stance.duration_s, n))


def unexpected_hard_vs_soft(freq_hz: float = 2.2, effects: Effects = Effects(), keep_pad: bool = False,
                            anticipate: bool = True, preprogrammed: bool = True, stiffening: float | None = None,
                            expected: str = "soft", **options) -> SurfaceSurprise:
    """Calibrate the hop on the expected surface, then simulate its stance on soft and on hard from the same touchdown.

    ``options`` are :func:`~hop_impedance.simulation.scenarios.hopping_config`'s keyword options (e.g.
    :func:`~hop_impedance.simulation.scenarios.seed_like_hopper_options`); no hop-to-hop variability. A ``pad`` among
    them is dropped (:func:`seed001_options`) unless ``keep_pad``. ``anticipate``: the law's springs scaled for the
    expected surface (:func:`anticipated_stiffening`; x 1 when it is the hard one) before the calibration;
    ``preprogrammed``: the unexpected stance's k1 term follows the expected stance's course in time (module
    docstring). Both False: sessions 12-19's experiment. ``stiffening``: with ``anticipate``, this factor instead of
    the rule's (a robustness check, not the experiment). ``expected``: "soft" (default, seed 001's unexpected hard
    surface) or "hard" (its unexpected soft surface, whose "effects [are] opposite": the figures stay hard against
    soft, so the same :meth:`SurfaceSurprise.directions` hold).
    """
    if expected not in ("soft", "hard"):
        raise ValueError(f"expected must be 'soft' or 'hard', got {expected!r}")
    options = seed001_options(options, keep_pad)
    expected_law, unexpected_law = (SOFT, HARD) if expected == "soft" else (HARD, SOFT)
    factor = 1.0
    if anticipate:
        factor = (anticipated_stiffening(freq_hz, options, effects, expected=expected_law) if stiffening is None
                  else float(stiffening))
        options = with_stiffening(options, freq_hz, factor)
    chain, cfg = hopping_config(freq_hz, expected, 1, effects, variability=False, **options)
    q = touchdown_posture(chain, np.array(cfg.touchdown_rho_rad))
    cal = calibrate(chain, cfg, q)
    if not cal.success:
        raise ValueError(f"{freq_hz} Hz: no calibrated hop on the {expected} surface (closest: stance "
                         f"{1000 * cal.stance_s:.0f} ms, flight {1000 * cal.flight_s:.0f} ms at touchdown speed "
                         f"{cal.speed_m_s:.2f} m/s)")
    law = scale_push_off(cfg.law, cal.push_scale)
    td = touchdown_state(chain, q, np.array([0.0, -cal.speed_m_s]), 0.0)
    pad = cfg.surface.pad if isinstance(cfg.surface, PaddedGround) else None  # keep_pad: the pad on both surfaces
    expected_ground, unexpected_ground = with_pad(expected_law, pad), with_pad(unexpected_law, pad)
    prepared = _dense(chain, law, expected_ground, td,
                      simulate_stance(chain, law, expected_ground, td, friction_coefficient=cfg.friction_coefficient,
                                      trunk_balance=cfg.trunk_balance))
    surprise_law = law
    if preprogrammed:
        surprise_law = with_prepared_stiffening(law, prepared.t_s, prepared.rho_rad - prepared.rho_rad[0])
    surprised = _dense(chain, surprise_law, unexpected_ground, td,
                       simulate_stance(chain, surprise_law, unexpected_ground, td,
                                       friction_coefficient=cfg.friction_coefficient, trunk_balance=cfg.trunk_balance))
    soft, hard = (prepared, surprised) if expected == "soft" else (surprised, prepared)

    def flexion(st: StanceSimulation) -> np.ndarray:
        return np.max(st.rho_rad, axis=0) - st.rho_rad[0]

    return SurfaceSurprise(leg_stiffness_n_per_m(chain, soft), leg_stiffness_n_per_m(chain, hard),
                           flexion(hard) - flexion(soft), joint_stiffness_nm_rad(chain, soft),
                           joint_stiffness_nm_rad(chain, hard), soft, hard, float(cal.push_scale), factor)
