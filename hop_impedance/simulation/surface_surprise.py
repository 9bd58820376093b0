"""Seed 001's unexpected hard surface: one stance on the expected soft surface against the same on hard.

Seed 001 (van der Krogt et al. 2009): the law tuned for the soft surface, the same touchdown and the same
pre-programmed activation meet an unexpected hard surface; leg stiffness (peak GRF over leg compression) falls
compared with the expected soft surface, the ankle and knee flex more and the hip less ("increased flexion in the
ankle and knee joint and, to a lesser extent, in the hip joint"), and "joint stiffness was lower at all joints ...
most pronounced at the ankle". :func:`unexpected_hard_vs_soft` measures those figures on one simulated stance pair;
test/simulation and bench/simulator_issue17.py use it.

Joint stiffness (choice; seed 001 defines it as "the slope of the relationship between" joint moment and joint
angle): the net moment's change over the angle's change from touchdown to the joint's maximal flexion (the
loading phase), the hip's net moment including the trunk balance. "Falls most" is read relatively (hard / soft - 1),
since the three joints' stiffnesses differ several-fold.

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

from hop_impedance.simulation.ground import HARD, SOFT, PaddedGround, with_pad
from hop_impedance.simulation.hopping_trial import (
    calibrate,
    leg_stiffness_n_per_m,
    scale_push_off,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.scenarios import Effects, hopping_config
from hop_impedance.simulation.stance import StanceSimulation, simulate_stance


def joint_stiffness_nm_rad(stance: StanceSimulation) -> np.ndarray:
    """Per joint (ankle, knee, hip): net moment change over angle change, touchdown to maximal flexion (N m/rad)."""
    moments = stance.moments_nm  # the net joint moment (with the trunk balance's part at the hip)
    peak = np.argmax(stance.rho_rad, axis=0)
    joints = np.arange(3)
    return (moments[peak, joints] - moments[0]) / (stance.rho_rad[peak, joints] - stance.rho_rad[0])


@dataclass(frozen=True)
class SurfaceSurprise:
    """One stance on the expected soft and the unexpected hard surface (same law, same touchdown)."""

    leg_soft: tuple[float, float, float]  # (stiffness N/m, peak Fz N, compression m), leg_stiffness_n_per_m
    leg_hard: tuple[float, float, float]
    extra_flexion_rad: np.ndarray  # (3,): range of flexion on hard minus on soft, ankle / knee / hip
    joint_stiffness_soft: np.ndarray  # (3,) N m/rad, joint_stiffness_nm_rad
    joint_stiffness_hard: np.ndarray
    soft: StanceSimulation | None = None  # the two stances themselves (bench/simulator_seed001_shape.py reads them)
    hard: StanceSimulation | None = None
    push_scale: float = float("nan")  # the soft hop's calibrated push-off scale

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


def unexpected_hard_vs_soft(freq_hz: float = 2.2, effects: Effects = Effects(), keep_pad: bool = False,
                            **options) -> SurfaceSurprise:
    """Calibrate the hop on the soft surface, then simulate its stance on soft and on hard from the same touchdown.

    ``options`` are :func:`~hop_impedance.simulation.scenarios.hopping_config`'s keyword options (e.g.
    :func:`~hop_impedance.simulation.scenarios.seed_like_options`); no hop-to-hop variability. A ``pad`` among them
    is dropped (:func:`seed001_options`) unless ``keep_pad``.
    """
    chain, cfg = hopping_config(freq_hz, "soft", 1, effects, variability=False,
                                **seed001_options(options, keep_pad))
    q = touchdown_posture(chain, np.array(cfg.touchdown_rho_rad))
    cal = calibrate(chain, cfg, q)
    if not cal.success:
        raise ValueError(f"{freq_hz} Hz: no calibrated hop on the soft surface (closest: stance {1000 * cal.stance_s:.0f} ms, "
                         f"flight {1000 * cal.flight_s:.0f} ms at touchdown speed {cal.speed_m_s:.2f} m/s)")
    law = scale_push_off(cfg.law, cal.push_scale)
    td = touchdown_state(chain, q, np.array([0.0, -cal.speed_m_s]), 0.0)
    pad = cfg.surface.pad if isinstance(cfg.surface, PaddedGround) else None  # keep_pad: the pad on both surfaces
    soft, hard = (simulate_stance(chain, law, with_pad(ground, pad), td, friction_coefficient=cfg.friction_coefficient,
                                  trunk_balance=cfg.trunk_balance) for ground in (SOFT, HARD))

    def flexion(st: StanceSimulation) -> np.ndarray:
        return np.max(st.rho_rad, axis=0) - st.rho_rad[0]

    return SurfaceSurprise(leg_stiffness_n_per_m(chain, soft), leg_stiffness_n_per_m(chain, hard),
                           flexion(hard) - flexion(soft), joint_stiffness_nm_rad(soft), joint_stiffness_nm_rad(hard),
                           soft, hard, float(cal.push_scale))
