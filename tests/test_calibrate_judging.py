"""The batch verdict's new words: pose sets judged by station (bootstrap over stations, per-station residuals, an
outlying station named), every radius saying what it covers, the offset's sign in words, ties among input mistakes
named together in a fixed order, and each new threshold at its boundary."""
import dataclasses
import json

import jsonschema
import numpy as np
import pytest

from replication.core import so3
from replication.rig.association import offset_in_words
from replication.rig.calibration import calibrate
from replication.rig.diagnose import HYPOTHESES, TIE_SHARE, _one_finding
from replication.rig.poses import calibrate_poses
from replication.rig.quality import THRESHOLDS, Evidence, judge
from replication.rig.report import RADIUS_COVERS
from replication.study.simulation import rig_streams

SCHEMA = json.loads((__import__("pathlib").Path(__file__).resolve().parent.parent / "docs"
                     / "calibration_report.schema.json").read_text())


def _stations(rng, N=30, *, station_noise_deg=0.3, bad=None, bad_deg=3.0):
    """Static stations of a robot and a camera rigidly linked by R0 (``C_k = R0 S_k``, both ``body_from_world``), each
    station's two attitudes with independent noise (``bad``: one station's camera attitude turned by ``bad_deg``)."""
    R0 = so3.random_rotations(rng, ())
    W = so3.random_rotations(rng, ())  # the target's frame in the robot base's
    S = so3.random_rotations(rng, N, angle_range_deg=(5.0, 60.0))
    C = R0 @ S @ W
    sd = np.radians(station_noise_deg) / np.sqrt(3)
    C = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ C
    S = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ S
    if bad is not None:
        C[bad] = so3.matrix_from_rotation_vector(np.radians(bad_deg) * np.array([0.0, 0.6, 0.8])) @ C[bad]
    return R0, C, S


def _reasons(result):
    return {r.check: r for r in result.verdict.reasons}


def test_pose_sets_resample_stations_not_pairs(rng):
    R0, C, S = _stations(rng)
    r = calibrate_poses(C, S, n_bootstrap=100, seed=1)
    assert r.bootstrap_resamples == "stations"
    pairs = calibrate_poses(C, S, n_bootstrap=100, seed=1, pairs="consecutive")
    assert pairs.bootstrap_resamples == "pairs in moving blocks of 2"
    # the pairs share their stations' noise: 435 pairs from 30 stations carry about 30 stations' information
    import replication.rig.estimate as est

    J = r.n_pairs
    by_pairs = est.block_indices(np.random.default_rng(1), J, 1, 100)
    motions = __import__("replication.core.motions", fromlist=["prepare_motions"]).prepare_motions(
        *__import__("replication.rig.poses", fromlist=["pose_pairs"]).pose_pairs(C, S))
    R_boot = est.bootstrap_replicates(motions, "chordal_optimal", {}, by_pairs, progress=False)
    naive = float(np.percentile(so3.angle_between_deg(R_boot, r.R), 95))
    assert r.bootstrap_ci95_deg > 2.5 * naive


def test_station_bootstrap_covers_the_error_about_95_percent(rng):
    """40 problems: the error within the station radius in most (the 95 % level, 40 draws: at least 32)."""
    hits = 0
    for _ in range(40):
        R0, C, S = _stations(rng, N=20)
        r = calibrate_poses(C, S, n_bootstrap=100, seed=2)
        hits += float(so3.angle_between_deg(r.R, R0)) <= r.bootstrap_ci95_deg
    assert hits >= 32, hits


def test_an_outlying_station_is_named_with_its_index(rng):
    R0, C, S = _stations(rng, bad=7)
    r = calibrate_poses(C, S, n_bootstrap=0)
    reason = _reasons(r)["pose_outliers"]
    assert reason.level == "warning" and "7 (" in reason.message and reason.threshold == THRESHOLDS[
        "pose_residual_ratio"][0]
    assert len(r.pose_residual_median_deg) == 30 and int(np.argmax(r.pose_residual_median_deg)) == 7
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["pose_residual_median_deg"][7] == pytest.approx(max(report["pose_residual_median_deg"]))
    clean = calibrate_poses(*_stations(rng)[1:], n_bootstrap=0)
    assert "pose_outliers" not in _reasons(clean)


