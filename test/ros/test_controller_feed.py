"""Issue 21, controller feed: who, which stance, how sure, how old; invalidation over real DDS.

One process, one rclpy context, loopback DDS: the real ``impedance_estimator``
node, and a test node that publishes ``/subject`` and ``/stance/kinetics``
(the bundled recording's ten stances as analysed by ``analyze_recording``,
turned into messages by inverse_dynamics' own ``stance_message``) and
listens to ``/impedance/controller`` and ``/impedance/profile``. The fits,
the standard errors and the plausibility rule are the node's own; nothing is
mocked.

Shown: the feed's pooled k0/k1/b0 and their standard errors equal a direct
inverse-variance computation from the same stances' published fits
(``ImpedanceProfile.coefficients`` / ``std_errors``); a valid value is
republished invalid once older than ``max_age_s``, and a stance that arrives
already older is not valid; a ``/subject`` change invalidates the latched
values at once (NaN, pool emptied), and neither a stance that touched down
before the new subject nor one analysed for another body mass becomes valid.
"""

import functools
import math
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from hop_impedance_msgs.msg import ControllerImpedance, ImpedanceProfile, StanceKinetics, SubjectInfo  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from hop_impedance.biomech.analysis import analyze_recording  # noqa: E402
from hop_impedance.biomech.joint_angles import JOINT_NAMES  # noqa: E402
from hop_impedance.nodes.common import CONTROLLER_TOPIC, PROFILE_TOPIC, STANCE_KINETICS_TOPIC, set_stamp, stamp_ns  # noqa: E402
from hop_impedance.nodes.inverse_dynamics import stance_message  # noqa: E402
from hop_impedance.nodes.qos import history_qos, latched_qos, result_qos  # noqa: E402
from hop_impedance.recording import SUBJECT_TOPIC  # noqa: E402
from test.cli import bad_recordings as bad  # noqa: E402

MAX_AGE_S = 1.5
POOL = 4


@pytest.fixture(scope="module")
def stances():
    rec = bad.bundled()
    analysis = analyze_recording(rec)
    msgs = [stance_message(s, analysis.start_ns) for s in analysis.stances if s.rejection_reason is None]
    assert len(msgs) == 10
    return rec.subject, msgs


def _subject(subject_id: str, mass: float, height: float, stamp_ns_: int = 0) -> SubjectInfo:
    msg = SubjectInfo(subject_id=subject_id, body_mass=mass, body_height=height)
    set_stamp(msg.header.stamp, stamp_ns_)
    return msg


def _spin_until(executor, predicate, timeout_s: float = 30.0) -> bool:
    """Spin until ``predicate()`` holds or ``timeout_s`` has passed; returns ``predicate()``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not predicate():
        executor.spin_once(timeout_sec=0.02)
    return predicate()


def _direct_pool(values: list[float], errors: list[float]) -> tuple[float, float, float]:
    """Inverse-variance weighted mean, its standard error and Cochran's Q / (n - 1), written out (not the pooling module)."""
    w = [1.0 / (e * e) for e in errors]
    mean = sum(wi * v for wi, v in zip(w, values)) / sum(w)
    q = sum(wi * (v - mean) ** 2 for wi, v in zip(w, values))
    return mean, 1.0 / math.sqrt(sum(w)), q / (len(w) - 1) if len(w) > 1 else math.nan


