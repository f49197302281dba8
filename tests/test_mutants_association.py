"""The clock-offset search's pieces and the pairing (:mod:`replication.rig.association`) at their boundaries: the
parabola's vertex, which maxima count, the overlap's ten samples, the offset in words, which camera samples pair at
an interval and offset, and ``stream_pairs``. Mutation testing (scripts/mutation) found these unguarded by the fast
tests."""
import math
import warnings

import numpy as np
import pytest

from replication.core import so3
from replication.rig import association
from replication.rig.association import motion_pairs, offset_in_words, stream_pairs
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro


def test_vertex_of_the_parabola_through_the_maximum_and_its_neighbours():
    x = np.array([0.0, 1.0, 2.0, 4.0, 5.0])
    y = -(x - 2.3) ** 2  # a parabola: its vertex exactly, though the points are unequally spaced
    assert association._vertex(x, y) == pytest.approx(2.3, abs=1e-12)
    ys = np.stack([y, -(x - 0.8) ** 2, -(x - 4.4) ** 2])
    assert association._vertex(x, ys) == pytest.approx([2.3, 0.8, 4.4], abs=1e-12)
    # a maximum at either end is not refined; nor a flat (non-concave) top; no finite value: NaN
    assert association._vertex(x, x) == 5.0 and association._vertex(x, -x) == 0.0
    lone = np.array([np.nan, 1.0, np.nan, 0.0, 0.0])  # no finite neighbours: no parabola
    assert association._vertex(x, lone) == 1.0
    assert math.isnan(association._vertex(x, np.full(5, np.nan)))
    with_nan = np.array([np.nan, 1.0, 3.0, 2.0, np.nan])
    assert 1.0 < association._vertex(x, with_nan) < 4.0
    # the vertex is clipped to the three points' span
    skew = np.array([0.0, 0.0, 1.0, 0.999, 0.0])
    v = association._vertex(x, skew)
    assert 1.0 <= v <= 4.0 and v == pytest.approx(
        0.5 * (1 + 2) - (1.0 / 1.0) / (2 * ((0.999 - 1.0) / 2.0 - 1.0) / 3.0))


def test_local_maxima_are_interior_strict_on_the_left():
    c = np.array([0.0, 1.0, 0.5, 0.5, 0.7, 0.7, 0.2, 0.9])
    assert association._local_maxima(c).tolist() == [1, 4]  # 5 ties 4 from the left: not a maximum; 7 is an end
    assert association._local_maxima(np.array([3.0, 2.0, 1.0])).tolist() == []


def _streams(n_cam=40, dt=0.05, sensor_span=(-1.0, 3.0), rate=(0.4, 0.9, -0.3)):
    w = np.array(rate)
    tc = np.arange(n_cam) * dt
    ts = np.arange(sensor_span[0], sensor_span[1], 0.01)
    cam = OrientationStream(tc, so3.matrix_from_rotation_vector(tc[:, None] * w), "cam")
    sen = OrientationStream(ts, so3.matrix_from_rotation_vector(ts[:, None] * w), "sen")
    return cam, sen


def test_the_overlap_needs_ten_camera_samples_inside_the_shifted_sensor_stream():
    cam, sen = _streams(n_cam=40)
    t, speed = association._overlap(cam, sen, 0.2)
    assert np.array_equal(t, cam.t) and speed.shape == (39,)
    assert np.allclose(speed, np.linalg.norm([0.4, 0.9, -0.3]))
    # the sensor covers camera times 0 .. 0.45 + 0.2 exactly: ten samples (0 .. 0.45), inclusive at both ends
    sen10 = OrientationStream(np.linspace(-0.2, 0.65, 86), so3.matrix_from_rotation_vector(np.linspace(-0.2, 0.65,
                                                                                                       86)[:, None]
                                                                         * np.array([0.4, 0.9, -0.3])))
    t, _ = association._overlap(cam, sen10, 0.2)
    assert len(t) == 10 and t[0] == 0.0 and t[-1] == pytest.approx(0.45)
    sen9 = OrientationStream(np.linspace(-0.2, 0.6, 81), so3.matrix_from_rotation_vector(np.linspace(-0.2, 0.6,
                                                                                                     81)[:, None]
                                                                        * np.array([0.4, 0.9, -0.3])))
    with pytest.raises(ValueError, match=r"^the streams overlap in fewer than 10 camera samples \(overlap "
                                         r"0\.000\.\.0\.400 s\)$"):
        association._overlap(cam, sen9, 0.2)


