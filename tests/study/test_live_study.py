"""The simulation half of notebook 08 (``replication.study.live_study``) at small sizes, without the
real recordings.

The notebook runs these studies at full size (100-200 runs, 12-hour streams) and only where the real
recordings are present; here each runs in about a second on a few runs, and the assertions are the
notebook's claims, loosened to what so few runs can show.
"""
import numpy as np
import pytest

from replication.core.so3 import angle_between_deg, random_rotations, rotation_angle_deg
from replication.rig.online import MIN_PAIRS
from replication.rig.online_events import EVENT_KINDS
from replication.study.live_study import (
    coverage_study,
    degenerate_streams,
    detection_study,
    event_rates,
    online_mistakes,
    pair_stream,
    ready_coverage,
    update_costs,
)


def test_pair_stream_is_a_rig_with_the_stated_motions_and_noise(rng):
    R0 = random_rotations(rng, ())
    A, B = pair_stream(rng, 4000, R0, noise_deg=0.0, motion_deg=(5.0, 60.0))
    assert A.shape == B.shape == (4000, 3, 3)
    np.testing.assert_allclose(B, R0.T @ A @ R0, rtol=0, atol=1e-14)  # noise-free: eq. (7) exactly
    angles = rotation_angle_deg(A)
    assert 5.0 <= angles.min() < 5.5 and 59.5 < angles.max() <= 60.0
    A, B = pair_stream(rng, 4000, R0, noise_deg=0.5)
    residual = angle_between_deg(A @ R0, R0 @ B)  # the pair residual
    assert np.sqrt(np.mean(residual ** 2)) == pytest.approx(0.5, rel=0.03)  # RMS noise_deg (SE about 0.7 %)
    A, _ = pair_stream(rng, 50, R0, noise_deg=0.0, axis=[0.0, 3.0, 4.0])
    axes = np.stack([A[:, 2, 1] - A[:, 1, 2], A[:, 0, 2] - A[:, 2, 0], A[:, 1, 0] - A[:, 0, 1]], -1)
    np.testing.assert_allclose(axes / np.linalg.norm(axes, axis=1, keepdims=True),
                               np.tile([0.0, 0.6, 0.8], (50, 1)), atol=1e-12)


def test_coverage_study_covers_about_95_percent():
    table = coverage_study({"paper's simulation": {}}, n_runs=20, n_pairs=60, checkpoints=range(10, 61), seed=8000)
    row = table.loc["paper's simulation"]
    assert row["checks"] == 20 * 51
    # measured: 0.90 [0.82, 0.98]; a radius twice too large covers every check (interval [1, 1]),
    # half of it covers 0.42
    assert row["covered low"] <= 0.95 <= row["covered high"] and 0.8 <= row["covered"] <= 0.99
    assert 0 < row["median error (deg)"] < row["median radius (deg)"] < 0.5


def test_ready_coverage_is_ready_and_covered_when_it_says_so():
    table = ready_coverage({"noise 0.2": {"noise_deg": 0.2}, "small motions": {"noise_deg": 0.2,
                                                                               "motion_deg": (2.0, 10.0)}},
                           n_runs=20, n_pairs=300, seed=8001)
    assert (table["runs"] == 20).all() and (table["ready"] == 20).all()
    assert (table["covered share low"] <= 0.95).all() and (table["covered share high"] >= 0.95).all()
    assert (table["covered share"] >= 0.8).all()  # measured 0.95 (19 of 20) in both
    assert (table["median radius at ready (deg)"] < 0.5).all()  # the target
    assert (table["median pairs to ready"] >= MIN_PAIRS).all()
    # small motions need more pairs to reach the same radius (measured 10 and 60)
    assert table.loc["small motions", "median pairs to ready"] > table.loc["noise 0.2", "median pairs to ready"]


