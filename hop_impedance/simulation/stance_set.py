"""A cheap recording of independent stances: the test-case generator of the discovery workflow.

Why this exists
---------------
:func:`hop_impedance.simulation.simulate.simulate_recording` sequences hops
with a calibrated push-off controller. A law without a push-off (the
discovery baseline: constant stiffness, no damping, no active moment) cannot
sustain hopping there, and its calibration costs several seconds. The
discovery workflow needs many recordings of *any* law, including the
baseline itself, so this module simulates each stance on its own from a
touchdown state (nominal posture and speed plus seeded variability) and
joins the stances by smooth flights.

Model (documented simplifications)
----------------------------------
- Stances: :func:`hop_impedance.simulation.stance.simulate_stance`, exact
  forward dynamics with the chosen law and surface (physical).
- Flights: *not* ballistic. The COM and the segment angles follow quintics
  (``scipy.interpolate.BPoly``) from the take-off state (position, velocity,
  acceleration) to the next touchdown state; at both ends the COM
  acceleration is ``-g``. The force plate reads zero in flight. This stands
  in for the energy the missing push-off would supply; no stance quantity
  depends on it.
- Touchdown speed: ``g (1/f - T_nominal) / 2`` (the symmetric flight of a hop
  of frequency ``f``), ``T_nominal`` the stance time of one nominal stance.
- ``"rigid"`` means :data:`RIGID_NO_BOUNCE`: the simulator's rigid law with
  ten times its Hunt-Crossley damping, because with zero joint moments at
  touchdown the light foot bounces off the simulator's ``RIGID`` after 20 ms.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from functools import partial

import numpy as np
from scipy.interpolate import BPoly

from hop_impedance.biomech.body_model import body_model_from_stature
from hop_impedance.recording import Recording, Subject
from hop_impedance.simulation.dynamics import Chain, body_com, chain_from_body_model, com_offset_jacobian, com_velocity
from hop_impedance.simulation.ground import GroundLaw, surface
from hop_impedance.simulation.hopping_trial import (
    Flight,
    HoppingConfig,
    HoppingTrial,
    StanceRecord,
    joint_triple,
    scale_push_off,
    touchdown_posture,
    touchdown_state,
)
from hop_impedance.simulation.impedance_laws import CompositeLaw, Eq3Law, ImpedanceLaw, PushOff, TimeActivation
from hop_impedance.simulation.scenarios import (
    DEFAULT_TOUCHDOWN_RHO,
    EXTRA_B1,
    EXTRA_K2,
    PUSH_OFF_TIMING,
    PUSH_OFF_WEIGHTS,
    SEED_SUBJECT,
    Effects,
    build_law,
    passive_law,
    seed_stiffness,
)
from hop_impedance.simulation.sensors import SensorConfig, sample_recording
from hop_impedance.simulation.stance import TouchdownState, simulate_stance

#: The rigid surface without the foot bounce (see module docstring).
RIGID_NO_BOUNCE = GroundLaw("rigid", 1.0e8, 1.5, 1.0e9, 1.5)


def ground_law(name: str) -> GroundLaw:
    """Surface by name; ``"rigid"`` is :data:`RIGID_NO_BOUNCE`, others as :func:`surface`."""
    return RIGID_NO_BOUNCE if name == "rigid" else surface(name)


@dataclass(frozen=True)
class EffectSizes:
    """Explicit, physically relevant magnitudes of the hidden effects (discovery test cases).

    The simulator's default magnitudes (:mod:`hop_impedance.simulation.scenarios`)
    were chosen to be illustrative, and some are at or below what any method
    can see in a few noisy stances (``k3 = (3, 2, 1)`` contributes < 2 % of the
    joint moment, ``b0 = 0.5`` ~2 %). A *hidden* effect in a test case must be
    large enough to matter physically; these sizes say how large, and the
    hit rates in ``docs/discovery.md`` hold at these sizes.

    Attributes
    ----------
    rate_fraction : float
        ``k3`` per joint is chosen so that ``max |k3 S|`` over a nominal stance
        is this fraction of that joint's peak moment (``S = int (omega - omega0) omega dt``).
    damping_b0_nm_s_rad : float
        ``b0`` of every joint (N m s/rad).
    activation_a_min, activation_tau_s : float
        Seed 001 activation ``a(t) = a_min + (1 - a_min)(1 - exp(-t / tau))``.
    push_fraction : float
        Push-off amplitude at the ankle as a fraction of the nominal passive
        stance's peak ankle moment; knee and hip get
        :data:`~hop_impedance.simulation.scenarios.PUSH_OFF_WEIGHTS` of it.
    """

    rate_fraction: float = 0.15
    damping_b0_nm_s_rad: float = 2.0
    activation_a_min: float = 0.3
    activation_tau_s: float = 0.05
    push_fraction: float = 0.3

    def to_dict(self) -> dict:
        """Plain numbers for the truth file."""
        return asdict(self)


def _nominal_passive_stance(chain: Chain, law: ImpedanceLaw, ground: GroundLaw, rho_td, freq_hz: float):
    speed, _ = nominal_touchdown_speed(chain, law, ground, rho_td, freq_hz)
    q = touchdown_posture(chain, np.asarray(rho_td, float))
    return simulate_stance(chain, law, ground, touchdown_state(chain, q, np.array([0.0, -speed]), 0.0),
                           t_max_s=2.0 / freq_hz, rtol=1e-6, atol=1e-8)


def sized_law(chain: Chain, freq_hz: float, effects: Effects, sizes: EffectSizes, ground: GroundLaw,
              rho_td=DEFAULT_TOUCHDOWN_RHO) -> tuple[CompositeLaw, float]:
    """The joint law of ``effects`` with the magnitudes of ``sizes``.

    ``k0``, ``k1`` come from seed Table 2 (interpolated in frequency), ``k2`` and
    ``b1`` keep the simulator's values. ``k3`` and the push-off amplitude are
    scaled on the nominal passive stance (at the nominal touchdown speed) on
    ``ground``: ``k3`` by three fixed-point passes so that its share holds on
    the stance *with* ``k3`` in (within a few %); the push-off is timed like the
    simulator's (onset 35 %, duration 60 % of that stance).

    Returns
    -------
    law : ImpedanceLaw
        ``CompositeLaw((Eq3Law, [PushOff]))``; extensor positive.
    nominal_stance_s : float
        Duration (s) of the nominal stance of the final passive law.
    """
    k0, k1 = seed_stiffness(freq_hz)
    eq3 = Eq3Law(
        k0=k0,
        k1=k1 if effects.angle_dependent_stiffness else np.zeros(3),
        k2=np.array(EXTRA_K2 if effects.quadratic_stiffness else 0.0),
        b0=np.array(sizes.damping_b0_nm_s_rad if effects.damping else 0.0),
        b1=np.array(EXTRA_B1 if effects.nonlinear_damping else 0.0),
        activation=TimeActivation(sizes.activation_a_min, sizes.activation_tau_s) if effects.time_activation else None,
    )
    nominal = _nominal_passive_stance(chain, eq3, ground, rho_td, freq_hz)
    for _ in range(3 if effects.rate_dependent_stiffness else 0):  # fixed point: share measured *with* k3 in
        s_peak = np.max(np.abs(nominal.law_states), axis=0)
        m_peak = np.max(np.abs(nominal.moments_nm), axis=0)
        eq3 = replace(eq3, k3=sizes.rate_fraction * m_peak / np.maximum(s_peak, 1e-9))
        nominal = _nominal_passive_stance(chain, eq3, ground, rho_td, freq_hz)
    ts = nominal.duration_s
    if not effects.push_off:
        return CompositeLaw((eq3,)), ts
    amp = sizes.push_fraction * float(np.max(nominal.moments_nm[:, 0])) * np.array(PUSH_OFF_WEIGHTS)
    return CompositeLaw((eq3, PushOff(amp, PUSH_OFF_TIMING[0] * ts, PUSH_OFF_TIMING[1] * ts))), ts


@dataclass(frozen=True)
class BridgedFlight:
    """Flight whose COM and angles follow quintics between two given states (duck-types :class:`Flight`)."""

    t_start_s: float
    duration_s: float
    com: BPoly
    angles: BPoly

    def evaluate(self, chain: Chain, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Generalized coordinates and velocities (N, 6) at absolute times ``t_s`` (s)."""
        tau = np.clip(np.asarray(t_s, float) - self.t_start_s, 0.0, self.duration_s)
        q, qd = self.angles(tau), self.angles.derivative()(tau)
        g = np.zeros((len(tau), 6))
        g[:, 2:] = q
        g[:, 0:2] = self.com(tau) - body_com(chain, g)
        gd = np.zeros_like(g)
        gd[:, 2:] = qd
        jac = np.array([com_offset_jacobian(chain, qi) for qi in q])
        gd[:, 0:2] = self.com.derivative()(tau) - np.einsum("nak,nk->na", jac, qd)
        return g, gd