def test_feed_pools_expires_and_invalidates_on_subject_change(stances):
    from hop_impedance.nodes.impedance_estimator import ImpedanceEstimatorNode

    subject, msgs = stances
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        estimator = ImpedanceEstimatorNode(context=context, parameter_overrides=[
            Parameter("max_age_s", value=MAX_AGE_S), Parameter("pool_stances", value=POOL),
            Parameter("diagnostics_period_s", value=0.0)])
        tester = rclpy.create_node("controller_feed_tester", context=context)
        feeds: list[tuple[float, ControllerImpedance]] = []
        profiles: list[ImpedanceProfile] = []
        tester.create_subscription(ControllerImpedance, CONTROLLER_TOPIC, lambda m: feeds.append((time.time_ns(), m)),
                                   history_qos(200))
        tester.create_subscription(ImpedanceProfile, PROFILE_TOPIC, profiles.append, result_qos(1000))
        pub_stance = tester.create_publisher(StanceKinetics, STANCE_KINETICS_TOPIC, history_qos())
        pub_subject = tester.create_publisher(SubjectInfo, SUBJECT_TOPIC, latched_qos())
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(estimator)
        executor.add_node(tester)

        spin_until = functools.partial(_spin_until, executor)

        def late_controller() -> ControllerImpedance:
            """What a controller that subscribes now (reliable, transient-local) receives first."""
            got: list[ControllerImpedance] = []
            sub = tester.create_subscription(ControllerImpedance, CONTROLLER_TOPIC, got.append, latched_qos())
            assert spin_until(lambda: got, 10.0)
            tester.destroy_subscription(sub)
            return got[0]

        def send(msg: StanceKinetics, age_s: float = 0.0) -> ControllerImpedance:
            """Publish a stance whose take-off reached the pipeline ``age_s`` ago; return its feed message."""
            msg.takeoff_received_ns = time.time_ns() - int(age_s * 1e9)
            n = len(feeds)
            pub_stance.publish(msg)
            assert spin_until(lambda: any(f.stance_index == msg.stance_index and stamp_ns(f.takeoff_stamp) ==
                                          stamp_ns(msg.takeoff_stamp) for _, f in feeds[n:])), msg.stance_index
            return next(f for _, f in feeds[n:] if f.stance_index == msg.stance_index)

        assert spin_until(lambda: feeds)  # the start message: nothing valid
        assert not any(feeds[-1][1].valid) and feeds[-1][1].invalid_reason[0] == "no valid stance yet"
        pub_subject.publish(_subject(subject.subject_id, subject.body_mass_kg, subject.body_height_m))
        assert spin_until(lambda: estimator.subject_key is not None)

        # 1. six fresh stances: who, which stance, each SE, and the pooled estimate over the last POOL valid ones
        sent = [send(m) for m in msgs[:6]]
        assert spin_until(lambda: len(profiles) >= 18)
        last = sent[-1]
        assert last.side == "lumped" and last.subject_id == subject.subject_id and last.pool_size == POOL
        assert last.max_age_s == MAX_AGE_S
        assert stamp_ns(last.touchdown_stamp) == stamp_ns(msgs[5].touchdown_stamp)
        assert stamp_ns(last.takeoff_stamp) == stamp_ns(msgs[5].takeoff_stamp) == stamp_ns(last.header.stamp)
        fits = {(p.stance_index, p.joint): p for p in profiles}
        checked = 0
        for j, joint in enumerate(JOINT_NAMES):
            valid_idx = [f.stance_index for f in sent if f.valid[j]][-POOL:]
            # the hip: 2 valid of the first 6 on session 33's recording (stances 4 and 5; the others read a negative
            # damping or R^2 < 0.5: the trunk balance's moment, recordings/README.md), so its pool is those two
            # (session 32's recording: 1 valid, stance 4)
            assert len(valid_idx) >= (2 if joint != "hip" else 1), (joint, [f.invalid_reason[j] for f in sent])
            assert last.pooled_n_stances[j] == len(valid_idx)
            for term, value_field, se_field in (("k0", "pooled_k0_nm_per_rad", "pooled_k0_std_error"),
                                                ("k1", "pooled_k1_nm_per_rad2", "pooled_k1_std_error"),
                                                ("b0", "pooled_b0_nms_per_rad", "pooled_b0_std_error")):
                pairs = []
                for i in valid_idx:
                    p = fits[(i, joint)]
                    c, se = p.coefficients[p.terms.index(term)], p.std_errors[p.terms.index(term)]
                    if math.isfinite(se) and se > 0:
                        pairs.append((c, se))
                if not pairs:
                    assert math.isnan(getattr(last, value_field)[j])
                    continue
                value, se, chi2 = _direct_pool([c for c, _ in pairs], [s for _, s in pairs])
                assert getattr(last, value_field)[j] == pytest.approx(value, rel=1e-12)
                assert getattr(last, se_field)[j] == pytest.approx(se, rel=1e-12)
                chi2_feed = getattr(last, f"pooled_{term}_chi2_per_dof")[j]
                assert chi2_feed == pytest.approx(chi2, rel=1e-9) if len(pairs) > 1 else math.isnan(chi2_feed)
                # pooling narrows the interval; one stance's pool is that stance
                assert se < min(s for _, s in pairs) if len(pairs) > 1 else se == pytest.approx(pairs[0][1], rel=1e-12)
                checked += 1
            if last.valid[j]:  # the latest stance's own SEs are its fit's
                p = fits[(last.stance_index, joint)]
                assert last.k0_std_error[j] == pytest.approx(p.std_errors[p.terms.index("k0")], rel=1e-12)
                assert last.k0_nm_per_rad[j] == pytest.approx(p.coefficients[p.terms.index("k0")], rel=1e-12)
        assert checked >= 6
        print(f"pooled hip k0 {last.pooled_k0_nm_per_rad[2]:.1f} +- {last.pooled_k0_std_error[2]:.2f} N m/rad "
              f"over {last.pooled_n_stances[2]} stances; latest stance {last.k0_nm_per_rad[2]:.1f} +- "
              f"{last.k0_std_error[2]:.2f}; chi2/dof k0 " + ", ".join(f"{x:.2f}" for x in last.pooled_k0_chi2_per_dof))

        # 2. too old: the latched valid value is republished invalid once older than max_age_s
        assert any(last.valid)
        t_valid = time.time_ns()
        n = len(feeds)
        assert spin_until(lambda: any(not any(f.valid) for _, f in feeds[n:]), 3 * MAX_AGE_S + 5)
        t_expired, expired = next((t, f) for t, f in feeds[n:] if not any(f.valid))
        assert all(r.startswith(f"older than max_age_s {MAX_AGE_S:g} s") for r, v in zip(expired.invalid_reason, last.valid) if v)
        age_s = (t_expired - t_valid) * 1e-9
        assert MAX_AGE_S * 0.9 < age_s < MAX_AGE_S + 2.0, age_s
        print(f"expiry message {age_s:.2f} s after the stance (max_age_s {MAX_AGE_S})")
        # a controller that subscribes now gets the latched message: the invalid one
        late = late_controller()
        assert not any(late.valid) and late.stance_index == last.stance_index
        # ... and a stance that arrives already older than max_age_s is not valid either
        stale = send(msgs[6], age_s=2 * MAX_AGE_S)
        assert not any(stale.valid)
        # the plausible joints are refused as too old; a joint whose fit is implausible keeps that reason (stance 6's
        # hip on the seed-like recording: R^2 < 0.5, its moment holds the trunk balance, recordings/README.md)
        assert spin_until(lambda: sum(p.stance_index == 6 for p in profiles) == 3)
        fits = {(p.stance_index, p.joint): p for p in profiles}
        said = [r.startswith("older than max_age_s") if fits[(6, joint)].r_squared >= 0.5 else r.startswith("implausible: R^2")
                for joint, r in zip(JOINT_NAMES, stale.invalid_reason)]
        assert all(said) and sum(r.startswith("older than") for r in stale.invalid_reason) >= 2, stale.invalid_reason

        # 3. a new subject: the previous subject's latched values are invalid at once, NaN, pool emptied
        fresh = send(msgs[7])
        assert any(fresh.valid)
        after_last_touchdown = stamp_ns(msgs[-1].takeoff_stamp) + 1
        n = len(feeds)
        pub_subject.publish(_subject("next", subject.body_mass_kg, subject.body_height_m, after_last_touchdown))
        assert spin_until(lambda: len(feeds) > n)
        changed = feeds[n][1]
        assert changed.subject_id == "next" and not any(changed.valid)
        assert changed.invalid_reason == [f"subject changed from {subject.subject_id!r} to 'next'"] * 3
        assert all(math.isnan(v) for v in (*changed.k0_nm_per_rad, *changed.pooled_k0_nm_per_rad))
        assert list(changed.pooled_n_stances) == [0, 0, 0]
        late = late_controller()
        assert late.subject_id == "next" and not any(late.valid)
        # a stance that touched down before the new /subject belongs to the previous subject
        before = send(msgs[8])
        assert not any(before.valid) and list(before.pooled_n_stances) == [0, 0, 0]
        assert before.invalid_reason == ["stance touched down before /subject changed to 'next'"] * 3
        # a subject of another mass: a stance analysed for the old mass is not valid
        pub_subject.publish(_subject("heavier", subject.body_mass_kg + 10.0, subject.body_height_m))
        assert spin_until(lambda: feeds[-1][1].subject_id == "heavier")
        other = send(msgs[9])
        assert not any(other.valid)
        # ankle and knee refused for the mass; stance 9's hip keeps its own reason (session 33's recording: b_eq -3.10;
        # session 32's: -3.18)
        assert all(r.startswith("stance analysed for body mass 54.8 kg, /subject 'heavier' has 64.8 kg")
                   for r in other.invalid_reason[:2]), other.invalid_reason
        assert other.invalid_reason[2].startswith("implausible: b_eq -3.10"), other.invalid_reason
        # the fits themselves were accepted: the feed, not the fit, refused them
        assert all(p.accepted for p in profiles if p.stance_index in (6, 8, 9))
        # nothing published after the first change carried a valid value of the first subject
        assert not any(any(f.valid) for _, f in feeds[n:])
    finally:
        rclpy.shutdown(context=context)


