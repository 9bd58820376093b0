"""Several force plates as one contract wrench (biomech.plate_combining).

The must-be-shown comparison of issue 19: the same hops as one summed plate and
as two plates (distinct origins, the right plate turned round, asymmetric and
time-varying left/right split, 0.5 ms stamp skew) give the same stances and
impedance coefficients within 1e-6 relative through the whole analysis.
"""

from pathlib import Path

import numpy as np
import pytest

from hop_impedance.biomech.analysis import analyze_recording
from hop_impedance.biomech.plate_combining import PlateCombinerStage, PlateLayout, combine_plates
from hop_impedance.impedance.recording_fits import fit_recording
from hop_impedance.io.recording_io import load_recording
from hop_impedance.recording import ForcePlateSeries, Recording
from test.two_plates import LEFT_ORIGIN, LEFT_TOPIC, RIGHT_ORIGIN, RIGHT_TOPIC, RIGHT_YAW_DEG, SKEW_NS, split_two_plates

RECORDING = Path(__file__).resolve().parents[2] / "recordings" / "sim_2p20hz_hard.mcap"
LAYOUTS = [PlateLayout("left", tuple(LEFT_ORIGIN)), PlateLayout("right", tuple(RIGHT_ORIGIN), RIGHT_YAW_DEG)]


def test_point_load_lands_at_the_plate_it_stands_on():
    """600 N straight down on a plate's origin: the combined COP is that origin, whatever the plate's yaw."""
    layouts = [PlateLayout("a", (0.2, 0.1, 0.0)), PlateLayout("b", (-0.3, -0.2, 0.0), 90.0)]
    f = np.zeros((2, 1, 3))
    f[1, 0] = [0.0, 0.0, 600.0]  # only plate b loaded, its own axes
    force, moment = combine_plates(layouts, f, np.zeros((2, 1, 3)))
    assert force[0] == pytest.approx([0.0, 0.0, 600.0])
    assert -moment[0, 1] / force[0, 2] == pytest.approx(-0.3)  # contract cop_x
    assert moment[0, 0] / force[0, 2] == pytest.approx(-0.2)  # cop_y
    # A forward push in plate b's axes (x_b) is a push to the lab's left (+y) at 90 deg yaw.
    f[1, 0] = [50.0, 0.0, 600.0]
    force, _ = combine_plates(layouts, f, np.zeros((2, 1, 3)))
    assert force[0] == pytest.approx([0.0, 50.0, 600.0])


def _stream(stage, parts, chunk=20, drop_left=(), drop_right=(), right_until=None):
    """Feed both plates in interleaved chunks, the right one a chunk behind (as a live node gets them), then flush.

    ``drop_*``: sample indices lost on that plate; ``right_until``: the right plate stops after this many samples.
    """
    (ls, lw), (rs, rw) = parts[LEFT_TOPIC], parts[RIGHT_TOPIC]
    keep_l = np.setdiff1d(np.arange(len(ls)), drop_left)
    keep_r = np.setdiff1d(np.arange(len(rs) if right_until is None else right_until), drop_right)
    out = []
    n = len(ls)
    for i in range(0, n + 2 * chunk, chunk):
        sel = keep_l[(keep_l >= i) & (keep_l < i + chunk)]
        out.append(stage.push(0, ls[sel], lw[sel]))
        sel = keep_r[(keep_r >= i - chunk) & (keep_r < i)]
        out.append(stage.push(1, rs[sel], rw[sel]))
    out.append(stage.flush())
    return (np.concatenate([o[0] for o in out]), np.concatenate([o[1] for o in out]),
            np.concatenate([o[2] for o in out]))


def _rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = np.maximum(np.abs(b), 1e-300)
    both_zero = (a == 0) & (b == 0)
    return float(np.max(np.where(both_zero, 0.0, np.abs(a - b) / scale), initial=0.0))