@pytest.mark.parametrize("ratio, flagged", [(2.99, False), (3.01, True)])
def test_outlying_station_threshold_boundary(ratio, flagged):
    medians = np.full(20, 0.4)
    medians[3] = ratio * 0.4
    e = Evidence(n_pairs=190, residual_median_deg=0.4, motion_median_deg=30.0, bootstrap_deg=0.1,
                 axis_spread_deg=10.0, pose_residual_medians_deg=tuple(medians))
    assert ("pose_outliers" in {r.check for r in judge(e).reasons}) is flagged


@pytest.mark.parametrize("motion, level", [(1.01, None), (0.99, "warning"), (0.51, "warning"), (0.49, "fail")])
def test_motion_median_threshold_boundaries(motion, level):
    e = Evidence(n_pairs=100, residual_median_deg=0.001, motion_median_deg=motion, bootstrap_deg=0.1,
                 axis_spread_deg=10.0)
    found = {r.check: r.level for r in judge(e).reasons}
    assert found.get("motion_median_deg") == level


@pytest.mark.parametrize("excitation, level", [(1.01, None), (0.99, "warning")])
def test_excitation_threshold_boundary(excitation, level):
    e = Evidence(n_pairs=100, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.1,
                 excitation_deg=excitation, radius_kind="curvature")
    found = {r.check: r.level for r in judge(e).reasons}
    assert found.get("excitation_deg") == level


def test_every_radius_says_what_it_covers(rng):
    R0, camera, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.05)
    r = calibrate(camera, gyro, n_bootstrap=30)
    assert RADIUS_COVERS in r.summary() and r.bootstrap_covers == RADIUS_COVERS
    assert r.bootstrap_resamples.startswith("pairs in moving blocks of")
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["bootstrap_covers"] == RADIUS_COVERS and "not in it" in report["bootstrap_covers"]


@pytest.mark.parametrize("offset, words", [
    (0.0123, "+12.3 ms: the sensor sample stamped t + 12.3 ms matches the camera sample stamped t (sensor clock ahead "
             "of the camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)"),
    (-0.0123, "-12.3 ms: the sensor sample stamped t - 12.3 ms matches the camera sample stamped t (sensor clock "
              "behind the camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)"),
])
def test_the_offset_sign_in_words_in_the_summary(rng, offset, words):
    """The summary states the sign right for both signs (it printed 'ahead' whatever the sign)."""
    assert offset_in_words(offset) == words
    R0, camera, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.02)
    from replication.rig.streams import GyroStream

    # the rates as recorded (bias-free): the bias model moves the offset within its noise, here by 0.01 ms
    r = calibrate(camera, GyroStream(gyro.t + offset, gyro.omega, "gyro"), n_bootstrap=20, gyro_bias=False)
    line = next(x for x in r.summary().splitlines() if x.startswith("time offset"))
    side = "ahead of" if offset > 0 else "behind"
    assert f"sensor clock {side} the camera's by 12.30 ms" in line and "95 % interval" in line
    lo, hi = r.time_offset_ci95_s
    assert lo <= offset <= hi and hi - lo < 2e-3


def test_tied_hypotheses_are_one_finding_in_a_fixed_order():
    """Residuals that differ in the last bits name the same hypotheses in the same order, whichever is smaller."""
    R = np.eye(3)
    a, b = (0, 0.2 + 1e-15, "first", R, 0.9), (3, 0.2, "second", R, 0.9)
    one = _one_finding([a, b], 1.0, lambda f: f[2], None)[1]
    two = _one_finding([b, a], 1.0, lambda f: f[2], None)[1]
    flipped = _one_finding([(0, 0.2, "first", R, 0.9), (3, 0.2 + 1e-15, "second", R, 0.9)], 1.0, lambda f: f[2],
                           None)[1]
    assert one == two and "first, or second: the data cannot tell which; a reference can" in one
    assert flipped.split(";")[0] == one.split(";")[0]
    outside = _one_finding([(0, 0.2, "first", R, 0.9), (3, 0.2 * TIE_SHARE * 1.01, "second", R, 0.9)], 1.0,
                           lambda f: f[2], None)[1]
    assert "second" not in outside