def _bridge(chain: Chain, t0: float, dur: float, g0, gd0, gdd0, g1, gd1) -> BridgedFlight:
    grav = np.array([0.0, -chain.gravity_m_s2])
    c0, c1 = body_com(chain, g0), body_com(chain, g1)
    v0, v1 = com_velocity(chain, g0, gd0), com_velocity(chain, g1, gd1)
    com = BPoly.from_derivatives([0.0, dur], np.array([[c0, v0, grav], [c1, v1, grav]]))
    angles = BPoly.from_derivatives([0.0, dur], np.array([[g0[2:], gd0[2:], gdd0[2:]], [g1[2:], gd1[2:], np.zeros(4)]]))
    return BridgedFlight(t0, dur, com, angles)


def nominal_touchdown_speed(chain: Chain, law, ground: GroundLaw, rho_td, freq_hz: float) -> tuple[float, float]:
    """(touchdown speed m/s, nominal stance s) for hops at ``freq_hz`` with symmetric flights."""
    q = touchdown_posture(chain, np.asarray(rho_td, float))
    speed = chain.gravity_m_s2 * 0.4 / freq_hz / 2.0
    for _ in range(2):
        st = simulate_stance(chain, law, ground, touchdown_state(chain, q, np.array([0.0, -speed]), 0.0),
                             t_max_s=2.0 / freq_hz, rtol=1e-6, atol=1e-8)
        speed = max(chain.gravity_m_s2 * (1.0 / freq_hz - st.duration_s) / 2.0, 0.3)
    return speed, st.duration_s