@pytest.mark.parametrize("mass_offset_kg", [0.0, 10.0])
def test_first_subject_after_the_first_stance(stances, mass_offset_kg):
    """In separate processes ``/subject`` may reach the estimator after the first stance (discovery order; a
    fresh-clone CI run once saw an extra, invalid feed message this way). The first ``/subject`` heard leaves the
    latched values valid when they were analysed for its body mass, and invalidates them when not."""
    from hop_impedance.nodes.impedance_estimator import ImpedanceEstimatorNode

    subject, msgs = stances
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        estimator = ImpedanceEstimatorNode(context=context, parameter_overrides=[
            Parameter("max_age_s", value=0.0), Parameter("diagnostics_period_s", value=0.0)])
        tester = rclpy.create_node("first_subject_tester", context=context)
        feeds: list[ControllerImpedance] = []
        tester.create_subscription(ControllerImpedance, CONTROLLER_TOPIC, feeds.append, history_qos(200))
        pub_stance = tester.create_publisher(StanceKinetics, STANCE_KINETICS_TOPIC, history_qos())
        pub_subject = tester.create_publisher(SubjectInfo, SUBJECT_TOPIC, latched_qos())
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(estimator)
        executor.add_node(tester)

        spin_until = functools.partial(_spin_until, executor)

        assert spin_until(lambda: len(feeds) >= 1)  # the start message
        msg = msgs[0]
        msg.takeoff_received_ns = time.time_ns()
        pub_stance.publish(msg)
        assert spin_until(lambda: any(stamp_ns(f.takeoff_stamp) for f in feeds))
        first = [f for f in feeds if stamp_ns(f.takeoff_stamp)]
        assert len(first) == 1 and any(first[0].valid) and first[0].subject_id == ""
        n = len(feeds)
        pub_subject.publish(_subject(subject.subject_id, subject.body_mass_kg + mass_offset_kg, subject.body_height_m))
        assert spin_until(lambda: estimator.subject_key is not None)
        spin_until(lambda: False, 1.0)  # anything the subject caused has arrived by now
        assert estimator.feed.subject_id == subject.subject_id
        if mass_offset_kg == 0.0:
            # the same body mass the stance was analysed for: nothing to withdraw, nothing republished
            assert feeds[n:] == [] and list(estimator.feed.valid) == list(first[0].valid)
        else:
            assert len(feeds[n:]) == 1 and not any(feeds[n].valid)
            assert feeds[n].invalid_reason == [f"subject changed from '' to {subject.subject_id!r}"] * 3
    finally:
        rclpy.shutdown(context=context)
