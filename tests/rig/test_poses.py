"""Static pose sets (``replication/rig/poses.py``): ``calibrate_poses`` recovers a known R0 from
noise-free stations and gets a verdict; an outlying station is named by its own residual (not the
pairs' median, which blames its neighbours); stations repeated within the motion a pair needs are
grouped (every member repeats every other, a chain of close stations is no group); the report has
no clock offset; two references, and references of a bad shape."""
import jsonschema
import numpy as np
import pytest

from conftest import SCHEMA, _reasons, _stations, _turned
from replication.core import so3
from replication.rig.poses import calibrate_poses
from replication.rig.quality import THRESHOLDS
from replication.testing import RIG_R0 as R0


def test_calibrate_poses_recovers_R0(rng):
    R0 = so3.random_rotations(rng, ())
    S = so3.random_rotations(rng, 15)  # sensor_from_world
    C = R0 @ S  # camera_from_world = camera_from_sensor sensor_from_world
    res = calibrate_poses(C, S, reference=R0, n_bootstrap=0)
    assert res.reference_error_deg < 1e-10 and res.n_pairs == 105  # noise-free: measured 5e-14


def test_static_pose_sets_get_a_verdict_and_name_their_pairs(rig):
    camera, _, sensor = rig
    C, S = np.swapaxes(camera.R[::60], -1, -2), np.swapaxes(sensor.at(camera.t[::60]), -1, -2)
    r = calibrate_poses(C, S, reference=R0, n_bootstrap=20)
    assert r.verdict.level == "ok" and r.reference_error_deg < 1e-10  # noise-free: measured 6e-14
    assert "pairs of static poses" in r.summary() and "nan" not in r.summary()



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
    """The boundary is min_motion_deg (2 deg by default): closer on both sides, a pair of them is
    noise, not motion, and they are one station; a station apart on one side only is no repeat (a
    bad measurement, not the same pose)."""
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
    """Each station step_deg from the next (under the 2 deg of a repeat), 30 of them spanning tens
    of degrees: no group may hold two stations further apart than 2 deg (a case once found: a linked
    chain was read as one station)."""
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



def test_identical_stations_are_repeats_even_with_no_motion_threshold(rng):
    R0, C, S = _stations(rng, N=10)
    r = calibrate_poses(np.concatenate([C, C]), np.concatenate([S, S]), min_motion_deg=0.0, n_bootstrap=20)
    assert r.station_repeats["distinct"] == 10 and "repeated_stations" in _reasons(r)



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
    """Their neighbours share a bad pair each; their own residual does not. The pairs' median (the
    rule before) named a neighbour in 7 of these 8 cases (and nothing for two adjacent stations 3
    deg off)."""
    C, S = _bad_stations(bad, bad_deg=bad_deg)
    r = calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)
    assert _blamed(r) == set(bad)
    assert "(0-based index, its own residual)" in _reasons(r)["pose_outliers"].message



def test_with_consecutive_pairs_a_clean_set_blames_no_station():
    C, S = _bad_stations([])
    assert _blamed(calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)) == set()



def test_a_stations_own_residual_is_its_error_and_the_pairs_median_would_blame_its_neighbours():
    from replication.rig.poses import own_residuals_deg, pose_pairs
    from replication.rig.solve_and_judge import per_station_median

    C, S = _bad_stations([7], bad_deg=6.0)
    r = calibrate_poses(C, S, pairs="consecutive", n_bootstrap=0)
    own = own_residuals_deg(C, S, r.R)
    assert _blamed(r) == {7}
    assert 3.0 < own[7] < 7.0 and np.max(np.delete(own, 7)) < 3 * np.median(own) < own[7]
    A, B, i, j = pose_pairs(C, S, pairs="consecutive", stations=True)
    from replication.core.handeye import pair_residual_deg

    medians = per_station_median(pair_residual_deg(r.R, A, B), (i, j, len(C)))
    assert max(medians[6], medians[8]) > 3 * np.median(medians)  # the old rule blamed a neighbour



def test_two_references_for_static_poses_and_bad_shapes(rig_tr):
    R0, camera, _ = rig_tr
    C = np.swapaxes(camera.R[::40], -1, -2)
    S = np.swapaxes(camera.R[::40] @ R0, -1, -2)
    r = calibrate_poses(C, S, n_bootstrap=0, reference=np.stack([_turned(R0, 0.1), _turned(R0, -0.1)]))
    assert r.reference_disagreement_deg == pytest.approx(0.2) and len(r.reference_errors_deg) == 2
    with pytest.raises(ValueError, match=r"got shape \(3, 3, 3\) \(two references, e.g. two published"):
        calibrate_poses(C, S, n_bootstrap=0, reference=np.stack([R0] * 3))