def simulate_stance_set_recording(
    freq_hz: float = 2.2, surfaces: tuple[str, ...] = ("rigid",), n_hops: int = 8, seed: int = 1,
    effects: Effects = Effects(angle_dependent_stiffness=False, damping=False, push_off=False),
    sensors: SensorConfig = SensorConfig(), *, subject: Subject = SEED_SUBJECT, touchdown_rho_rad=DEFAULT_TOUCHDOWN_RHO,
    posture_sd_rad: float = 0.02, speed_sd: float = 0.05, push_sd: float = 0.05, rtol: float = 1e-7,
    sizes: EffectSizes | None = None, redraws: int = 0,
) -> tuple[Recording, dict]:
    """Recording of ``n_hops`` independently simulated stances (see module docstring).

    Parameters
    ----------
    freq_hz : float
        Hop frequency (Hz); stiffness from seed Table 2 (interpolated).
    surfaces : tuple of str
        Surfaces cycled over the hops (``"rigid"``, ``"hard"``, ``"soft"``);
        the push-off timing and touchdown speed are tuned on the first.
    n_hops : int
    seed : int
        Seeds variability (posture, speed, push-off scale) and sensor noise.
    effects : Effects
        Law effects present (default: the discovery baseline, constant stiffness).
    sensors : SensorConfig
    posture_sd_rad, speed_sd, push_sd : float
        Hop-to-hop variability of joint angles (rad), touchdown speed and
        push-off amplitude (fractions).
    sizes : EffectSizes, optional
        Explicit effect magnitudes (:func:`sized_law`); default: the
        simulator's magnitudes (:func:`~hop_impedance.simulation.scenarios.build_law`).
    redraws : int
        A stance that does not take off (e.g. a soft, weakly activated body
        that collapses) is re-drawn with a new touchdown state up to this
        many times per hop, then ValueError (default 0: ValueError at once).
        Re-drawn hops are counted in ``truth["redrawn_hops"]``.

    Returns
    -------
    recording : Recording
    truth : dict
        ``effects``, ``law``, ``surfaces``, ``sensors``, and per stance
        ``touchdown_s``, ``takeoff_s``, ``surface``; ``sizes`` (or None) and
        ``redrawn_hops``.
    """
    if n_hops < 1:
        raise ValueError(f"n_hops must be at least 1, got {n_hops}")
    rng = np.random.default_rng(seed)
    chain = chain_from_body_model(body_model_from_stature(subject))
    laws = [ground_law(s) for s in surfaces]
    law, speed_nom, ts_nom = _stance_set_law(chain, freq_hz, effects, sizes, laws[0], touchdown_rho_rad)
    draw = partial(_draw_touchdown, chain, rng, touchdown_rho_rad, posture_sd_rad, speed_nom, speed_sd)
    tds = [draw() for _ in range(n_hops)]
    sims, redrawn = _simulate_hops(chain, law, laws, tds, draw, rng, push_sd, freq_hz, rtol, redraws)
    trial = _joined_trial(chain, sims, tds, max(1.0 / freq_hz - ts_nom, 0.1),
                          HoppingConfig(freq_hz, n_hops, laws[0], law, joint_triple(touchdown_rho_rad)))
    recording, _ = sample_recording(trial, sensors, subject, np.random.default_rng([seed, 1]))
    truth = {"generator": "hop_impedance.simulation.stance_set", "seed": seed, "freq_hz": freq_hz,
             "effects": effects.to_dict(), "law": law.to_dict(), "surfaces": list(surfaces), "sensors": sensors.to_dict(),
             "sizes": sizes.to_dict() if sizes is not None else None, "redrawn_hops": redrawn,
             "stances": [_stance_truth(r) for r in trial.stances]}
    return recording, truth