def test_degenerate_streams_are_never_ready():
    table = degenerate_streams(n_runs=2, n_pairs=100, seed=8003)
    assert len(table) == 8 and (table["runs"] == 2).all() and (table["false ready"] == 0).all()
    degenerate = table.drop(index="30 pairs, then the last repeated")
    assert (degenerate["ever ready"] == 0).all()
    assert all(said != "ready" for said in degenerate["said at the end (run 1)"])  # each names why not
    assert "the motion does not determine R0" in table.loc["one axis, noisy", "said at the end (run 1)"]
    assert "repeated pairs" in table.loc["one pair repeated", "said at the end (run 1)"]
    determined = table.loc["30 pairs, then the last repeated"]
    assert determined["ever ready"] == 2 and determined["largest error when ready (deg)"] < 0.5


def test_online_mistakes_are_never_ready_and_fail():
    table = online_mistakes(seed=8004, seconds=15.0)
    assert table.loc["as recorded", "ever ready"] and table.loc["as recorded", "final error (deg)"] < 0.5
    assert table.loc["as recorded", "verdict"] != "fail"
    mistakes = table.drop(index="as recorded")
    assert not mistakes["ever ready"].any() and (mistakes["verdict"] == "fail").all()
    assert "deg/s" in table.loc["gyro in deg/s read as rad/s", "input mistake named"]
    assert "camera_from_world" in table.loc["camera poses inverted (camera_from_world)", "input mistake named"]
    assert "sensor_from_world" in table.loc["sensor orientations inverted (sensor_from_world)", "input mistake named"]
    assert "offset_at_bound" in table.loc["sensor clock 5 s off", "fail checks"]
    assert "motion_median_deg" in table.loc["rig at rest", "fail checks"]


SETTING = {"noise 0.2 deg": {"noise_deg": 0.2, "motion_deg": (5.0, 60.0)}}


def test_a_short_clean_stream_has_no_event():
    row = event_rates(SETTING, hours=0.25, seed=8005).loc["noise 0.2 deg"]
    assert row["pairs"] == 900 and row["hours"] == 0.25
    assert all(row[kind] == 0 for kind in EVENT_KINDS) and row["false re-mounts per hour"] == 0
    assert row["95 % upper bound per hour"] == pytest.approx(-np.log(0.05) / 0.25)  # 0 events in 0.25 h
    assert row["final error (deg)"] < 0.05  # 900 pairs of 0.2 deg noise: measured 0.009


def test_outlier_bursts_and_noise_jumps_are_events_but_not_remounts():
    bursts = event_rates(SETTING, hours=0.25, seed=8007, burst_every=300).loc["noise 0.2 deg"]
    assert bursts["bursts"] >= 1 and bursts["outliers"] >= 1 and bursts["remount"] == 0  # measured 2 and 2
    assert bursts["final error (deg)"] < 0.05
    jumps = event_rates(SETTING, hours=0.25, seed=8008, jump_every=300).loc["noise 0.2 deg"]
    assert jumps["noise_change"] >= 1 and jumps["remount"] == 0 and "bursts" not in jumps


def test_a_5_deg_remount_is_detected_and_no_remount_is_not():
    table = detection_study((0.0, 5.0), {"noise 0.2 deg": {"noise_deg": 0.2}}, n_placements=4, seed=8009)
    none, five = table.loc[("noise 0.2 deg", 0.0)], table.loc[("noise 0.2 deg", 5.0)]
    assert none["detected"] == 0 and five["detected"] == 4 and (table["of"] == 4).all()
    assert (table["re-mounts before the step"] == 0).all() and (table["other events"] == 0).all()
    assert 0 < five["median delay (pairs)"] <= 50  # measured 14
    assert five["median error at the end (deg)"] < 0.1  # on the new mounting
    assert np.isnan(none["median delay (pairs)"])


def test_update_costs_are_per_pair_microseconds():
    costs = update_costs(300, seed=0)
    assert set(costs) == {"median_us", "mean_us", "p99_us", "replay_pairs_per_s"}
    # microseconds, not seconds: one Python-level update takes more than 1 us and (here) well under
    # 100 ms
    assert 1.0 < costs["median_us"] <= costs["p99_us"] < 1e5 and costs["mean_us"] > 1.0
    assert 10 < costs["replay_pairs_per_s"] < 1e7