def test_offset_in_words():
    assert offset_in_words(0.0123) == ("+12.3 ms: the sensor sample stamped t + 12.3 ms matches the camera sample "
                                       "stamped t (sensor clock ahead of the camera's by 12.3 ms; Kalibr's "
                                       "timeshift_cam_imu, t_imu = t_cam + shift)")
    assert offset_in_words(-0.0123, decimals=2).startswith("-12.30 ms: the sensor sample stamped t - 12.30 ms matches"
                                                           " the camera sample stamped t (sensor clock behind the "
                                                           "camera's by 12.30 ms;")
    assert offset_in_words(0.00004) == ("0.0 ms: the sensor sample stamped t matches the camera sample stamped t (the "
                                        "clocks agree to 0.05 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)")
    assert offset_in_words(-0.00004, decimals=0).startswith("0 ms: the sensor sample stamped t matches the camera "
                                                            "sample stamped t (the clocks agree to 0.5 ms;")
    assert offset_in_words(0.00005, decimals=1).startswith("+0.1 ms")  # rounds half to even, away from 0 here
    with pytest.raises(ValueError, match=r"^decimals must be >= 0, got -1$"):
        offset_in_words(0.01, decimals=-1)
    with pytest.raises(ValueError, match=r"^offset_s must be a finite number"):
        offset_in_words(math.nan)


def test_motion_pairs_pair_each_camera_sample_with_the_one_an_interval_later():
    cam, sen = _streams(n_cam=40, dt=0.05)
    A, B, t = motion_pairs(cam, sen, 0.25)
    assert np.allclose(t, np.arange(35) * 0.05)  # 0.25 s = 5 samples later, for every sample with one
    w = np.array([0.4, 0.9, -0.3])
    assert np.allclose(A, so3.matrix_from_rotation_vector(np.broadcast_to(-0.25 * w, (35, 3))), atol=1e-9)
    assert np.allclose(B, A, atol=1e-6)
    # within half a camera step of the interval
    A2, _, t2 = motion_pairs(cam, sen, 0.27)
    assert np.allclose(t2, t) and np.allclose(A2, A)
    A3, _, t3 = motion_pairs(cam, sen, 0.2249)
    assert len(t3) == 36 and np.allclose(A3[0], so3.matrix_from_rotation_vector(-0.2 * w), atol=1e-9)
    # the offset: the sensor read at t + offset; camera samples whose shifted time leaves the sensor are dropped
    _, B4, t4 = motion_pairs(cam, sen, 0.25, offset=0.1)
    assert np.allclose(t4, t) and np.allclose(B4, A, atol=1e-6)
    short = OrientationStream(np.arange(0.0, 1.0, 0.01), so3.matrix_from_rotation_vector(np.arange(0.0, 1.0,
                                                                                                   0.01)[:, None] * w))
    _, _, t5 = motion_pairs(cam, short, 0.25, offset=0.1)
    assert t5[0] == 0.0 and t5[-1] == pytest.approx(0.85 - 0.25 + 1e-12, abs=1e-9)
    with pytest.raises(ValueError, match=r"^interval must be positive, got 0$"):
        motion_pairs(cam, sen, 0)
    with pytest.raises(ValueError, match=r"^fewer than 2 motion pairs at interval 1\.95 s "
                                         r"\(streams overlap 1\.95 s\)$"):
        motion_pairs(cam, sen, 1.95)
    assert len(motion_pairs(cam, sen, 1.9)[2]) == 2