def _stance_truth(record: StanceRecord) -> dict:
    """A stance of the truth document: touchdown and take-off (s since recording start), surface name."""
    return {"touchdown_s": record.t_touchdown_s, "takeoff_s": record.t_takeoff_s, "surface": record.surface.name}


def _stance_set_law(chain: Chain, freq_hz: float, effects: Effects, sizes: EffectSizes | None, ground: GroundLaw,
                    rho_td) -> tuple[ImpedanceLaw, float, float]:
    """(law, nominal touchdown speed m/s, nominal stance s) of a stance set on ``ground``.

    Without ``sizes`` the simulator's magnitudes (:func:`build_law`), the push-off timed on the
    nominal passive stance (onset 35 %, duration 60 %); with ``sizes`` :func:`sized_law`. The nominal
    speed and stance are those of the law without its push-off (:func:`nominal_touchdown_speed`).
    """
    if sizes is None:
        passive = passive_law(freq_hz, effects)
        speed_nom, ts_nom = nominal_touchdown_speed(chain, passive, ground, rho_td, freq_hz)
        law = build_law(freq_hz, effects, PUSH_OFF_TIMING[0] * ts_nom, PUSH_OFF_TIMING[1] * ts_nom)
    else:
        law, _ = sized_law(chain, freq_hz, effects, sizes, ground, rho_td)
        passive = CompositeLaw(tuple(p for p in law.parts if not isinstance(p, PushOff)))
        speed_nom, ts_nom = nominal_touchdown_speed(chain, passive, ground, rho_td, freq_hz)
    return law, speed_nom, ts_nom


