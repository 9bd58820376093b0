"""Continuous hopping: stance by forward integration, flight prescribed and ballistic.

Flight model (a documented simplification; ``HoppingConfig.flight``)
--------------------------------------------------------------------
Integrating the free four-segment chain through flight is hard to steer to a
chosen landing posture. Instead, during flight the whole-body centre of mass
follows the exact ballistic path from its take-off position and velocity,
and the segment angles follow a quintic (``scipy.interpolate.BPoly``) from
their take-off angle, velocity and acceleration to the next touchdown posture
with zero acceleration; the toe is placed so that the COM is where the
ballistic path puts it. The force plate reads zero in flight. Whole-body
angular momentum is not conserved in flight (the angles are prescribed); no
quantity the analysis uses depends on it.

- ``"prescribed"`` (default): the segments arrive at rest (only the rates that
  keep the toe still horizontally), so the kinetic energy of segment motion
  relative to the COM at take-off is discarded (issue 17: 28 / 7 / 3 J per
  hop at 1.53 / 1.87 / 2.2 Hz).
- ``"energy_keeping"``: the touchdown segment rates carry that energy plus what
  the joint springs give back in flight, along the
  time-reversed take-off rates (:func:`flight_segment_rates`); with the COM
  ballistic, kinetic + gravitational + stored elastic energy at touchdown equals
  that at take-off (test/simulation/test_sim_flight_energy.py). Not the
  library's default; the seed-like preset's flight in session 32
  (scenarios.SEED_LIKE_HOPPER_FLIGHT, landing ``"prescribed"``). With lossless
  laws and no push-off, what the hop gains or loses is then the work of a non-conservative part: the trunk balance's
  (:class:`~hop_impedance.simulation.impedance_laws.TrunkBalance`, a moment on
  the trunk's absolute pitch acting at the hip). With a hip spring in its place
  the energy at touchdown stays the same to 3e-8 over 30 hops and the hop keeps
  its stance time and apex within 1.2 % (test/simulation/test_sim_lossless_hops.py;
  the hop-to-hop map and its periodic orbits: :mod:`~hop_impedance.simulation.periodic_hop`). The seed-like
  hopper's lossless counterpart keeps its hop with a conservative landing feedback (:class:`LandingFeedback`,
  scenarios.seed_like_lossless_config, test/simulation/test_sim_lossless_seed_like.py).
- ``"trunk_held"`` (session 24, off by default): the energy-keeping flight with the
  trunk balance holding the trunk in flight (:func:`trunk_held_segment_rates`): the
  trunk (q4) lands with zero absolute pitch rate, the legs (q1..q3) carry the rest
  of the carried energy along the landing direction's leg part, and the trunk's
  share of the landing motion is taken out by the balance in flight, reported per
  hop (``HoppingTrial.flight_balance_loss_j``; the energy budget's
  ``flight_balance_loss_j``), so energy at touchdown = energy at take-off - that
  loss exactly. The calibration's rounds use the same flight.
- ``"trunk_still"`` (session 32, off by default): the energy-keeping flight landing
  the trunk without pitching as ``"trunk_held"`` does, but with nothing taken out:
  the legs carry all of the carried energy (:func:`touchdown_segment_rates` with the
  trunk held), so energy at touchdown = energy at take-off as for
  ``"energy_keeping"``; only the landing motion's direction differs (the trunk's
  part of it moved to the legs). The seed-like preset's flight since session 33
  (scenarios.SEED_LIKE_HOPPER_FLIGHT; docs/simulator.md, "Session 32" and "Session 33").

Touchdown and hop sequencing
----------------------------
- Touchdown posture: joint angles ``rho_td`` (+ seeded N(0, posture_sd) per hop);
  the foot angle q1 is chosen so that the COM is a set distance in front of
  the toe: the calibrated offset that gives zero horizontal take-off velocity,
  minus a Raibert-style foot-placement term ``vx (stance/2 + placement_gain_s)``
  that keeps the hopper in place.
- Segment angular velocities at touchdown: zero, plus the smallest correction
  that makes the toe's horizontal velocity zero (so that the no-slip stance
  starts without a horizontal impact).
- The flight time follows from the take-off velocity (ballistic) and the next
  touchdown posture. Before the first hop, :func:`calibrate` solves (with
  ``scipy.optimize.root``) for the touchdown speed and push-off scale that make
  the hop periodic (next touchdown speed = this one) with period ``1/freq``. Hop
  by hop a proportional controller corrects the push-off scale from the
  touchdown-speed error, with seeded variability of the target.
- If the law has no push-off part, only the touchdown speed is calibrated;
  hops then grow or decay according to the law's energy balance.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, fields, replace

import numpy as np
from scipy.interpolate import BPoly
from scipy.optimize import brentq, least_squares

from hop_impedance.biomech.joint_angles import joint_angles, segment_angles_from_joint_angles
from hop_impedance.simulation.dynamics import (
    Chain,
    body_com,
    com_offset_jacobian,
    com_velocity,
    internal_kinetic_energy_j,
    internal_mass_matrix,
)
from hop_impedance.simulation.ground import Ground
from hop_impedance.simulation.impedance_laws import (
    BiarticularSpring,
    CompositeLaw,
    Eq3Law,
    ImpedanceLaw,
    PushOff,
    TrunkBalance,
    law_part,
)
from hop_impedance.simulation.passive_flight import passive_duration_s, passive_knots
from hop_impedance.simulation.stance import (
    DEFAULT_ATOL,
    DEFAULT_FRICTION_COEFFICIENT,
    DEFAULT_RTOL,
    StanceSimulation,
    TouchdownState,
    resample_stance,
    simulate_stance,
)

#: A contact shorter than this is a bounce of the foot, not a hop (s).
MIN_HOP_STANCE_S = 0.05
#: Flight models of :class:`HoppingConfig` (module docstring).
FLIGHT_MODELS = ("prescribed", "energy_keeping", "trunk_held", "trunk_still")
#: The flight models whose touchdown rates carry the take-off's segment energy (all of it, or less the trunk's share).
ENERGY_KEEPING_FLIGHTS = ("energy_keeping", "trunk_held", "trunk_still")
#: The flights that land the trunk without pitching (zero absolute trunk rate at every touchdown, the calibrated one's
#: rates moved to the trial's posture through the legs only, :func:`trunk_held_toe_correction`).
TRUNK_AT_REST_FLIGHTS = ("trunk_held", "trunk_still")
#: Landing directions of the energy-keeping flight (:attr:`HoppingConfig.landing`).
LANDINGS = ("reversed", "prescribed")


def joint_triple(values: Iterable[float]) -> tuple[float, float, float]:
    """Three per-joint values (ankle, knee, hip) as floats, e.g. :attr:`HoppingConfig.touchdown_rho_rad`."""
    ankle, knee, hip = (float(v) for v in values)
    return ankle, knee, hip


@dataclass(frozen=True)
class LandingFeedback:
    """Issue 17: a conservative landing controller for the energy-keeping flight (:func:`landing_for_hop`).

    In flight the hopper chooses how it lands, from the touchdown state ``x`` of the hop it is in
    (:mod:`~hop_impedance.simulation.periodic_hop`'s vector: touchdown speed, COM vx, COM ahead of the toe,
    segment rates): the direction of its landing segment rates ``landing_ref + u[:4]`` and the foot placement's
    reference offset ``com_ahead_ref_m + u[4]``, with ``u = -gain (x - state_ref)``. Neither changes the energy
    (the flight gives the landing rates the energy it carries, whatever their direction, and the placement only
    turns the touchdown posture about the toe), so the hopper stays conservative; a periodic hop ``state_ref``
    whose landing and placement are ``landing_ref``, ``com_ahead_ref_m`` stays periodic, and ``gain``
    (:func:`~hop_impedance.simulation.periodic_hop.landing_feedback`) makes it attract nearby hops of the same
    energy (hops of another energy go to the periodic hop of theirs: nothing restores energy without work).

    Attributes
    ----------
    state_ref : 7 floats
        The periodic hop's touchdown state.
    landing_ref : 4 floats
        Its landing rates (rad/s; HoppingConfig.landing_rates_rad_s).
    com_ahead_ref_m : float
        Its foot placement's reference offset (m; HopCalibration.com_ahead_m).
    gain : 5 x 7 nested tuples
        Feedback gain (rad/s and m per unit of the state's entries).
    """

    state_ref: tuple[float, ...]
    landing_ref: tuple[float, ...]
    com_ahead_ref_m: float
    gain: tuple[tuple[float, ...], ...]

    def choose(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        """(landing rates rad/s shape (4,), placement reference m) for touchdown state ``x``."""
        u = -np.asarray(self.gain, float) @ (np.asarray(x, float) - np.asarray(self.state_ref, float))
        return np.asarray(self.landing_ref, float) + u[:4], self.com_ahead_ref_m + float(u[4])


@dataclass(frozen=True)
class HoppingConfig:
    """Everything that defines a hopping trial (all SI).

    Attributes
    ----------
    freq_hz : float
        Target hop frequency (Hz).
    n_hops : int
    surface : GroundLaw
        Expected surface (the one the calibration uses).
    law : ImpedanceLaw
        Joint torque law; a :class:`PushOff` part (inside a CompositeLaw) is
        scaled by the controller.
    touchdown_rho_rad : tuple of 3 floats
        Nominal joint angles at touchdown (rad).
    com_ahead_m : float
        COM horizontal position in front of the toe at touchdown (m).
    unexpected_surface : GroundLaw or None
        Surface used instead of ``surface`` on the hops in ``unexpected_hops``
        (0-based), without changing the law (seed 001's unexpected surface).
    posture_sd_rad, speed_sd, push_sd : float
        Hop-to-hop variability: joint angles (rad), target touchdown speed
        (fraction), push-off scale (fraction).
    placement_gain_s : float
        Horizontal balance: the COM is placed behind the toe by
        ``vx (stance/2 + placement_gain_s)`` at touchdown (s).
    lead_in_s : float
        Flight before the first touchdown (s); the recording starts there.
    rtol, atol : float
        Stance integration tolerances.
    friction_coefficient : float or None
        Coulomb friction of the sole (stance.py docstring); None = never slides.
    trunk_balance : TrunkBalance or None
        Postural moment at the hip holding the trunk at its touchdown inclination.
    flight : {"prescribed", "energy_keeping", "trunk_held", "trunk_still"}
        ``"prescribed"``: segments brought to rest at the next touchdown (the energy of segment
        motion at take-off is discarded). ``"energy_keeping"``: the touchdown segment rates carry
        that energy (:func:`flight_segment_rates`); module docstring. ``"trunk_held"``: the same with the
        trunk balance holding the trunk in flight (:func:`trunk_held_segment_rates`): zero absolute trunk rate
        at touchdown, the trunk's share of the landing motion an explicit flight loss (module docstring).
        ``"trunk_still"``: zero absolute trunk rate at touchdown with all of the carried energy in the legs.
    landing_rates_rad_s : 4 floats or None
        Energy-keeping flight only: land along these segment rates (rad/s; their direction, the
        magnitude carries the flight's energy) instead of the take-off rates reversed: a practised
        landing motion chosen in flight (issue 17; e.g. the touchdown rates of a periodic hop,
        :mod:`~hop_impedance.simulation.periodic_hop`). None (default): reversed take-off rates. The
        calibration's rounds keep the reversed rates, so it is the same with or without.
    first_touchdown : 7 floats or None
        The first touchdown state instead of the calibrated one: touchdown speed (m/s, down), COM vx
        (m/s), COM ahead of the toe (m), segment rates q1..q4 (rad/s), e.g. a periodic hop's
        (:func:`~hop_impedance.simulation.periodic_hop.periodic_hop`). None (default): calibrated.
        Given, the trial is not calibrated (:func:`given_start_calibration`): the push-off keeps its
        scale 1 and the foot placement's reference is ``com_ahead_m``.
    landing_feedback : LandingFeedback or None
        Energy-keeping flight only: choose each landing's rates and the foot placement's reference from the
        hop's own touchdown state (:class:`LandingFeedback`, :func:`landing_for_hop`) instead of the fixed
        ``landing_rates_rad_s`` and ``com_ahead_m``. None (default): fixed.
    landing : {"reversed", "prescribed"}
        Energy-keeping flight without ``landing_rates_rad_s`` only: the direction of the landing segment rates.
        ``"reversed"`` (default): the take-off rates reversed. ``"prescribed"``: the direction the prescribed
        flight's segments move in as they settle into the touchdown posture (:func:`prescribed_landing_direction`:
        its quintic arrives at rest, so the direction is that of its last motion, the third derivative at
        touchdown), i.e. the preset's own landing motion, chosen in flight as a practised landing; the energy
        the flight carries is unchanged, only its direction. The calibration's rounds use it too.
    push_off_gain : float
        The hop-by-hop push-off controller's gain as a fraction of its deadbeat one (:func:`_hop_push_scale`:
        the push-off scale is corrected by ``push_off_gain (target - speed) / d_speed_d_scale``). 1 (default):
        the deadbeat correction; smaller: a partial correction per hop (a steadier push-off).
    passive_takeoff_s, passive_landing_s : float
        The flight's first / last phase (s; each at most :data:`~hop_impedance.simulation.passive_flight.MAX_FLIGHT_FRACTION`
        of the flight) as the free chain with zero joint moments (:mod:`~hop_impedance.simulation.passive_flight`): the
        take-off and touchdown states, and so every stance, are unchanged; only the segments' motion in the air is (what
        the markers record), in every flight after a stance (the lead-in onto the first touchdown keeps its quintic).
        0 (default): the quintic from the take-off / to the touchdown.
    """

    freq_hz: float
    n_hops: int
    surface: Ground
    law: ImpedanceLaw
    touchdown_rho_rad: tuple[float, float, float]
    com_ahead_m: float = 0.0
    unexpected_surface: Ground | None = None
    unexpected_hops: tuple[int, ...] = ()
    posture_sd_rad: float = 0.01
    speed_sd: float = 0.02
    push_sd: float = 0.03
    placement_gain_s: float = 0.05
    lead_in_s: float = 0.4
    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL
    friction_coefficient: float | None = DEFAULT_FRICTION_COEFFICIENT
    trunk_balance: TrunkBalance | None = None
    flight: str = "prescribed"
    landing_rates_rad_s: tuple[float, ...] | None = None
    first_touchdown: tuple[float, ...] | None = None
    landing_feedback: LandingFeedback | None = None
    landing: str = "reversed"
    push_off_gain: float = 1.0
    passive_takeoff_s: float = 0.0
    passive_landing_s: float = 0.0

    def __post_init__(self) -> None:
        if self.flight not in FLIGHT_MODELS:
            raise ValueError(f"flight must be one of {FLIGHT_MODELS}, got {self.flight!r}")
        if self.landing not in LANDINGS:
            raise ValueError(f"landing must be one of {LANDINGS}, got {self.landing!r}")
        if not self.freq_hz > 0:
            raise ValueError(f"freq_hz must be positive, got {self.freq_hz}")
        if self.n_hops < 1:
            raise ValueError(f"n_hops must be at least 1, got {self.n_hops}")
        if not self.push_off_gain >= 0:
            raise ValueError(f"push_off_gain must be non-negative, got {self.push_off_gain}")
        for name in ("passive_takeoff_s", "passive_landing_s"):
            if not 0 <= getattr(self, name) < 1:
                raise ValueError(f"{name} must be in [0, 1) s, got {getattr(self, name)}")

    def surface_for_hop(self, hop: int) -> Ground:
        """Surface under hop ``hop`` (0-based)."""
        if self.unexpected_surface is not None and hop in self.unexpected_hops:
            return self.unexpected_surface
        return self.surface


def push_off_part(law: ImpedanceLaw) -> PushOff | None:
    """The push-off part of a law, if any."""
    return law_part(law, PushOff)


def scale_push_off(law: ImpedanceLaw, scale: float) -> ImpedanceLaw:
    """Copy of ``law`` whose push-off amplitude is multiplied by ``scale`` (>= 0)."""
    part = push_off_part(law)
    if part is None:
        return law
    new = part.with_amplitude(max(scale, 0.0) * part.amplitude_nm)
    if law is part:
        return new
    assert isinstance(law, CompositeLaw)  # push_off_part found the part in a composite
    return law.replace_part(part, new)


def touchdown_posture(chain: Chain, rho_rad: np.ndarray, com_ahead_m: float = 0.0) -> np.ndarray:
    """Segment angles q1..q4 (rad) with joint angles ``rho_rad`` and the COM ``com_ahead_m`` before the toe."""
    rho = np.asarray(rho_rad, float)[None]

    def com_x(q1: float) -> float:
        q = segment_angles_from_joint_angles(rho, np.array([q1]), chain.alpha_rad)[0]
        return body_com(chain, np.r_[0.0, 0.0, q])[0] - com_ahead_m

    grid = np.linspace(0.3, 3.0, 28)
    vals = np.array([com_x(v) for v in grid])
    sign_change = np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]
    if not len(sign_change):
        raise ValueError(f"no foot angle puts the COM {com_ahead_m} m ahead of the toe for rho = {rho_rad}")
    i = sign_change[0]
    q1 = brentq(com_x, grid[i], grid[i + 1], xtol=1e-12)
    return segment_angles_from_joint_angles(rho, np.array([q1]), chain.alpha_rad)[0]


def touchdown_state(chain: Chain, q: np.ndarray, com_velocity_m_s: np.ndarray, x_toe_m: float,
                    segment_rates: np.ndarray | None = None) -> TouchdownState:
    """Touchdown state with the toe at ``(x_toe, 0)`` and zero toe x velocity.

    Without ``segment_rates`` the segment angular velocities are the minimum-norm set that cancels
    the COM's horizontal velocity relative to the toe. With ``segment_rates`` (rad/s, shape (4,)),
    those rates are used after removing the part that would move the toe horizontally (the
    component along d(COM x - toe x)/dq is set to cancel the COM's horizontal velocity). The COM
    velocity is kept in both cases.
    """
    jac = com_offset_jacobian(chain, q)
    qd = jac[0] * (com_velocity_m_s[0] / float(jac[0] @ jac[0]))
    if segment_rates is not None:
        rates = np.asarray(segment_rates, float)
        qd = qd + rates - jac[0] * (float(jac[0] @ rates) / float(jac[0] @ jac[0]))
    toe_z_velocity = com_velocity_m_s[1] - float(jac[1] @ qd)
    return TouchdownState(np.r_[x_toe_m, 0.0, q], np.r_[0.0, toe_z_velocity, qd])


def returned_spring_energy_j(law: ImpedanceLaw, ref, rho_takeoff: np.ndarray, rho_touchdown: np.ndarray) -> float:
    """Elastic energy the joint springs give back in flight (J): U(take-off) - U(next touchdown).

    U is the Eq. 3 part's stored energy about its touchdown reference ``ref``
    (:meth:`Eq3Law.elastic_energy_j`); the spring keeps acting in flight until the next touchdown,
    where the reference is reset and what is left, U(next touchdown), is lost ("springs not
    returned"). A law without a conservative Eq. 3 part (activation, k3) returns nothing (0) from it. A
    :class:`~hop_impedance.simulation.impedance_laws.BiarticularSpring` part (conservative) returns its own the same
    way, added.
    """
    eq3, biarticular = law_part(law, Eq3Law), law_part(law, BiarticularSpring)
    returned = 0.0
    if eq3 is not None:
        try:
            returned = float(eq3.elastic_energy_j(np.asarray(rho_takeoff, float), ref)
                             - eq3.elastic_energy_j(np.asarray(rho_touchdown, float), ref))
        except NotImplementedError:
            returned = 0.0
    if biarticular is not None:
        returned += float(biarticular.elastic_energy_j(rho_takeoff, ref) - biarticular.elastic_energy_j(rho_touchdown, ref))
    return returned


def _toe_row(chain: Chain, q: np.ndarray, held: int | None = None) -> np.ndarray:
    """d(COM x - toe x)/dq in posture ``q`` (shape (4,)): the segment rates' horizontal toe velocity relative to the
    COM; with ``held`` that segment's entry zero (the rates that keep the toe still then leave it at rest)."""
    j0 = com_offset_jacobian(chain, q)[0]
    if held is not None:
        j0 = j0.copy()
        j0[held] = 0.0
    return j0


def touchdown_segment_rates(chain: Chain, q: np.ndarray, com_vx_m_s: float, direction: np.ndarray,
                            internal_energy_j: float, held: int | None = None) -> tuple[np.ndarray, float]:
    """Segment rates at touchdown that carry ``internal_energy_j`` of motion relative to the COM.

    The rates are ``base + s u``: ``base`` the minimum-norm rates that keep the toe still
    horizontally, ``u`` the part of ``direction`` that does not move the toe horizontally, and
    ``s >= 0`` solves ``0.5 qd^T M_int qd = internal_energy_j`` (:func:`internal_mass_matrix`).
    With ``held`` (a segment index) that segment's rate is zero: ``base`` and ``u`` use the other
    segments only (:func:`_toe_row`).

    Returns
    -------
    rates : ndarray, shape (4,)
        Segment angular velocities (rad/s).
    not_placed_j : float
        Energy that could not be given to the segments (J): positive when ``internal_energy_j`` is
        below what ``base`` alone carries, or when ``direction`` is zero; 0 normally.
    """
    q = np.asarray(q, float)
    j0 = _toe_row(chain, q, held)
    base = j0 * (com_vx_m_s / float(j0 @ j0))
    d = np.array(direction, float)
    if held is not None:
        d[held] = 0.0
    u = d - j0 * (float(j0 @ d) / float(j0 @ j0))
    m_int = internal_mass_matrix(chain, q)
    a, b, c = 0.5 * float(u @ m_int @ u), float(u @ m_int @ base), 0.5 * float(base @ m_int @ base)
    disc = b * b - 4.0 * a * (c - internal_energy_j)
    if a <= 1e-12 or disc < 0.0 or (-b + np.sqrt(disc)) < 0.0:
        return base, float(internal_energy_j - c)
    s = (-b + np.sqrt(disc)) / (2.0 * a)
    return base + s * u, 0.0


@dataclass(frozen=True)
class Flight:
    """A prescribed flight phase from take-off to the next touchdown (or the recording end)."""

    t_start_s: float
    duration_s: float
    com0_m: np.ndarray
    com_vel0_m_s: np.ndarray
    angles: BPoly
    gravity_m_s2: float

    def evaluate(self, chain: Chain, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Generalized coordinates and velocities, each shape (N, 6), at absolute times ``t_s``."""
        tau = np.clip(np.asarray(t_s, float) - self.t_start_s, 0.0, self.duration_s)
        com = self.com0_m + np.outer(tau, self.com_vel0_m_s)
        com[:, 1] -= 0.5 * self.gravity_m_s2 * tau**2
        vel = np.tile(self.com_vel0_m_s, (len(tau), 1))
        vel[:, 1] -= self.gravity_m_s2 * tau
        q = self.angles(tau)
        qd = self.angles.derivative()(tau)
        g = np.zeros((len(tau), 6))
        g[:, 2:] = q
        offset = body_com(chain, g)
        g[:, 0:2] = com - offset
        gd = np.zeros_like(g)
        gd[:, 2:] = qd
        jac = np.array([com_offset_jacobian(chain, qi) for qi in q])
        gd[:, 0:2] = vel - np.einsum("nak,nk->na", jac, qd)
        return g, gd


def flight_time_s(chain: Chain, com_z_m: float, com_vz_m_s: float, q_next: np.ndarray) -> float:
    """Ballistic time until the COM is at the height that puts the toe on z = 0 in posture ``q_next`` (s).

    Raises ValueError if the body cannot get there (take-off too weak).
    """
    height = com_z_m - body_com(chain, np.r_[0.0, 0.0, q_next])[1]
    disc = com_vz_m_s**2 + 2.0 * chain.gravity_m_s2 * height
    if disc < 0:
        raise ValueError("take-off too weak: the COM never returns to touchdown height")
    t = (com_vz_m_s + np.sqrt(disc)) / chain.gravity_m_s2
    if not t > 0:
        raise ValueError("take-off too weak: no flight phase")
    return float(t)


@dataclass
class StanceRecord:
    """One simulated stance inside a trial."""

    index: int
    t_touchdown_s: float
    stance: StanceSimulation
    surface: Ground
    law: ImpedanceLaw
    touchdown: TouchdownState

    @property
    def t_takeoff_s(self) -> float:
        """Take-off instant (s since recording start)."""
        return self.t_touchdown_s + self.stance.duration_s


@dataclass
class HoppingTrial:
    """A simulated trial: stances, flights and everything needed to sample sensors."""

    config: HoppingConfig
    chain: Chain
    stances: list[StanceRecord]
    flights: list[Flight]
    t_end_s: float
    calibration: HopCalibration | None
    stop_reason: str = ""
    notes: list[str] = field(default_factory=list)
    #: Energy the trunk balance took out in the flight after each stance (J; one entry per flight that ends in a
    #: touchdown, the last hop's flight ending at its apex has none; > 0 with the ``"trunk_held"`` flight only, 0 for
    #: the other flights).
    flight_balance_loss_j: list[float] = field(default_factory=list)

    def sample(self, t_s: np.ndarray) -> dict[str, np.ndarray]:
        """True state at absolute times ``t_s`` (s), shape (N,).

        Returns
        -------
        dict with ``g``, ``gd`` (N, 6), ``grf_n`` (N, 2) ([Fx, Fz] at the toe),
        ``moments_nm`` (N, 3) (NaN in flight: prescribed kinematics),
        ``stance_index`` (N,) int (-1 in flight).
        """
        t_s = np.asarray(t_s, float)
        n = len(t_s)
        out = {
            "g": np.full((n, 6), np.nan),
            "gd": np.full((n, 6), np.nan),
            "grf_n": np.zeros((n, 2)),
            "moments_nm": np.full((n, 3), np.nan),
            "stance_index": np.full(n, -1),
        }
        for fl in self.flights:
            sel = (t_s >= fl.t_start_s) & (t_s <= fl.t_start_s + fl.duration_s)
            if sel.any():
                out["g"][sel], out["gd"][sel] = fl.evaluate(self.chain, t_s[sel])
        for rec in self.stances:
            sel = (t_s >= rec.t_touchdown_s) & (t_s <= rec.t_takeoff_s)
            if not sel.any():
                continue
            st = simulate_resample(self.chain, rec, t_s[sel] - rec.t_touchdown_s)
            out["g"][sel], out["gd"][sel] = st.g, st.gd
            out["grf_n"][sel], out["moments_nm"][sel] = st.grf_n, st.moments_nm
            out["stance_index"][sel] = rec.index
        return out


def simulate_resample(chain: Chain, rec: StanceRecord, t_since_td: np.ndarray) -> StanceSimulation:
    """The stance of ``rec`` evaluated at other times since touchdown (dense output, no re-integration)."""
    return resample_stance(chain, rec.law, rec.surface, rec.touchdown, rec.stance, t_since_td)


def _next_touchdown_speed(chain: Chain, stance: StanceSimulation, q_next: np.ndarray) -> tuple[float, float]:
    """(flight time (s), touchdown COM vertical speed (m/s, positive down)) after a stance."""
    g, gd = stance.g[-1], stance.gd[-1]
    vz = com_velocity(chain, g, gd)[1]
    t_f = flight_time_s(chain, body_com(chain, g)[1], vz, q_next)
    return t_f, -(vz - chain.gravity_m_s2 * t_f)


def flight_segment_rates(chain: Chain, law: ImpedanceLaw, stance: StanceSimulation, q_next: np.ndarray,
                         com_vx_m_s: float, landing_rates_rad_s=None) -> tuple[np.ndarray, float, float]:
    """Segment rates at the touchdown after ``stance``: the flight keeps the energy of segment motion.

    Energy carried = kinetic energy of the segments relative to the COM at take-off + what the joint
    springs give back in flight (:func:`returned_spring_energy_j`); it is put into the touchdown
    rates along the time-reversed take-off rates (:func:`touchdown_segment_rates`), so a lossless
    stance is followed by (nearly) its mirror image; with ``landing_rates_rad_s`` along those rates
    instead (:attr:`HoppingConfig.landing_rates_rad_s`). The COM itself is ballistic, so kinetic +
    gravitational energy of the COM is conserved exactly; together nothing is discarded in flight.

    Returns
    -------
    (rates rad/s shape (4,), energy carried J, energy not placed J)
    """
    carried, direction = _carried_flight_energy(chain, law, stance, q_next, landing_rates_rad_s)
    rates, not_placed = touchdown_segment_rates(chain, q_next, com_vx_m_s, direction, carried)
    return rates, carried, not_placed


def _carried_flight_energy(chain: Chain, law: ImpedanceLaw, stance: StanceSimulation, q_next: np.ndarray,
                           landing_rates_rad_s=None) -> tuple[float, np.ndarray]:
    """(energy the flight after ``stance`` carries to the touchdown in posture ``q_next`` (J): the segments' kinetic
    energy relative to the COM at take-off + :func:`returned_spring_energy_j`; the landing direction: the take-off
    rates reversed, or ``landing_rates_rad_s``)."""
    g, gd = stance.g[-1], stance.gd[-1]
    rho_next = joint_angles(np.asarray(q_next, float)[None], chain.alpha_rad)[0]
    carried = internal_kinetic_energy_j(chain, g[2:], gd[2:]) + returned_spring_energy_j(
        law, stance.ref, stance.rho_rad[-1], rho_next)
    return carried, -gd[2:] if landing_rates_rad_s is None else np.asarray(landing_rates_rad_s, float)


#: Index of the trunk (HAT) among the segment angles q1..q4.
TRUNK_SEGMENT = 3


def trunk_held_segment_rates(chain: Chain, q: np.ndarray, com_vx_m_s: float, direction: np.ndarray,
                             internal_energy_j: float) -> tuple[np.ndarray, float, float]:
    """Touchdown rates of the ``"trunk_held"`` flight: the trunk balance has held the trunk in flight.

    The landing the energy-keeping flight would give, ``full`` = :func:`touchdown_segment_rates` (``direction``,
    ``internal_energy_j``), is split at the trunk: the balance (a moment on the trunk's absolute pitch,
    :class:`~hop_impedance.simulation.impedance_laws.TrunkBalance`) stops the trunk's pitch, which, done by an
    impulse along q4, takes out ``loss = 0.5 full[3]^2 / (M^-1)[3, 3]`` (M the segments' mass matrix relative to
    the COM, :func:`internal_mass_matrix`): the M-orthogonal split of T(full) into the motion with the trunk at
    rest and the trunk's share, so ``0 <= loss <= internal_energy_j``. The legs then land carrying
    ``internal_energy_j - loss``: :func:`touchdown_segment_rates` with the trunk held (zero absolute trunk pitch
    rate at touchdown, so the balance's damper starts the stance at rest; the legs along the leg part of
    ``direction``).

    Returns
    -------
    rates : ndarray, shape (4,)
        Segment angular velocities (rad/s); ``rates[3]`` is zero.
    loss_j : float
        Energy the balance took out in flight (J).
    not_placed_j : float
        Energy that could not be given to the legs (J; :func:`touchdown_segment_rates`'s), 0 normally.
    """
    q = np.asarray(q, float)
    full, not_placed_full = touchdown_segment_rates(chain, q, com_vx_m_s, direction, internal_energy_j)
    m_int = internal_mass_matrix(chain, q)
    loss = 0.5 * full[TRUNK_SEGMENT] ** 2 / float(np.linalg.inv(m_int)[TRUNK_SEGMENT, TRUNK_SEGMENT])
    rates, not_placed = touchdown_segment_rates(chain, q, com_vx_m_s, direction,
                                                internal_energy_j - not_placed_full - loss, held=TRUNK_SEGMENT)
    return rates, float(loss), float(not_placed_full + not_placed)


def trunk_held_toe_correction(chain: Chain, q: np.ndarray, com_vx_m_s: float, rates: np.ndarray) -> np.ndarray:
    """``rates`` (trunk entry zero) with the leg part along d(COM x - toe x)/dq set so the toe is still horizontally
    in posture ``q`` at COM vx ``com_vx_m_s``: the ``"trunk_held"`` flight's touchdown rates computed in another
    posture (the calibration's, for the first hop and the COM-offset probes) moved to ``q`` without giving the trunk
    a rate (:func:`touchdown_state` then keeps them as they are)."""
    j0 = _toe_row(chain, np.asarray(q, float), TRUNK_SEGMENT)
    r = np.array(rates, float)
    r[TRUNK_SEGMENT] = 0.0
    return r + j0 * ((com_vx_m_s - float(j0 @ r)) / float(j0 @ j0))


def flight_rates(chain: Chain, config: HoppingConfig, law: ImpedanceLaw, stance: StanceSimulation,
                 q_next: np.ndarray, com_vx_m_s: float, direction=None) -> tuple[np.ndarray, float, float]:
    """(touchdown rates rad/s, balance loss J, energy not placed J) of ``config.flight``'s energy-keeping flights:
    :func:`flight_segment_rates` (``"energy_keeping"``, loss 0), the same carried energy landed with the trunk
    held (``"trunk_held"``, :func:`trunk_held_segment_rates`, the trunk's share lost) or landed with the trunk at rest
    and all of it in the legs (``"trunk_still"``: :func:`touchdown_segment_rates` with the trunk held, loss 0), along
    ``direction`` (None: the take-off rates reversed)."""
    if config.flight not in TRUNK_AT_REST_FLIGHTS:
        rates, _, not_placed = flight_segment_rates(chain, law, stance, q_next, com_vx_m_s, direction)
        return rates, 0.0, not_placed
    carried, d = _carried_flight_energy(chain, law, stance, q_next, direction)
    if config.flight == "trunk_still":
        rates, not_placed = touchdown_segment_rates(chain, q_next, com_vx_m_s, d, carried, held=TRUNK_SEGMENT)
        return rates, 0.0, not_placed
    return trunk_held_segment_rates(chain, q_next, com_vx_m_s, d, carried)


def prescribed_landing_direction(chain: Chain, stance: StanceSimulation, q_next: np.ndarray,
                                 com_vx_m_s: float, t_flight_s: float) -> np.ndarray:
    """The direction of the prescribed flight's landing motion after ``stance`` (shape (4,), unit norm).

    The prescribed flight's segment angles are a quintic from the take-off angles, rates and accelerations
    to the touchdown posture ``q_next`` with the toe-correction rates only (:func:`touchdown_state` without
    rates, ``com_vx_m_s``) and zero acceleration; those rates lie along d(COM x - toe x)/dq, the one
    direction the energy-keeping flight cannot give energy to (:func:`touchdown_segment_rates` removes
    it). Just before touchdown the quintic's rates are (toe correction) + h^2/2 d3q/dt3(touchdown), h the
    time left, so the direction the segments move in as they land is that of its third derivative there.
    """
    g_to, gd_to = stance.g[-1], stance.gd[-1]
    end_rates = touchdown_state(chain, np.asarray(q_next, float), np.array([com_vx_m_s, -1.0]), 0.0).gd[2:]
    angles = BPoly.from_derivatives(
        [0.0, t_flight_s],
        np.array([[g_to[2:], gd_to[2:], stance.gdd[-1, 2:]], [np.asarray(q_next, float), end_rates, np.zeros(4)]]),
    )
    jerk = np.asarray(angles.derivative(3)(t_flight_s), float)
    norm = float(np.linalg.norm(jerk))
    return jerk / norm if norm > 0 else jerk


def landing_direction(chain: Chain, config: HoppingConfig, stance: StanceSimulation, q_next: np.ndarray,
                      com_vx_m_s: float, t_flight_s: float) -> np.ndarray | None:
    """The energy-keeping flight's landing direction (``landing_rates_rad_s`` of :func:`flight_segment_rates`):
    ``config.landing_rates_rad_s`` if given, else :attr:`HoppingConfig.landing`'s (None: reversed take-off rates)."""
    if config.landing_rates_rad_s is not None:
        return np.asarray(config.landing_rates_rad_s, float)
    if config.landing == "prescribed":
        return prescribed_landing_direction(chain, stance, q_next, com_vx_m_s, t_flight_s)
    return None


#: Rounds of the calibration's fixed point on the touchdown segment rates (each one least-squares solve).
CALIBRATION_FLIGHT_ROUNDS = 3


@dataclass(frozen=True)
class HopCalibration:
    """The periodic hop :func:`calibrate` found (all SI).

    Attributes
    ----------
    speed_m_s : float
        Touchdown COM vertical speed (m/s, positive down).
    push_scale : float
        Push-off amplitude scale (1 when the law has no push-off part).
    stance_s, flight_s : float
        Stance and flight of the calibrated hop (s).
    next_speed_m_s : float
        Touchdown speed after the calibrated hop (m/s); ``speed_m_s`` for an exactly periodic hop.
    d_speed_d_scale : float
        Next touchdown speed per unit push-off scale (m/s; the hop-by-hop controller's gain basis;
        0 without a push-off part).
    success : bool
        False when the best compromise misses the speed by more than 0.01 m/s or the period by more
        than 5 ms (e.g. a frequency that the law cannot reach).
    com_ahead_m : float
        COM ahead of the toe at touchdown that makes the take-off vx zero (m; clipped to 5 cm about
        ``HoppingConfig.com_ahead_m``).
    take_off_vx_m_s : float
        Take-off horizontal COM velocity with the COM ``HoppingConfig.com_ahead_m`` ahead (m/s).
    d_vx_d_com_ahead_s : float
        Its change per metre of COM offset (1/s).
    touchdown_rates_rad_s : ndarray, shape (4,)
        Segment rates at touchdown (rad/s; zero unless the energy-keeping flight is calibrated).
    """

    speed_m_s: float
    push_scale: float
    stance_s: float
    flight_s: float
    next_speed_m_s: float
    d_speed_d_scale: float
    success: bool
    com_ahead_m: float
    take_off_vx_m_s: float
    d_vx_d_com_ahead_s: float
    touchdown_rates_rad_s: np.ndarray

    def to_dict(self) -> dict:
        """Plain numbers for the truth file; the rates as ``touchdown_rate_q1_rad_s`` .. ``q4``."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "touchdown_rates_rad_s"}
        return {**out, **{f"touchdown_rate_q{k + 1}_rad_s": float(r) for k, r in enumerate(self.touchdown_rates_rad_s)}}


@dataclass(frozen=True)
class _CalibrationHop:
    """One hop of the calibration from the touchdown posture ``q_td``: stance at 100 x the trial's tolerances."""

    chain: Chain
    config: HoppingConfig
    q_td: np.ndarray

    def stance(self, speed: float, scale: float, q: np.ndarray, rates: np.ndarray | None):
        """(law with the push-off scaled, stance) from posture ``q`` at touchdown speed ``speed`` (m/s).

        Raises ValueError if the stance does not end in take-off.
        """
        config, period = self.config, 1.0 / self.config.freq_hz
        law = scale_push_off(config.law, scale)
        if config.flight in TRUNK_AT_REST_FLIGHTS and rates is not None:
            rates = trunk_held_toe_correction(self.chain, q, 0.0, rates)
        td = touchdown_state(self.chain, q, np.array([0.0, -speed]), 0.0, rates)
        st = simulate_stance(self.chain, law, config.surface, td, t_max_s=2.0 * period,
                             rtol=config.rtol * 100, atol=config.atol * 100,
                             friction_coefficient=config.friction_coefficient, trunk_balance=config.trunk_balance)
        if st.end_reason != "take_off":
            raise ValueError(f"calibration stance ended by {st.end_reason} at speed {speed:.2f} m/s")
        return law, st

    def run(self, speed: float, scale: float, rates: np.ndarray | None) -> tuple[float, float, float]:
        """(stance s, flight s, next touchdown speed m/s) of the hop from ``q_td``."""
        _, st = self.stance(speed, scale, self.q_td, rates)
        t_f, v_next = _next_touchdown_speed(self.chain, st, self.q_td)
        return st.duration_s, t_f, v_next


def calibrate(chain: Chain, config: HoppingConfig, q_td: np.ndarray, speed_guess: float | None = None) -> HopCalibration:
    """Touchdown speed, segment rates and push-off scale for a periodic hop at ``config.freq_hz``.

    For fixed touchdown segment rates, solves ``next touchdown speed = touchdown speed`` and
    ``stance + flight = 1 / freq`` in the least-squares sense (:func:`_solve_periodic_hop`);
    without a push-off part only the period equation (touchdown speed only). The touchdown rates
    start at zero and are then replaced ``CALIBRATION_FLIGHT_ROUNDS - 1`` times by the rates the
    energy-keeping flight (:func:`flight_segment_rates`) gives after the calibrated stance, so the
    first hop starts near the periodic hop's own touchdown motion (:func:`_calibrate_touchdown_rates`).
    ``success`` is False when the best compromise misses the speed by more than
    0.01 m/s or the period by more than 5 ms (e.g. a frequency that the law
    cannot reach); the caller then reports the achieved values. The COM offset at touchdown
    comes from :func:`_balanced_com_ahead`. Returns a :class:`HopCalibration`.
    """
    period = 1.0 / config.freq_hz
    has_push = push_off_part(config.law) is not None
    hop = _CalibrationHop(chain, config, q_td)
    speed = chain.gravity_m_s2 * 0.4 * period / 2.0 if speed_guess is None else speed_guess
    speed, scale, rates = _calibrate_touchdown_rates(hop, has_push, speed)
    ts, tf, v1 = hop.run(speed, scale, rates)
    slope = 0.0
    if has_push:
        _, _, v2 = hop.run(speed, scale + 0.1, rates)
        slope = (v2 - v1) / 0.1
    success = abs(v1 - speed) < 0.01 if has_push else True
    success = success and abs(ts + tf - period) < 0.005
    base = config.com_ahead_m
    com_ahead, vx0, vx1 = _balanced_com_ahead(hop, speed, scale, rates)
    rates_out = np.zeros(4) if rates is None else rates
    return HopCalibration(
        speed_m_s=speed, push_scale=scale, stance_s=ts, flight_s=tf, next_speed_m_s=v1, d_speed_d_scale=slope,
        success=bool(success), com_ahead_m=float(np.clip(com_ahead, base - 0.05, base + 0.05)),
        take_off_vx_m_s=float(vx0), d_vx_d_com_ahead_s=float((vx1 - vx0) / 0.01),
        touchdown_rates_rad_s=np.array([float(rates_out[k]) for k in range(4)]))


def _solve_periodic_hop(hop: _CalibrationHop, has_push: bool, rates: np.ndarray | None,
                        guess: list[float]) -> tuple[float, float]:
    """(touchdown speed m/s, push-off scale) of the periodic hop for fixed touchdown ``rates``.

    ``scipy.optimize.least_squares``, bounded (speed 0.2-3 m/s, scale 0-20), on ``next speed -
    speed`` and the period error; without a push-off part the period error alone (scale 1). A
    touchdown speed whose stance does not take off scores 1 on every residual.
    """
    period = 1.0 / hop.config.freq_hz

    def residual(x):
        try:
            ts, tf, v_next = hop.run(x[0], x[1] if has_push else 1.0, rates)
        except ValueError:
            return [1.0, 1.0] if has_push else [1.0]
        period_error = (ts + tf - period) * 5.0  # 1 ms of period weighs like 5 mm/s of speed
        return [v_next - x[0], period_error] if has_push else [period_error]

    if has_push:
        sol = least_squares(residual, guess, bounds=([0.2, 0.0], [3.0, 20.0]),
                            diff_step=1e-3, xtol=1e-8, ftol=1e-10)
        return float(sol.x[0]), float(sol.x[1])
    sol = least_squares(residual, guess[:1], bounds=([0.2], [3.0]), diff_step=1e-3, xtol=1e-8)
    return float(sol.x[0]), 1.0


def _calibrate_touchdown_rates(hop: _CalibrationHop, has_push: bool,
                               speed: float) -> tuple[float, float, np.ndarray | None]:
    """(speed m/s, push-off scale, touchdown rates rad/s or None) after the calibration's rounds.

    One round (:func:`_solve_periodic_hop` with zero rates) for the prescribed flight;
    :data:`CALIBRATION_FLIGHT_ROUNDS` for the energy-keeping one, each next round's rates those the
    energy-keeping flight gives after this round's stance. A round whose solution does not hop ends
    the rounds; the last round whose solution hops is kept.
    """
    chain, q_td = hop.chain, hop.q_td
    scale, rates = 1.0, None
    rounds = CALIBRATION_FLIGHT_ROUNDS if hop.config.flight in ENERGY_KEEPING_FLIGHTS else 1
    # (speed, scale, rates) of the last round whose solution hops
    accepted: tuple[float, float, np.ndarray | None] | None = None
    for round_ in range(rounds):
        speed, scale = _solve_periodic_hop(hop, has_push, rates, [speed, scale])
        if rounds == 1:
            break
        try:
            law, st = hop.stance(speed, scale, q_td, rates)
            t_f, _ = _next_touchdown_speed(chain, st, q_td)
        except ValueError:
            break  # this round's rates lead to no hop: keep the previous round's solution
        accepted = (speed, scale, rates)
        if round_ < rounds - 1:
            direction = None if hop.config.landing == "reversed" else landing_direction(
                chain, hop.config, st, q_td, 0.0, t_f)
            rates = flight_rates(chain, hop.config, law, st, q_td, 0.0, direction)[0]
    if accepted is not None:
        speed, scale, rates = accepted
    return speed, scale, rates


def _balanced_com_ahead(hop: _CalibrationHop, speed: float, scale: float,
                        rates: np.ndarray | None) -> tuple[float, float, float]:
    """Horizontal balance: the COM offset at touchdown that makes the take-off vx zero (secant, linear).

    Returns (offset m, unclipped; take-off vx at ``HoppingConfig.com_ahead_m``; at 1 cm more), m/s.
    """
    rho_td = np.asarray(hop.config.touchdown_rho_rad, float)
    base = hop.config.com_ahead_m

    def take_off_vx(ahead: float) -> float:
        _, st = hop.stance(speed, scale, touchdown_posture(hop.chain, rho_td, ahead), rates)
        return float(com_velocity(hop.chain, st.g[-1], st.gd[-1])[0])

    vx0, vx1 = take_off_vx(base), take_off_vx(base + 0.01)
    com_ahead = base - vx0 * 0.01 / (vx1 - vx0) if vx1 != vx0 else base
    return com_ahead, vx0, vx1


def simulate_hopping(chain: Chain, config: HoppingConfig, seed: int = 0, posture_offsets: dict | None = None) -> HoppingTrial:
    """Simulate ``config.n_hops`` hops; seeded variability (``posture_offsets``: hop >= 1 -> rad added to its rho_td).

    The trial starts ``lead_in_s`` before the first touchdown (in flight) and
    ends at the apex of the flight after the last stance, so no stance is cut
    at the recording edges. A stance that does not end in take-off (collapse,
    too long) or a take-off too weak to fly stops the trial early; the reason
    is kept in ``stop_reason``.
    """
    rng = np.random.default_rng(seed)
    rho_nom = np.asarray(config.touchdown_rho_rad, float)
    if config.first_touchdown is None:
        cal = calibrate(chain, config, touchdown_posture(chain, rho_nom, config.com_ahead_m))
    else:
        cal = given_start_calibration(config)
    notes = [] if cal.success else [_calibration_note(config, cal)]
    period = 1.0 / config.freq_hz
    q_td = touchdown_posture(chain, rho_nom, cal.com_ahead_m)
    td_rates = np.array(cal.touchdown_rates_rad_s, float)
    rates: np.ndarray | None = td_rates
    speed = cal.speed_m_s
    flights = [_lead_in_flight(chain, config, q_td, td_rates, speed)]
    stances: list[StanceRecord] = []
    x_toe, vx_com = 0.0, 0.0
    if config.first_touchdown is not None:
        speed, vx_com, ahead, *first_rates = (float(v) for v in config.first_touchdown)
        q_td, rates = touchdown_posture(chain, rho_nom, ahead), np.array(first_rates)
        flights = [_lead_in_flight(chain, config, q_td, rates, speed, vx_com)]
    elif config.flight in TRUNK_AT_REST_FLIGHTS:  # the calibration's rates moved to the trial's posture, the trunk at rest
        rates = trunk_held_toe_correction(chain, q_td, vx_com, td_rates)
    stop = ""
    t_td = t_end = config.lead_in_s
    balance_losses: list[float] = []
    for i in range(config.n_hops):
        surface = config.surface_for_hop(i)
        law = scale_push_off(config.law, _hop_push_scale(config, cal, speed, rng))
        td = touchdown_state(chain, q_td, np.array([vx_com, -speed]), x_toe, rates)
        st = simulate_stance(chain, law, surface, td, t_max_s=2.0 * period, rtol=config.rtol, atol=config.atol,
                             friction_coefficient=config.friction_coefficient, trunk_balance=config.trunk_balance)
        stances.append(StanceRecord(i, t_td, st, surface, law, td))
        t_end = t_td + st.duration_s
        stop = _stance_stop_reason(i, st)
        if stop:
            break
        v_to = com_velocity(chain, st.g[-1], st.gd[-1])
        hop_config, hop_cal = landing_for_hop(chain, config, cal, td)
        rho_next = rho_nom + rng.normal(0.0, config.posture_sd_rad, 3) + (posture_offsets or {}).get(i + 1, 0.0)
        q_next = _next_posture(chain, hop_config, hop_cal, rho_next, float(v_to[0]), st.duration_s)
        try:
            nxt = _flight_to_next_touchdown(chain, hop_config, law, st, q_next, t_end, last=i == config.n_hops - 1)
        except ValueError as exc:
            stop = f"hop {i}: {exc}"
            break
        if nxt.not_placed_j > 1e-9:
            notes.append(f"flight after hop {i}: {nxt.not_placed_j:.3f} J of segment energy could not be placed")
        flights.append(nxt.flight)
        balance_losses.append(nxt.balance_loss_j)
        x_toe, vx_com, speed, q_td, rates = nxt.x_toe_m, nxt.com_vx_m_s, nxt.speed_m_s, q_next, nxt.rates
        t_td = t_end = t_end + nxt.flight.duration_s
    return HoppingTrial(config, chain, stances, flights, t_end, cal, stop, notes, balance_losses[: config.n_hops - 1])


def given_start_calibration(config: HoppingConfig) -> HopCalibration:
    """The :class:`HopCalibration` of a trial that starts from ``config.first_touchdown`` (a known hop, e.g. a periodic
    one) instead of calibrating: its touchdown speed and rates, push-off scale 1 without the hop-by-hop correction
    (gain 0), and the foot placement's reference offset ``config.com_ahead_m``. The stance, flight and take-off
    figures are not computed (NaN): the trial's first hop is that hop."""
    if config.first_touchdown is None:
        raise ValueError("given_start_calibration needs HoppingConfig.first_touchdown")
    speed, *_, r1, r2, r3, r4 = (float(v) for v in config.first_touchdown)
    return HopCalibration(speed_m_s=speed, push_scale=1.0, stance_s=np.nan, flight_s=np.nan, next_speed_m_s=np.nan,
                          d_speed_d_scale=0.0, success=True, com_ahead_m=config.com_ahead_m, take_off_vx_m_s=np.nan,
                          d_vx_d_com_ahead_s=np.nan, touchdown_rates_rad_s=np.array([r1, r2, r3, r4]))


def touchdown_state_vector(chain: Chain, td: TouchdownState) -> np.ndarray:
    """The hop map's state of a touchdown (periodic_hop.STATE_NAMES): touchdown speed (m/s, down), COM vx (m/s), COM
    ahead of the toe (m), segment rates q1..q4 (rad/s)."""
    v = com_velocity(chain, td.g, td.gd)
    return np.r_[-v[1], v[0], body_com(chain, td.g)[0] - td.g[0], td.gd[2:]]


def landing_for_hop(chain: Chain, config: HoppingConfig, cal: HopCalibration,
                    td: TouchdownState) -> tuple[HoppingConfig, HopCalibration]:
    """The configuration and calibration the flight after the hop that touched down in ``td`` uses: with
    ``config.landing_feedback`` its landing rates and foot placement reference (:class:`LandingFeedback`), else
    ``config`` and ``cal`` themselves."""
    feedback = config.landing_feedback
    if feedback is None:
        return config, cal
    landing, ahead = feedback.choose(touchdown_state_vector(chain, td))
    return (replace(config, landing_rates_rad_s=tuple(float(r) for r in landing)),
            replace(cal, com_ahead_m=float(ahead)))


def _calibration_note(config: HoppingConfig, cal: HopCalibration) -> str:
    """The trial note when the calibration found no exactly periodic hop (its best compromise)."""
    return (
        f"no exactly periodic hop at {config.freq_hz} Hz on {config.surface.name}: best compromise "
        f"stance {cal.stance_s:.3f} s + flight {cal.flight_s:.3f} s "
        f"({1.0 / (cal.stance_s + cal.flight_s):.2f} Hz), touchdown speed {cal.speed_m_s:.2f} -> "
        f"{cal.next_speed_m_s:.2f} m/s"
    )


def _lead_in_flight(chain: Chain, config: HoppingConfig, q_td: np.ndarray, rates: np.ndarray, speed: float,
                    vx: float | None = None) -> Flight:
    """Lead-in flight: COM falling onto the first touchdown at ``speed`` (m/s) (and moving at ``vx`` m/s, if
    given); the segments start at rest and reach the touchdown ``rates`` (half the lead-in's worth of motion
    before touchdown)."""
    g_acc = chain.gravity_m_s2
    com_td = body_com(chain, np.r_[0.0, 0.0, q_td])
    com0 = com_td + np.array([0.0, speed * config.lead_in_s - 0.5 * g_acc * config.lead_in_s**2])
    vel0 = np.array([0.0, -speed + g_acc * config.lead_in_s])
    if vx is not None:
        com0[0] -= vx * config.lead_in_s
        vel0[0] = vx
    start = [q_td - 0.5 * config.lead_in_s * rates, np.zeros(4), np.zeros(4)]
    lead = BPoly.from_derivatives([0.0, config.lead_in_s], np.array([start, [q_td, rates, np.zeros(4)]]))
    return Flight(0.0, config.lead_in_s, com0, vel0, lead, g_acc)


def _hop_push_scale(config: HoppingConfig, cal: HopCalibration, speed: float, rng: np.random.Generator) -> float:
    """Push-off scale of a hop: the calibrated one, corrected by the proportional controller towards a seeded
    target touchdown speed (``speed_sd``; ``push_off_gain`` of the deadbeat correction) and varied by ``push_sd``."""
    gain = cal.d_speed_d_scale
    target = cal.speed_m_s * (1.0 + rng.normal(0.0, config.speed_sd))
    scale = cal.push_scale
    if gain > 0:
        scale += config.push_off_gain * (target - speed) / gain
    scale *= 1.0 + rng.normal(0.0, config.push_sd)
    return scale


def _stance_stop_reason(i: int, st: StanceSimulation) -> str:
    """Why hop ``i``'s stance ends the trial ("" when it took off as a hop)."""
    if st.end_reason != "take_off":
        return f"hop {i}: stance ended by {st.end_reason} at {st.duration_s:.3f} s"
    if st.duration_s < MIN_HOP_STANCE_S:
        return f"hop {i}: the foot bounced off after {st.duration_s * 1000:.0f} ms (joints too soft?)"
    return ""


def _next_posture(chain: Chain, config: HoppingConfig, cal: HopCalibration, rho: np.ndarray, vx: float,
                  stance_s: float) -> np.ndarray:
    """Next touchdown posture: joint angles ``rho`` (nominal + noise), COM placed for horizontal balance
    (Raibert-style: ``vx (stance/2 + placement_gain_s)`` behind the calibrated offset)."""
    ahead = cal.com_ahead_m - vx * (0.5 * stance_s + config.placement_gain_s)
    return touchdown_posture(chain, rho, ahead)


@dataclass(frozen=True)
class _NextTouchdown:
    """The flight after a stance and the touchdown it leads to (:func:`_flight_to_next_touchdown`)."""

    flight: Flight
    x_toe_m: float
    com_vx_m_s: float
    speed_m_s: float
    rates: np.ndarray | None
    not_placed_j: float
    balance_loss_j: float = 0.0


def _flight_to_next_touchdown(chain: Chain, config: HoppingConfig, law: ImpedanceLaw, st: StanceSimulation,
                              q_next: np.ndarray, t_takeoff_s: float, last: bool) -> _NextTouchdown:
    """Ballistic COM from take-off to the touchdown in posture ``q_next``; segment angles a quintic from the
    take-off angles, rates and accelerations to the touchdown ones (module docstring: rates zero plus the toe
    correction, or the energy-keeping ones). The ``last`` flight ends the recording at its apex (or after 40 %
    of the flight if it never rises); its segments keep the pace of a whole flight, so the last take-off looks
    like every other one. Raises ValueError if the take-off is too weak to fly (:func:`flight_time_s`)."""
    g_acc = chain.gravity_m_s2
    g_to, gd_to = st.g[-1], st.gd[-1]
    com_to, v_to = body_com(chain, g_to), com_velocity(chain, g_to, gd_to)
    t_f = flight_time_s(chain, com_to[1], v_to[1], q_next)
    com_next = com_to + v_to * t_f - np.array([0.0, 0.5 * g_acc * t_f**2])
    v_next = v_to - np.array([0.0, g_acc * t_f])
    rates, not_placed, loss = None, 0.0, 0.0
    if config.flight in ENERGY_KEEPING_FLIGHTS:
        rates, loss, not_placed = flight_rates(
            chain, config, law, st, q_next, float(v_next[0]),
            landing_direction(chain, config, st, q_next, float(v_next[0]), t_f))
    td_next = touchdown_state(chain, q_next, v_next, 0.0, rates)
    angles = flight_angles(chain, (g_to, gd_to, st.gdd[-1]), td_next, t_f, (config.passive_takeoff_s, config.passive_landing_s))
    if last:
        t_f = max(v_to[1] / g_acc, 0.4 * t_f)
    x_toe = float(com_next[0] - body_com(chain, np.r_[0.0, 0.0, q_next])[0])
    return _NextTouchdown(Flight(t_takeoff_s, t_f, com_to, v_to, angles, g_acc), x_toe, float(v_next[0]),
                          float(-v_next[1]), rates, not_placed, loss)


def flight_angles(chain: Chain, takeoff: tuple[np.ndarray, np.ndarray, np.ndarray], td: TouchdownState, t_f: float,
                  passive_s: tuple[float, float] = (0.0, 0.0)) -> BPoly:
    """The flight's segment angles over ``[0, t_f]`` (s since take-off).

    A quintic from the take-off's angles, rates and accelerations (``takeoff``: the stance's last ``g``, ``gd``,
    ``gdd``) to the touchdown ``td``'s angles and rates with zero acceleration. ``passive_s`` = (after take-off,
    before touchdown) > 0: the flight's first / last :func:`~hop_impedance.simulation.passive_flight.passive_duration_s`
    are the free chain with zero joint moments from the take-off state forward / to the touchdown state backward
    (:mod:`~hop_impedance.simulation.passive_flight`; shorter where its toe would pass through the ground), the quintic
    joining them (angles, rates, accelerations)."""
    g_to, gd_to, gdd_to = takeoff
    up, down = (passive_duration_s(s, t_f) for s in passive_s)
    tau_up, knots_up = passive_knots(chain, g_to, gd_to, up) if up > 0 else (np.zeros(1), None)
    tau_down, knots_down = passive_knots(chain, td.g, td.gd, -down) if down > 0 else (np.zeros(1), None)
    if len(tau_up) == 1:  # no phase (or none the ground allows): the quintic from the take-off's own state
        knots_up = np.array([[g_to[2:], gd_to[2:], gdd_to[2:]]])
    if len(tau_down) == 1:
        knots_down = np.array([[td.g[2:], td.gd[2:], np.zeros(4)]])
    return BPoly.from_derivatives(np.r_[tau_up, t_f + tau_down], np.concatenate([knots_up, knots_down]))


def leg_stiffness_n_per_m(chain: Chain, stance: StanceSimulation) -> tuple[float, float, float]:
    """Seed 001's leg stiffness: peak vertical GRF / maximal leg compression.

    Leg compression is the COM's downward displacement since touchdown minus the
    surface's (toe's) downward displacement, i.e. the shortening of the vertical
    COM-toe distance.

    Returns
    -------
    (stiffness N/m, peak Fz N, max compression m)
    """
    com_z = np.array([body_com(chain, g)[1] for g in stance.g])
    height = com_z - stance.g[:, 1]
    compression = float(np.max(height[0] - height))
    peak = float(np.max(stance.grf_n[:, 1]))
    return peak / compression, peak, compression