def test_two_plates_give_the_summed_plate_stances_and_coefficients():
    rec = load_recording(RECORDING)
    parts = split_two_plates(rec.force)
    assert not np.allclose(parts[LEFT_TOPIC][1][:, :3], parts[RIGHT_TOPIC][1][:, :3])  # really two different plates
    stage = PlateCombinerStage(LAYOUTS)
    stamps, force, moment = _stream(stage, parts)
    assert stage.skew_ns[1] == SKEW_NS
    assert stage.missing == [0, 0] and stage.dropped == 0
    np.testing.assert_array_equal(stamps, rec.force.stamp_ns)
    np.testing.assert_allclose(force, rec.force.force_n, rtol=0, atol=1e-9 * np.abs(rec.force.force_n).max())
    np.testing.assert_allclose(moment, rec.force.torque_nm, rtol=0, atol=1e-9 * np.abs(rec.force.torque_nm).max())

    two = Recording(ForcePlateSeries(stamps, force, moment), rec.markers, rec.subject, "two plates")
    a1, a2 = analyze_recording(rec), analyze_recording(two)
    assert len(a1.stances) == len(a2.stances) == 10
    worst = {"stance times": 0.0, "coefficients": 0.0}
    for s1, s2 in zip(a1.stances, a2.stances):
        assert s2.rejection_reason == s1.rejection_reason
        worst["stance times"] = max(worst["stance times"], _rel([s2.touchdown_s, s2.takeoff_s, s2.peak_grf_n],
                                                                 [s1.touchdown_s, s1.takeoff_s, s1.peak_grf_n]))
    fits1, fits2 = fit_recording(a1), fit_recording(a2)
    n_coef = 0
    for f1, f2 in zip(fits1, fits2):
        assert f1.keys() == f2.keys()
        for joint in f1:
            assert f2[joint].rejection_reason == f1[joint].rejection_reason
            assert f2[joint].coefficients.keys() == f1[joint].coefficients.keys()
            for term, v in f1[joint].coefficients.items():
                worst["coefficients"] = max(worst["coefficients"], _rel(f2[joint].coefficients[term], v))
                n_coef += 1
    print(f"two plates vs summed plate: {n_coef} coefficients, max relative difference "
          f"stance times/peaks {worst['stance times']:.2e}, coefficients {worst['coefficients']:.2e}")
    assert n_coef >= 60
    assert worst["stance times"] <= 1e-6
    assert worst["coefficients"] <= 1e-6


def test_a_lost_sample_drops_that_instant_instead_of_half_a_wrench():
    rec = load_recording(RECORDING)
    parts = split_two_plates(rec.force)
    stage = PlateCombinerStage(LAYOUTS)
    stamps, force, _ = _stream(stage, parts, drop_left=[500, 2000, 2001], drop_right=[1200])
    lost = np.array([500, 1200, 2000, 2001])
    expected = np.delete(np.arange(len(rec.force)), lost)
    np.testing.assert_array_equal(stamps, rec.force.stamp_ns[expected])
    np.testing.assert_allclose(force[:, 2], rec.force.force_n[expected, 2], atol=1e-9)
    assert stage.missing == [3, 1]  # left missed 3 instants, right 1
    assert stage.dropped == 4


def test_a_plate_that_stops_is_reported_and_nothing_is_summed_without_it():
    rec = load_recording(RECORDING)
    parts = split_two_plates(rec.force)
    stage = PlateCombinerStage(LAYOUTS, wait_ns=50_000_000)
    (ls, lw), (rs, rw) = parts[LEFT_TOPIC], parts[RIGHT_TOPIC]
    n = 0
    for i in range(0, 2000, 20):  # both plates up to sample 1000, then only the left one
        n += stage.push(0, ls[i:i + 20], lw[i:i + 20])[0].size
        if i < 1000:
            n += stage.push(1, rs[i:i + 20], rw[i:i + 20])[0].size
    assert n == 1000  # every instant while both plates ran, none after
    assert stage.silent_plates() == ["right"]
    assert stage.missing == [0, 1000 - 51]  # the left run 1000..1999, except the last wait_ns (50 ms) still waiting
    assert stage.flush()[0].size == 0
    assert stage.missing == [0, 1000]


@pytest.mark.parametrize("late, skew_ns, missing", [
    # The right plate starts 2 samples late: the left's first two instants are counted, the rest pair at +0.5 ms.
    (RIGHT_TOPIC, SKEW_NS, [0, 2]),
    # The left starts 2 late: at 0.5 ms (half a period at 1 kHz) the right's second sample is as close to the
    # left's first one as its own partner, so the lock takes -0.5 ms, as the module docstring warns.
    (LEFT_TOPIC, SKEW_NS - 1_000_000, [2, 0]),
])
def test_skew_lock_when_one_plate_starts_late(late, skew_ns, missing):
    rec = load_recording(RECORDING)
    parts = split_two_plates(rec.force)
    parts[late] = (parts[late][0][2:], parts[late][1][2:])
    stage = PlateCombinerStage(LAYOUTS)
    stamps, _, _ = _stream(stage, parts)
    np.testing.assert_array_equal(stamps, rec.force.stamp_ns[2:])
    assert stage.skew_ns[1] == skew_ns
    assert stage.missing == missing


def test_bad_layouts_are_one_line_errors():
    with pytest.raises(ValueError, match="names must differ"):
        PlateCombinerStage([PlateLayout("a"), PlateLayout("a")])
    with pytest.raises(ValueError, match="jitter"):
        PlateCombinerStage(LAYOUTS, max_skew_ns=100, jitter_ns=200)