def _draw_touchdown(chain: Chain, rng: np.random.Generator, rho_td, posture_sd_rad: float, speed_nom: float,
                    speed_sd: float) -> TouchdownState:
    """A touchdown at the nominal posture and speed with seeded variability (joint angles rad, speed fraction)."""
    rho = np.asarray(rho_td, float) + rng.normal(0.0, posture_sd_rad, 3)
    speed = speed_nom * (1.0 + rng.normal(0.0, speed_sd))
    return touchdown_state(chain, touchdown_posture(chain, rho), np.array([0.0, -speed]), 0.0)


def _simulate_hops(chain: Chain, law: ImpedanceLaw, laws: list[GroundLaw], tds: list[TouchdownState], draw,
                   rng: np.random.Generator, push_sd: float, freq_hz: float, rtol: float, redraws: int):
    """Each hop's stance from its touchdown in ``tds``: push-off scaled by 1 + N(0, push_sd), surfaces cycled.

    A stance that does not take off is re-drawn (``draw()``, replacing its entry of ``tds``) up to
    ``redraws`` times, then ValueError. Returns ([(stance, surface, law)] per hop, re-drawn count).
    """
    redrawn = 0
    sims = []
    for i in range(len(tds)):
        hop_law = scale_push_off(law, 1.0 + rng.normal(0.0, push_sd))
        ground = laws[i % len(laws)]
        for attempt in range(redraws + 1):
            st = simulate_stance(chain, hop_law, ground, tds[i], t_max_s=2.0 / freq_hz, rtol=rtol, atol=rtol * 1e-2)
            if st.end_reason == "take_off":
                break
            if attempt == redraws:
                raise ValueError(f"hop {i}: stance ended by {st.end_reason} after {st.duration_s:.3f} s"
                                 + (f" ({redraws} re-draws tried)" if redraws else ""))
            tds[i] = draw()
            redrawn += 1
        sims.append((st, ground, hop_law))
    return sims, redrawn


def _joined_trial(chain: Chain, sims: list, tds: list[TouchdownState], flight_s: float,
                  config: HoppingConfig) -> HoppingTrial:
    """The stances joined into a trial: a 0.4 s lead-in falling onto the first touchdown (segments at rest),
    bridged flights of ``flight_s`` (:func:`_bridge`; the last one towards the first touchdown), and the
    recording ending half a flight after the last take-off."""
    lead = 0.4
    rest = np.array([tds[0].g[2:], np.zeros(4), np.zeros(4)])
    c_td = body_com(chain, tds[0].g)
    v_td = com_velocity(chain, tds[0].g, tds[0].gd)
    com0 = c_td - v_td * lead + 0.5 * np.array([0.0, -chain.gravity_m_s2]) * lead**2
    flights: list = [Flight(0.0, lead, com0, v_td - np.array([0.0, -chain.gravity_m_s2]) * lead,
                            BPoly.from_derivatives([0.0, lead], np.array([rest, rest])), chain.gravity_m_s2)]
    stances, t_td = [], lead
    for i, (st, ground, hop_law) in enumerate(sims):
        stances.append(StanceRecord(i, t_td, st, ground, hop_law, tds[i]))
        t_to = t_td + st.duration_s
        nxt = tds[i + 1] if i + 1 < len(sims) else tds[0]
        flights.append(_bridge(chain, t_to, flight_s, st.g[-1], st.gd[-1], st.gdd[-1], nxt.g, nxt.gd))
        t_td = t_to + flight_s
    t_end = stances[-1].t_takeoff_s + 0.5 * flight_s
    return HoppingTrial(config, chain, stances, flights, t_end, None)