def test_stream_pairs_integrates_a_gyro_and_applies_the_offset_unless_told_not_to():
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 30.0, 0.005)
    omega = (np.stack([np.sin(1.1 * t), np.cos(0.7 * t), 0.6 * np.sin(2.3 * t + 0.5)], axis=1)
             + 0.01 * rng.standard_normal((len(t), 3)))
    gyro = GyroStream(t, omega, "g")
    Q = integrate_gyro(gyro)
    d = 0.03
    tc = np.arange(1.0, 29.0, 0.05)
    cam = OrientationStream(tc, Q.at(tc + d), "c")
    A, B, offset, corr = stream_pairs(cam, gyro, interval=0.5)
    assert offset == pytest.approx(d, abs=1e-3) and corr > 0.99
    assert np.max(so3.angle_between_deg(A, B)) < 0.05
    A2, B2, offset2, _ = stream_pairs(cam, gyro, interval=0.5, correct_offset=False)
    assert offset2 == offset and np.max(so3.angle_between_deg(A2, B2)) > 0.1
    _, _, offset3, _ = stream_pairs(cam, Q, interval=0.5, max_offset=0.1)
    assert offset3 == pytest.approx(offset, abs=1e-9)
    with pytest.raises(ValueError, match=r"^camera must be an OrientationStream and sensor an OrientationStream or "
                                         r"GyroStream$"):
        stream_pairs(gyro, Q)
    with pytest.raises(ValueError, match="camera must be an OrientationStream"):
        stream_pairs(cam, omega)


# ------------------------------------------------------------------ offset_analysis: parameters, block, interval

def _turning_rig(n_cam=61, dt=0.05, offset=0.0):
    """A camera at 20 Hz (3 s) and a 200 Hz orientation sensor over a wider span, turning at a varying speed."""
    def Q(t):
        t = np.asarray(t, float)
        return so3.matrix_from_rotation_vector(np.stack([np.sin(1.3 * t) + 0.5 * t, 0.8 * np.cos(2.1 * t), 0.3 * t * t],
                                                        axis=-1))
    tc = np.arange(n_cam) * dt
    ts = np.arange(-1.0, n_cam * dt + 1.0, 0.005)
    return OrientationStream(tc, Q(tc), "cam"), OrientationStream(ts, Q(ts + offset), "sen")


@pytest.mark.parametrize("name, value, match", [
    ("n_bootstrap", -1, r"^n_bootstrap must be >= 0, got -1$"),
    ("seed", -1, r"^seed must be >= 0, got -1$"),
    ("block_s", 0.0, r"^block_s must be > 0, got 0.0$"),
    ("resolution", 0.0, r"^resolution must be > 0, got 0.0$"),
    ("max_offset", -0.1, r"^max_offset must be > 0, got -0.1$"),
])
def test_offset_analysis_names_the_parameter_it_refuses(name, value, match):
    cam, sen = _turning_rig()
    with pytest.raises(ValueError, match=match):
        association.offset_analysis(cam, sen, **{name: value})


@pytest.fixture
def replicates(monkeypatch):
    """offset_analysis with the bootstrap's replicate offsets set by the test; records the block length asked."""
    state = {"blocks": []}

    def fake(a, rows, x, n_bootstrap, block, rng):
        state["blocks"].append(block)
        return state["boot"][:n_bootstrap]

    monkeypatch.setattr(association, "_bootstrap_offsets", fake)
    return state


def test_the_interval_ends_are_order_statistics_at_or_outside_2_5_and_97_5_percent(replicates):
    cam, sen = _turning_rig()
    replicates["boot"] = np.random.default_rng(4).permutation(np.arange(200.0))
    found = association.offset_analysis(cam, sen, n_bootstrap=200)
    # 2.5 % of 199 gaps is 4.975 -> the 5th smallest (index 4); 97.5 % is 194.025 -> index 195
    assert found.ci95_s == (4.0, 195.0)
    boot = np.arange(200.0)
    boot[0] = np.nan  # a replicate without a peak is left out: 1 .. 199, 2.5 % of 198 gaps is 4.95 -> 5
    replicates["boot"] = boot
    assert association.offset_analysis(cam, sen, n_bootstrap=200).ci95_s == (5.0, 195.0)
    replicates["boot"] = np.array([0.0123])  # one replicate is an interval too
    assert association.offset_analysis(cam, sen, n_bootstrap=1).ci95_s == (0.0123, 0.0123)
    found = association.offset_analysis(cam, sen, n_bootstrap=0)
    assert all(math.isnan(v) for v in found.ci95_s)