def test_a_reference_tells_tied_hypotheses_apart():
    R_right = so3.matrix_from_rotation_vector(np.radians([10.0, 0.0, 0.0]))
    fits = [(0, 0.2, "first", np.eye(3), 0.9), (3, 0.2, "second", R_right, 0.9)]
    message = _one_finding(fits, 1.0, lambda f: f[2], R_right)[1]
    assert message.startswith("likely input mistake: second; the reference tells them apart")


def test_hypotheses_are_listed_once_each():
    assert len(set(HYPOTHESES)) == len(HYPOTHESES)


def test_inverted_pose_sets_are_both_named_when_the_data_cannot_tell(rng):
    R0, C, S = _stations(rng)
    r = calibrate_poses(np.swapaxes(C, -1, -2), S, n_bootstrap=0)
    message = _reasons(r)["input_mistake"].message
    # both fit equally: named together (the branch this test is about was conditional; it always holds here),
    # camera first, and the reference decides
    assert "camera poses inverted" in message and "robot poses inverted" in message and "cannot tell" in message
    assert message.index("camera poses") < message.index("robot poses")
    decided = calibrate_poses(np.swapaxes(C, -1, -2), S, n_bootstrap=0, reference=R0)
    assert "robot poses inverted" not in _reasons(decided)["input_mistake"].message.split(";")[0]


def test_judge_tolerates_missing_residuals():
    e = dataclasses.replace(Evidence(n_pairs=12, residual_median_deg=None, motion_median_deg=None, bootstrap_deg=None),
                            radius_kind="curvature")
    # nothing to judge but the count of pairs: no error, and only that warning
    assert [(r.check, r.level) for r in judge(e).reasons] == [("n_pairs", "warning")]


# ----------------------------------------------------------------------------------------- a change inside a recording

def test_a_remount_inside_a_recording_fails_naming_the_time_and_both_estimates(rng):
    from replication.rig.changepoint import remounted

    R0, camera, gyro, _ = rig_streams(90.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.05)
    step = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))
    r = calibrate(camera, remounted(gyro, 45.0, step), n_bootstrap=20)
    reason = _reasons(r)["remount_deg"]
    assert r.verdict.level == "fail" and reason.level == "fail" and "after 45" in reason.message
    assert "R0 before (" in reason.message and "after (" in reason.message
    c = r.change_test
    assert c["significant"] and abs(c["split_time_s"] - 45.0) < 1.0 and c["angle_deg"] == pytest.approx(2.0, abs=0.05)
    assert so3.angle_between_deg(np.array(c["R0_before"]), R0) < 0.05
    assert so3.angle_between_deg(np.array(c["R0_after"]), R0 @ step) < 0.05
    jsonschema.validate(r.to_dict(), SCHEMA)
    clean = calibrate(camera, gyro, n_bootstrap=20)
    assert "remount_deg" not in _reasons(clean) and clean.change_test["run"] and not clean.change_test["significant"]


def test_a_short_recording_says_why_the_change_test_did_not_run(rng):
    R0, camera, gyro, _ = rig_streams(15.0, rng=rng, camera_noise_deg=0.05)
    r = calibrate(camera, gyro, n_bootstrap=0)
    assert not r.change_test["run"] and r.change_test["note"].startswith("not run: ")
    assert "change test: not run" in r.summary()


class _Change:
    significant, split_time, n_before, n_after, p_value, difference_radius_deg = True, 10.0, 500, 500, 1e-6, 0.05
    level = 0.01
    R_before = R_after = np.eye(3)

    def __init__(self, angle_deg, significant=True):
        self.angle_deg, self.significant = angle_deg, significant


@pytest.mark.parametrize("angle, significant, level", [
    (0.49, True, None), (0.51, True, "warning"), (0.74, True, "warning"), (0.76, True, "fail"), (5.0, False, None)])
def test_remount_threshold_boundaries(angle, significant, level):
    e = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.05,
                 axis_spread_deg=10.0, change=_Change(angle, significant))
    assert {r.check: r.level for r in judge(e).reasons}.get("remount_deg") == level


@pytest.mark.parametrize("fit, reported", [(0.29, True), (0.31, False)])
def test_a_change_is_a_remount_only_where_each_side_fits_its_own_estimate(fit, reported):
    """An input mistake leaves both halves unfit and their estimates apart: that is not a re-mount (the residual
    reasons say what it is); the bound is residual_to_motion's fail bound."""
    e = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.05,
                 axis_spread_deg=10.0, change=_Change(2.0), change_sides_fit=fit)
    assert ("remount_deg" in {r.check for r in judge(e).reasons}) is reported
    assert THRESHOLDS["residual_to_motion"][1] == 0.3


def test_an_input_mistake_is_not_called_a_remount(rng):
    R0, camera, gyro, _ = rig_streams(60.0, rng=rng, camera_noise_deg=0.05)
    q = so3.quaternion_from_matrix(camera.R)[:, [1, 2, 3, 0]]
    from replication.rig.streams import OrientationStream

    r = calibrate(OrientationStream(camera.t, so3.matrix_from_quaternion(q), "camera"), gyro, n_bootstrap=0)
    assert r.verdict.level == "fail" and "input_mistake" in _reasons(r) and "remount_deg" not in _reasons(r)
    assert r.change_test["sides_fit"] > THRESHOLDS["residual_to_motion"][1]


# ------------------------------------------------------------------------------------------------ handedness

def _rig_from_body_rates(out_of_plane: float, seed: int = 0, seconds: float = 40.0):
    """A camera turning about its x and y axes (and ``out_of_plane`` rad/s about z), a gyro on the same body."""
    from replication.rig.streams import GyroStream, OrientationStream

    rng = np.random.default_rng(seed)
    R0 = so3.matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))
    dt = 2e-3
    t = np.arange(-1.0, seconds + 1.0, dt)
    w = np.stack([0.7 * np.sin(0.9 * t), 0.6 * np.sin(1.3 * t + 1.0), out_of_plane * np.sin(0.5 * t + 2.0)], -1)
    C = np.concatenate([np.eye(3)[None], so3.cumulative_product(so3.matrix_from_rotation_vector(w[:-1] * dt))])
    k = np.arange(int(1.0 / dt), int((seconds + 1.0) / dt), 25)  # the camera at 20 Hz
    camera = OrientationStream(t[k], C[k] @ so3.matrix_from_rotation_vector(rng.normal(0, np.radians(0.1) / np.sqrt(3),
                                                                                       (len(k), 3))),
                               "camera")
    Q = C[::2] @ R0  # the gyro at 250 Hz
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / (2 * dt)
    omega += rng.normal(0, np.radians(0.2), omega.shape)
    return R0, camera, GyroStream(t[::2][:-1] + dt, omega, "gyro")


def test_rates_in_one_plane_cannot_show_a_flipped_gyro_axis_and_the_verdict_says_so():
    """Red team: a gyro with one axis's sign flipped and rates in one plane gave ok, radius 0.02 deg, R0 126 deg off.
    The flipped gyro is exactly a right-handed one mounted otherwise; both now warn, naming the unturned axis."""
    from replication.rig.streams import GyroStream

    R0, camera, gyro = _rig_from_body_rates(0.0)
    normal = R0.T @ np.array([0.0, 0.0, 1.0])  # the camera's z axis in the sensor frame
    for g, n in ((gyro, normal), (GyroStream(gyro.t, gyro.omega * [1.0, 1.0, -1.0], "gyro"), normal * [1, 1, -1])):
        r = calibrate(camera, g, n_bootstrap=0)
        reason = _reasons(r)["mirror_fit_ratio"]
        assert r.verdict.level == "warning" and reason.level == "warning" and reason.measured < 1.5
        assert reason.threshold == THRESHOLDS["mirror_fit_ratio"][0]
        assert "one axis's sign flipped (a left-handed frame" in reason.message
        assert abs(np.dot(r.diagnostics["mirror_normal"], n)) > 0.99  # in the gyro's frame