def test_a_block_holds_block_s_over_the_camera_interval_speeds_at_least_one(replicates):
    cam, sen = _turning_rig()
    replicates["boot"] = np.zeros(10)
    for block_s in (0.001, 0.024, 0.05, 0.074, 0.076, 0.5):
        association.offset_analysis(cam, sen, n_bootstrap=10, block_s=block_s)
    assert replicates["blocks"] == [1, 1, 1, 1, 2, 10]


def test_the_overlap_must_hold_two_blocks():
    cam, sen = _turning_rig(n_cam=21)  # 21 camera samples: 20 speeds
    found = association.offset_analysis(cam, sen, n_bootstrap=4, block_s=0.5)  # blocks of 10: exactly two
    assert found.block_s == 0.5 and found.n_bootstrap == 4 and np.all(np.isfinite(found.ci95_s))
    with pytest.raises(ValueError, match=r"^block_s=0\.55 s makes blocks of 11 camera speeds, more than half of the 20 "
                                         r"in the overlap: use a shorter block_s$"):
        association.offset_analysis(cam, sen, n_bootstrap=4, block_s=0.55)


def test_offset_analysis_defaults_and_its_returned_fields():
    cam, sen = _turning_rig(offset=0.012)
    found = association.offset_analysis(cam, sen)
    assert found.n_bootstrap == 200 and found.block_s == 1.0
    assert found.ci95_s == association.offset_analysis(cam, sen, n_bootstrap=200, seed=0, block_s=1.0).ci95_s
    assert found.ci95_s != association.offset_analysis(cam, sen, n_bootstrap=200, seed=1, block_s=1.0).ci95_s
    offset, corr, (x, y) = association.estimate_time_offset(cam, sen, full_output=True)
    assert found.offset_s == offset and found.correlation == corr
    assert np.array_equal(found.curve[0], x) and np.array_equal(found.curve[1], y)


# ------------------------------------------------------------------ the bootstrap's replicates

def _spike(n=10, seed=1):
    """Camera speeds with a spike at sample 0 (and an exact 0 at sample 1), and sensor rows at three offsets: the
    first matches the spike only, the last matches the rest only, the middle neither."""
    rng = np.random.default_rng(seed)
    p = np.concatenate([[0.0, 0.0], rng.standard_normal(n - 2)])
    e0 = np.eye(n)[0]
    a = 10.0 * e0 + p
    rows = np.stack([10.0 * e0 + 0.3, 0.5 * p + rng.standard_normal(n), p])
    return a, rows, np.array([-0.01, 0.0, 0.01])


def test_a_replicate_peaking_at_the_first_or_last_offset_is_minus_or_plus_infinity():
    a, rows, x = _spike()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a replicate without the spike has a constant first row: 0/0, silently
        out = association._bootstrap_offsets(a, rows, x, 200, 1, np.random.default_rng(0))
    # with the spike drawn the first offset matches best (-inf), without it the last (+inf); every sample, the
    # first too, is drawn with probability 1 - 0.9^10 = 65 % per replicate
    assert np.all(np.isinf(out))
    assert 110 <= np.sum(out == -np.inf) <= 150 and np.sum(out == np.inf) == 200 - np.sum(out == -np.inf)


def test_a_replicate_peaking_inside_is_refined_near_that_offset():
    rng = np.random.default_rng(2)
    a = rng.standard_normal(40)
    z = rng.standard_normal(40)
    x = np.arange(5) * 0.001
    for k in (1, 2, 3):
        rows = np.stack([a + 0.2 * abs(j - k) * z for j in range(5)])
        out = association._bootstrap_offsets(a, rows, x, 30, 4, np.random.default_rng(0))
        assert np.all(np.abs(out - x[k]) < 0.001), (k, out)


def test_the_replicates_do_not_depend_on_the_speeds_scale():
    rng = np.random.default_rng(3)
    a = rng.standard_normal(40)
    x = np.arange(5) * 0.001
    rows = np.stack([a + 0.3 * abs(j - 2.4) * rng.standard_normal(40) for j in range(5)])
    out = association._bootstrap_offsets(a, rows, x, 30, 4, np.random.default_rng(0))
    small = association._bootstrap_offsets(1e-3 * a, 1e-3 * rows, x, 30, 4, np.random.default_rng(0))
    assert np.allclose(small, out, rtol=0, atol=1e-12)