def test_rates_about_a_third_axis_tell_the_flip_and_leave_no_such_warning():
    R0, camera, gyro = _rig_from_body_rates(0.3)
    r = calibrate(camera, gyro, n_bootstrap=0)
    assert "mirror_fit_ratio" not in _reasons(r) and r.diagnostics["mirror_fit_ratio"] > 10
    assert so3.angle_between_deg(r.R, R0) < 0.2


def test_the_mirror_ratio_threshold_at_its_boundary():
    bound = THRESHOLDS["mirror_fit_ratio"][0]
    kw = dict(n_pairs=100, residual_median_deg=0.1, motion_median_deg=20.0, bootstrap_deg=0.05)
    below = judge(Evidence(**kw, mirror_fit_ratio=bound * (1 - 1e-9), mirror_normal=(0.0, 0.0, 1.0)))
    assert [(x.check, x.level) for x in below.reasons] == [("mirror_fit_ratio", "warning")]
    assert "[0.0, 0.0, 1.0], sensor frame" in below.reasons[0].message
    assert judge(Evidence(**kw, mirror_fit_ratio=bound)).reasons == ()


def test_a_remount_in_the_last_tenth_of_a_recording_fails_and_the_tested_splits_are_said():
    """Red team: a 5 deg re-mount at 55 s of 60 s gave ok (the splits left 15 % on each side)."""
    from replication.rig.calibration import CHANGE_MIN_SHARE
    from replication.rig.changepoint import remounted

    R0, camera, gyro, _ = rig_streams(60, rng=np.random.default_rng(3), camera_noise_deg=0.1, gyro_noise_deg_s=0.2)
    turn = so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5,
                                                                                                           0.81]))
    r = calibrate(camera, remounted(gyro, 55.0, turn), n_bootstrap=0)
    reason = _reasons(r)["remount_deg"]
    assert reason.level == "fail" and 54.0 <= r.change_test["split_time_s"] <= 56.0
    # the last split leaves 5 % of the pairs and 5 blocks (of 1 s) after it: later than 0.15's 51 s
    assert 60.0 * (1 - 0.15) < r.change_test["splits_to_s"] <= 60.0 * (1 - CHANGE_MIN_SHARE)
    assert "a change outside cannot be told" in r.summary()


# ---------------------------------------------------------------------- no clock, no offset (issue 33, point 6)

def test_a_static_pose_report_has_no_clock_offset_and_the_schema_says_null_is_allowed(rng):
    R0, C, S = _stations(rng, N=12)
    r = calibrate_poses(C, S, n_bootstrap=20)
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["time_offset_s"] is None and report["time_offset_correlation"] is None
    assert report["time_offset_applied"] is False and "time offset" not in r.summary()
    assert "null for static poses" in SCHEMA["properties"]["time_offset_s"]["description"]
    # the schema still refuses what is neither a number nor null
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**report, "time_offset_s": "0.0"}, SCHEMA)


def test_a_stream_report_keeps_its_measured_clock_offset(rng):
    _, camera, gyro, _ = rig_streams(30.0, rng=rng, camera_noise_deg=0.05)
    report = calibrate(camera, gyro, n_bootstrap=0).to_dict()
    jsonschema.validate(report, SCHEMA)
    assert isinstance(report["time_offset_s"], float)


# -------------------------------------------------------------------- stations counted once (issue 33, point 2)

def test_stations_given_twice_are_named_and_counted_once_in_the_bootstrap(rng):
    """The same 10 stations given twice: the same estimate and, drawn as 10 distinct stations, the same radius (it
    was 0.68 -> 0.44 deg, ok, nothing said)."""
    R0, C, S = _stations(rng, N=10)
    once = calibrate_poses(C, S, n_bootstrap=100, seed=3)
    twice = calibrate_poses(np.concatenate([C, C]), np.concatenate([S, S]), n_bootstrap=100, seed=3)
    assert twice.bootstrap_ci95_deg == pytest.approx(once.bootstrap_ci95_deg, rel=1e-9)
    assert so3.angle_between_deg(twice.R, once.R) < 1e-9
    assert once.station_repeats is None and "repeated_stations" not in _reasons(once)
    assert once.bootstrap_resamples == "stations"
    assert twice.station_repeats == {"stations": 20, "distinct": 10, "groups": [[k, k + 10] for k in range(10)]}
    assert twice.bootstrap_resamples == "distinct stations (repeats as one)"
    reason = _reasons(twice)["repeated_stations"]
    assert reason.level == "warning" and reason.measured == 10
    assert reason.message.startswith("10 of the 20 stations repeat others (0-based, the same attitude on both sides")
    assert "0 = 10; 1 = 11; 2 = 12; 3 = 13; 4 = 14; and 5 more groups" in reason.message
    assert "counted once in the bootstrap (10 distinct stations)" in reason.message
    report = twice.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["station_repeats"]["distinct"] == 10 and once.to_dict()["station_repeats"] is None


def test_stations_remeasured_within_the_noise_are_repeats_too(rng):
    R0, C, S = _stations(rng, N=8, station_noise_deg=0.3)
    sd = np.radians(0.3) / np.sqrt(3)
    C3 = np.concatenate([C, so3.matrix_from_rotation_vector(rng.normal(0, sd, (8, 3))) @ C,
                         so3.matrix_from_rotation_vector(rng.normal(0, sd, (8, 3))) @ C])
    S3 = np.concatenate([S, so3.matrix_from_rotation_vector(rng.normal(0, sd, (8, 3))) @ S,
                         so3.matrix_from_rotation_vector(rng.normal(0, sd, (8, 3))) @ S])
    r = calibrate_poses(C3, S3, n_bootstrap=50)
    assert r.station_repeats["distinct"] == 8 and r.station_repeats["groups"][0] == [0, 8, 16]
    consecutive = calibrate_poses(C3, S3, n_bootstrap=50, pairs="consecutive")  # repeats drawn as one there too
    assert consecutive.bootstrap_resamples == "distinct stations (repeats as one)"


@pytest.mark.parametrize("apart_deg, same", [(1.99, True), (2.01, False)])
def test_a_repeat_is_within_the_motion_a_pair_needs_on_both_sides(rng, apart_deg, same):
    """The boundary is min_motion_deg (2 deg by default): closer on both sides, a pair of them is noise, not motion,
    and they are one station; a station apart on one side only is no repeat (a bad measurement, not the same pose)."""
    from replication.rig.poses import repeated_stations

    R0, C, S = _stations(rng, N=6, station_noise_deg=0.0)
    turn = so3.matrix_from_rotation_vector(np.radians(apart_deg) * np.array([0.0, 0.6, 0.8]))
    C2, S2 = np.concatenate([C, (R0 @ turn @ R0.T @ C[2])[None]]), np.concatenate([S, (turn @ S[2])[None]])
    labels = repeated_stations(C2, S2, 2.0)
    assert bool(labels[6] == 2) is same and list(labels[:6]) == list(range(6))
    one_side = np.concatenate([C, C[2][None]]), np.concatenate([S, (turn @ S[2])[None]])
    if not same:
        assert repeated_stations(*one_side, 2.0)[6] == 6
    r = calibrate_poses(C2, S2, n_bootstrap=20)
    assert (r.station_repeats is not None) is same