# ------------------------------------------------------------------ motion_pairs: which samples pair

def _dyadic_streams(tc, w=(0.4, 0.9, -0.3), sensor_t=None):
    """A camera at times ``tc`` and a sensor (at ``sensor_t``, default the camera's own stamps) turning at ``w``."""
    w = np.asarray(w)
    ts = np.asarray(tc if sensor_t is None else sensor_t, float)
    tc = np.asarray(tc, float)
    return (OrientationStream(tc, so3.matrix_from_rotation_vector(tc[:, None] * w), "cam"),
            OrientationStream(ts, so3.matrix_from_rotation_vector(ts[:, None] * w)))


def test_camera_samples_at_the_sensor_s_first_and_last_stamps_are_inside():
    cam, sen = _dyadic_streams(np.arange(40) * 0.0625)  # the sensor stamps are the camera's: both ends shared
    _, _, t = motion_pairs(cam, sen, 0.25)
    assert np.array_equal(t, np.arange(36) * 0.0625)  # pairs (0, 4) .. (35, 39): the first and last samples pair


def test_pairs_at_one_and_a_half_steps_take_the_later_sample_within_the_inclusive_half_step():
    cam, sen = _dyadic_streams(np.arange(20) * 0.0625)
    A, _, t = motion_pairs(cam, sen, 1.5 * 0.0625)  # equidistant from 1 and 2 steps, half a step from both
    w = np.array([0.4, 0.9, -0.3])
    assert np.array_equal(t, np.arange(19) * 0.0625)  # the 19th's only neighbour is one step on, at the tolerance
    assert np.allclose(A[:18], so3.matrix_from_rotation_vector(np.broadcast_to(-2 * 0.0625 * w, (18, 3))), atol=1e-12)
    assert np.allclose(A[18], so3.matrix_from_rotation_vector(-0.0625 * w), atol=1e-12)


def test_an_interval_nearer_the_sample_itself_pairs_nothing():
    cam, sen = _dyadic_streams(np.arange(20) * 0.0625)
    with pytest.raises(ValueError, match=r"^fewer than 2 motion pairs at interval 0\.01 s "
                                         r"\(streams overlap 1\.19 s\)$"):
        motion_pairs(cam, sen, 0.01)


def test_the_first_sample_pairs_only_with_its_nearest_neighbour_at_the_interval():
    # irregular stamps: the median step is 0.05 (tolerance 0.025); 0.009 s after sample 0 is nearest sample 0 itself
    tc = np.array([0.0, 0.02, 0.03, 0.04, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5])
    cam, sen = _dyadic_streams(tc, sensor_t=np.arange(-0.5, 1.0, 0.005))
    _, _, t = motion_pairs(cam, sen, 0.009)
    assert np.allclose(t, [0.02, 0.03, 0.04])


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # no sample inside: NumPy's median of no steps warns first
def test_too_few_pairs_says_the_overlap_of_the_streams():
    cam, sen = _dyadic_streams(1.0 + np.arange(40) * 0.05, sensor_t=np.arange(0.0, 4.0, 0.01))
    with pytest.raises(ValueError, match=r"^fewer than 2 motion pairs at interval 1\.95 s "
                                         r"\(streams overlap 1\.95 s\)$"):
        motion_pairs(cam, sen, 1.95)
    elsewhere = OrientationStream(np.arange(10.0, 11.0, 0.01), so3.matrix_from_rotation_vector(np.zeros((100, 3))))
    with pytest.raises(ValueError, match=r"^fewer than 2 motion pairs at interval 0\.25 s "
                                         r"\(streams overlap 0\.00 s\)$"):
        motion_pairs(cam, elsewhere, 0.25)


def test_orientations_off_orthogonal_by_a_few_millionths_still_pair():
    tc = np.arange(20) * 0.0625
    # ||R^T R - I||_F ~ 7e-6 < 1e-5
    R = so3.matrix_from_rotation_vector(tc[:, None] * np.array([0.4, 0.9, -0.3])) * (1.0 + 2e-6)
    cam = OrientationStream(tc, R, "cam")
    sen = OrientationStream(tc, R.copy(), "sen")
    A, B, t = motion_pairs(cam, sen, 0.25)
    assert len(t) == 16 and np.allclose(A, B)