@pytest.mark.parametrize("step_deg", [1.5, 1.0])
def test_a_chain_of_close_stations_is_not_one_station(step_deg):
    """Each station step_deg from the next (under the 2 deg of a repeat), 30 of them spanning tens of degrees: no group
    may hold two stations further apart than 2 deg (a red-team case: a linked chain was read as one station)."""
    from replication.rig.poses import repeated_stations

    axis = np.array([0.0, 0.6, 0.8])
    S = so3.matrix_from_rotation_vector(np.radians(step_deg) * np.arange(30)[:, None] * axis)
    labels = repeated_stations(S, S, 2.0)
    for g in np.unique(labels):
        members = S[labels == g]
        assert so3.rotation_angle_deg(members[-1] @ members[0].T) <= 2.0 + 1e-9
    assert len(np.unique(labels)) >= 30 * step_deg / 3.0


def test_a_station_joins_a_group_only_if_it_repeats_every_member():
    from replication.rig.poses import repeated_stations

    axis = np.array([1.0, 0.0, 0.0])
    # 0-1 and 1-2 within 2 deg, 0-2 not
    S = so3.matrix_from_rotation_vector(np.radians([0.0, 1.5, 3.0])[:, None] * axis)
    assert repeated_stations(S, S, 2.0).tolist() == [0, 0, 2]


# ------------------------------------------------------------------ name the culprit (issue 33, point 5)

def _bad_stations(bad, N=20, seed=5, bad_deg=3.0):
    rng = np.random.default_rng(seed)
    R0, C, S = _stations(rng, N=N)
    for b in bad:
        C[b] = so3.matrix_from_rotation_vector(np.radians(bad_deg) * np.array([0.0, 0.6, 0.8])) @ C[b]
    return C, S


def _blamed(result):
    reason = _reasons(result).get("pose_outliers")
    if reason is None:
        return set()
    named = reason.message.split("):", 1)[1].split(">")[0]
    return {int(part.split("(")[0]) for part in named.split(",")}


@pytest.mark.parametrize("bad_deg", [3.0, 6.0])
@pytest.mark.parametrize("bad", [[7], [7, 8], [7, 9], [3, 12]], ids=["one", "two-adjacent", "two-one-apart", "apart"])
def test_with_consecutive_pairs_only_the_bad_stations_are_blamed(bad, bad_deg):
    """Their neighbours share a bad pair each; their own residual does not. The pairs' median (the rule before) named
    a neighbour in 7 of these 8 cases (and nothing for two adjacent stations 3 deg off)."""
    C, S = _bad_stations(bad, bad_deg=bad_deg)
    r = calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)
    assert _blamed(r) == set(bad)
    assert "(0-based index, its own residual)" in _reasons(r)["pose_outliers"].message


def test_with_consecutive_pairs_a_clean_set_blames_no_station():
    C, S = _bad_stations([])
    assert _blamed(calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)) == set()


def test_a_stations_own_residual_is_its_error_and_the_pairs_median_would_blame_its_neighbours():
    from replication.rig.estimate import per_station_median
    from replication.rig.poses import own_residuals_deg, pose_pairs

    C, S = _bad_stations([7], bad_deg=6.0)
    r = calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)
    own = own_residuals_deg(C, S, r.R)
    assert _blamed(r) == {7}
    assert 3.0 < own[7] < 7.0 and np.max(np.delete(own, 7)) < 3 * np.median(own) < own[7]
    A, B, i, j = pose_pairs(C, S, pairs="consecutive", stations=True)
    from replication.core.handeye import pair_residual_deg

    medians = per_station_median(pair_residual_deg(r.R, A, B), (i, j, len(C)))
    assert max(medians[6], medians[8]) > 3 * np.median(medians)  # the old rule blamed a neighbour


def test_identical_stations_are_repeats_even_with_no_motion_threshold(rng):
    R0, C, S = _stations(rng, N=10)
    r = calibrate_poses(np.concatenate([C, C]), np.concatenate([S, S]), min_motion_deg=0.0, n_bootstrap=20)
    assert r.station_repeats["distinct"] == 10 and "repeated_stations" in _reasons(r)
