"""The common end of ``calibrate`` (``rig/solve_and_judge.py``): ``solve_pairs`` takes the pairs and
its named groups (``Resampling``, ``Provenance``), frozen; the bootstrap of pose sets draws stations
(repeats as one) and covers the error; every bootstrap replicate is judged (no rotation, no solution
of its resample at the fit factor, the answer returned unchanged), the solver named."""
import inspect
import math
import re

import jsonschema
import numpy as np
import pytest

from conftest import SCHEMA, _nan_like, _poses, _random_rotation, _reasons, _stations, noisy_problem
from replication.core import so3
from replication.rig.poses import calibrate_poses
from replication.rig.solve_and_judge import reference_reading


def test_solve_pairs_takes_the_pairs_and_six_named_groups():
    from replication.rig.solve_and_judge import solve_pairs

    params = inspect.signature(solve_pairs).parameters
    assert list(params) == ["A", "B", "method", "options", "reference", "evidence", "resampling", "provenance"]
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY and p.default is inspect.Parameter.empty
               for p in list(params.values())[2:])  # nothing forgotten silently: every group is said


def test_the_groups_are_frozen():
    import dataclasses

    from replication.rig.solve_and_judge import Provenance, Resampling

    with pytest.raises(dataclasses.FrozenInstanceError):
        Resampling(n_bootstrap=10, seed=0).seed = 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        Provenance().interval = 1.0
    p = Provenance()  # the defaults say "no clock, no interval" (a pose set), never a made-up number
    assert np.isnan(p.interval) and np.isnan(p.time_offset[0]) and p.time_offset[2] is False
    assert p.parameters == {} and p.parameters is not Provenance().parameters  # no dict shared between calls


def test_solve_pairs_reports_its_provenance_and_resamples_as_told():
    from replication.rig.solve_and_judge import Provenance, Resampling, solve_pairs

    R0, A, B = noisy_problem()
    times = np.arange(len(A)) * 0.5
    kw = dict(method="chordal_optimal", options={}, reference=R0, evidence={})
    provenance = Provenance(interval=0.5, time_offset=(0.01, 0.9, True), parameters={"method": "chordal_optimal"},
                            pair_times=times, extra_diagnostics={"mine": 1})
    res = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=3, block=3), provenance=provenance, **kw)
    assert res.interval_s == 0.5 and res.time_offset_s == 0.01 and res.time_offset_applied is True
    assert res.parameters == {"method": "chordal_optimal"} and res.diagnostics["mine"] == 1
    assert res.diagnostics["pair_times"] is times
    assert res.bootstrap_resamples == "pairs in moving blocks of 3" and np.isfinite(res.bootstrap_ci95_deg)
    again = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=3, block=3), provenance=provenance, **kw)
    assert again.bootstrap_ci95_deg == res.bootstrap_ci95_deg  # the seed decides the replicates
    other = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=4, block=3), provenance=provenance, **kw)
    assert other.bootstrap_ci95_deg != res.bootstrap_ci95_deg
    none = solve_pairs(A, B, resampling=Resampling(n_bootstrap=0, seed=3), provenance=Provenance(), **kw)
    assert none.bootstrap_resamples == "none" and np.isnan(none.bootstrap_ci95_deg) and np.isnan(none.interval_s)


EPS = 1e-9


@pytest.mark.parametrize("errors, floor, reading", [
    ((0.169, 0.234), 0.343, "agreement, not accuracy: both errors (0.169, 0.234 deg)"),  # EuRoC MH01, measured
    ((0.3, 0.3), 0.3, "agreement, not accuracy"),                      # at the floor: within it
    ((0.3 + EPS, 0.1), 0.3, "closer to reference 2: its error (0.100 deg) is within"),  # one just above
    ((0.1, 0.3 + EPS), 0.3, "closer to reference 1"),
    ((0.3 + EPS, 0.3 + EPS), 0.3, "a difference beyond the floor: both errors"),
])
def test_the_reading_of_two_references_at_the_floor(errors, floor, reading):
    text = reference_reading(errors, floor)
    assert text.startswith(reading)
    assert f"the references' own disagreement {floor:.3f} deg (the reference floor)" in text


@pytest.mark.parametrize("errors, floor, radius, reading", [
    ((0.0, 10.0), 10.0, 0.1, "closer to reference 1: its error (0.000 deg) is the smaller, by more than R0's"),
    ((0.5, 9.5), 10.0, 0.1, "closer to reference 1"),                   # was "agreement, not accuracy"
    ((0.05, 0.05), 0.0, 0.1, "agreement within R0's radius"),           # the same reference twice: was "beyond"
    ((0.1, 0.1), 0.0, 0.1, "agreement within R0's radius"),             # at the radius: within it
    ((0.1 + EPS, 0.1 + EPS), 0.0, 0.1, "a difference beyond the floor"),
    ((0.169, 0.234), 0.343, 0.09, "agreement, not accuracy"),           # EuRoC: 0.065 apart, within the radius
    ((0.169, 0.234), 0.343, 0.064, "closer to reference 1"),            # ... and just beyond a smaller radius
    ((0.2, 0.4), 0.3, 0.5, "agreement within R0's radius"),
    ((0.2, 0.55), 0.35, 0.5, "not resolved: the errors (0.200, 0.550 deg) differ by no more than"),
])
def test_the_reading_weighs_the_difference_of_the_errors_against_r0s_radius(errors, floor, radius, reading):
    assert reference_reading(errors, floor, radius).startswith(reading)


def test_pose_sets_resample_stations_not_pairs(rng):
    R0, C, S = _stations(rng)
    r = calibrate_poses(C, S, n_bootstrap=100, seed=1)
    assert r.bootstrap_resamples == "stations"
    pairs = calibrate_poses(C, S, n_bootstrap=100, seed=1, pairs="consecutive")
    assert pairs.bootstrap_resamples == "pairs in moving blocks of 2"
    # the pairs share their stations' noise: 435 pairs from 30 stations carry about 30 stations'
    # information
    import replication.rig.solve_and_judge as est

    J = r.n_pairs
    by_pairs = est.block_indices(np.random.default_rng(1), J, 1, 100)
    motions = __import__("replication.core.motions", fromlist=["prepare_motions"]).prepare_motions(
        *__import__("replication.rig.poses", fromlist=["pose_pairs"]).pose_pairs(C, S))
    R_boot = est.bootstrap_replicates(motions, "chordal_optimal", {}, by_pairs, progress=False)
    naive = float(np.percentile(so3.angle_between_deg(R_boot, r.R), 95))
    assert r.bootstrap_ci95_deg > 2.5 * naive



def test_station_bootstrap_covers_the_error_about_95_percent(rng):
    """40 problems: the error within the station radius in most (the 95 % level, 40 draws: at least
    32)."""
    hits = 0
    for _ in range(40):
        R0, C, S = _stations(rng, N=20)
        r = calibrate_poses(C, S, n_bootstrap=100, seed=2)
        hits += float(so3.angle_between_deg(r.R, R0)) <= r.bootstrap_ci95_deg
    assert hits >= 32, hits



def test_stations_given_twice_are_named_and_counted_once_in_the_bootstrap(rng):
    """The same 10 stations given twice: the same estimate and, drawn as 10 distinct stations, the
    same radius (it was 0.68 -> 0.44 deg, ok, nothing said)."""
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



def _bad_replicates(rig, door_solver, answer, bad_calls, counted):
    """A pose-set calibration with a solver giving ``answer(R, call)`` on the calls ``bad_calls``
    (the first call is the calibration's own solve): without bad calls a radius and no reason; else
    a ``bootstrap_answers`` fail counting them, and no radius. Returns the solver's name, the result
    and the reason (None without bad calls)."""
    C, S = _poses(rig)
    name = door_solver(lambda R, call: answer(R, call) if call in bad_calls else R)
    r = calibrate_poses(C, S, method=name, n_bootstrap=20, diagnose=False)
    reasons = _reasons(r)
    if not counted:
        assert "bootstrap_answers" not in reasons and math.isfinite(r.bootstrap_ci95_deg)
        return name, r, None
    reason = reasons["bootstrap_answers"]
    assert reason.level == "fail" and r.verdict.level == "fail" and reason.measured == counted
    assert not math.isfinite(r.bootstrap_ci95_deg) and r.diagnostics["bootstrap_rotvec_deg"].size == 0
    return name, r, reason



@pytest.mark.parametrize("what, answer, words", [
    ("reflection", lambda R: -R, r"returned a reflection \(det -1\)"),
    ("nan", _nan_like, r"declared a failure \(NaN\)"),
])
@pytest.mark.parametrize("bad_calls, counted", [((), 0), ((1,), 1), ((1, 5, 7), 3)])
def test_replicates_that_are_no_rotations_fail_naming_the_solver_and_give_no_radius(
        rig, door_solver, what, answer, words, bad_calls, counted):
    """No bad replicate: a radius and no such reason; one bad replicate of 20 (the boundary) already
    fails."""
    name, r, reason = _bad_replicates(rig, door_solver, lambda R, call: answer(R), bad_calls, counted)
    if reason is not None:
        assert re.search(rf"solver '{name}' {words} on {counted} of 20 bootstrap replicates", reason.message)
        assert r.to_dict()["bootstrap_ci95_deg"] is None



def test_bootstrap_replicates_without_masks_refuse_non_rotations(rig, door_solver):
    import replication.rig.solve_and_judge as est
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    motions = prepare_motions(*pose_pairs(C, S))
    name = door_solver(lambda R, call: -R if call == 2 else R)
    sets = est.block_indices(np.random.default_rng(0), motions.J, 1, 4)
    with pytest.raises(ValueError, match=rf"solver '{name}' returned a reflection \(det -1\) on 1 of 4 bootstrap"):
        est.bootstrap_replicates(motions, name, {}, [s for s in sets])
    R, failed, reflection, unfit = est.bootstrap_replicates(motions, name, {}, [s for s in sets], masks=True)
    assert not reflection.any() and not failed.any()  # calls 4-7: the bad one (call 2) was in the first run



@pytest.mark.parametrize("bad_calls, counted", [((), 0), ((1,), 1), ((1, 5, 7), 3)])
def test_replicates_that_are_no_solutions_fail_naming_the_solver_and_give_no_radius(rig, door_solver, bad_calls,
                                                                                    counted):
    """Right on the calibration's own solve, random rotations on some replicates (rotations, so the
    registry's checks pass them): without one, a radius; one of 20 (the boundary) already fails,
    naming the solver."""
    name, r, reason = _bad_replicates(rig, door_solver, _random_rotation, bad_calls, counted)
    if reason is None:
        return
    assert re.search(rf"solver '{name}' returned an answer that is no solution of its resample on {counted} of 20 "
                     r"bootstrap replicates \(worst: root-mean-square pair residual [\d.]+ deg", reason.message)
    assert "not a solution on resamples" in reason.message and "np." not in reason.message



def test_an_outlying_station_drawn_often_does_not_make_the_optimum_a_non_solution(rig):
    """A resample that draws an outlying station several times pulls the least-squares answer off
    the other stations (their median residual grows 6-fold here): it is still the resample's
    optimum, and not blamed."""
    C, S = _poses(rig)
    rng = np.random.default_rng(2)
    C = C @ so3.matrix_from_rotation_vector(rng.normal(scale=np.radians(0.3), size=(len(C), 3)))
    k = rng.choice(len(C), 1)
    C[k] = C[k] @ so3.matrix_from_rotation_vector(np.radians(30.0) * so3.random_rotations(rng, 1)[:, 0])
    r = calibrate_poses(C, S, n_bootstrap=200, diagnose=False)
    assert "bootstrap_answers" not in _reasons(r) and math.isfinite(r.bootstrap_ci95_deg)



def _rms(residual_deg):
    """Cost (8) of the pairs as an angle: the angle whose chordal distance is their root-mean-square
    one."""
    return float(np.degrees(2 * np.arcsin(np.sqrt(np.mean(np.sin(np.radians(residual_deg) / 2) ** 2)))))



@pytest.mark.parametrize("side", [-1, 1])
def test_a_replicate_is_judged_at_the_factor_times_the_answers_fit_on_the_same_pairs(rig, side):
    """The boundary: a replicate turned from the answer by just less / more than the angle at which
    its root-mean-square residual reaches REPLICATE_FIT_FACTOR times the answer's on the same pairs
    (noisy poses) is a solution / is not."""
    import replication.rig.solve_and_judge as est
    from replication.core.handeye import pair_residual_deg
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    C = C @ so3.matrix_from_rotation_vector(np.random.default_rng(1).normal(scale=np.radians(0.3), size=(len(C), 3)))
    motions = prepare_motions(*pose_pairs(C, S))
    R = calibrate_poses(C, S, n_bootstrap=0, diagnose=False).R
    sets = [np.arange(0, motions.J, 2)]  # a resample: every other pair
    base = _rms(pair_residual_deg(R, motions.A[sets[0]], motions.B[sets[0]]))
    threshold = est.REPLICATE_FIT_FACTOR * base + est.REPLICATE_FIT_FLOOR_DEG

    def turned(angle_deg):
        return so3.matrix_from_rotation_vector(np.radians(angle_deg) * np.array([0.0, 0.0, 1.0])) @ R

    def own(angle_deg):
        return _rms(pair_residual_deg(turned(angle_deg), motions.A[sets[0]], motions.B[sets[0]]))

    lo, hi = 0.0, 90.0  # bisection for the angle where the replicate's median reaches the threshold
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if own(mid) < threshold else (lo, mid)
    angle = hi * (1 + side * 1e-3)
    flags, (mine, full) = est.unfit_replicates(motions, turned(angle)[None], sets, R)
    assert full[0] == pytest.approx(base) and mine[0] == pytest.approx(own(angle))
    assert bool(mine[0] > threshold) is (side > 0) and bool(flags[0]) is (side > 0)



def test_bootstrap_replicates_without_masks_refuse_no_solutions_naming_the_solver(rig, door_solver):
    import replication.rig.solve_and_judge as est
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    motions = prepare_motions(*pose_pairs(C, S))
    sets = [s for s in est.block_indices(np.random.default_rng(0), motions.J, 1, 4)]
    # calls 0-3: the replicates (call 2 the third), then one solve on all the pairs for the check
    name = door_solver(lambda R, call: _random_rotation(R, call) if call == 2 else R)
    with pytest.raises(ValueError, match=rf"solver '{name}' returned an answer that is no solution of its resample "
                                         r"on 1 of 4 bootstrap replicates"):
        est.bootstrap_replicates(motions, name, {}, sets)
    name = door_solver(lambda R, call: R)
    R_boot, failed, reflection, unfit = est.bootstrap_replicates(motions, name, {}, sets, masks=True)
    assert not (failed.any() or reflection.any() or unfit.any()) and R_boot.shape == (4, 3, 3)



def test_a_solver_that_returns_its_first_answer_on_every_replicate_fails_naming_it(rig, door_solver):
    """A solver that ignores its input (its first answer cached) would give a radius of zero: it
    fails, named; the same pose set with an honest solver keeps its radius, and noise-free data
    (replicates all equal to the answer, as they should be) name nothing."""
    C, S = _poses(rig)
    noisy = C @ so3.matrix_from_rotation_vector(np.random.default_rng(3).normal(scale=np.radians(0.3), size=(len(C),
                                                                                                             3)))
    first = {}
    name = door_solver(lambda R, call: first.setdefault("R", R) if R.ndim == 2 else np.broadcast_to(
        first.setdefault("R", R[0]), R.shape).copy())
    r = calibrate_poses(noisy, S, method=name, n_bootstrap=20, diagnose=False)
    reason = _reasons(r)["bootstrap_answers"]
    assert reason.level == "fail" and f"solver '{name}' returned the answer on all the pairs, unchanged" in (
        reason.message) and "on every one of the 20 bootstrap replicates" in reason.message
    assert not math.isfinite(r.bootstrap_ci95_deg)
    honest = calibrate_poses(noisy, S, n_bootstrap=20, diagnose=False)
    assert "bootstrap_answers" not in _reasons(honest) and honest.bootstrap_ci95_deg > 0
    exact = calibrate_poses(C, S, n_bootstrap=20, diagnose=False)
    assert "bootstrap_answers" not in _reasons(exact) and math.isfinite(exact.bootstrap_ci95_deg)



@pytest.mark.parametrize("turn, frozen", [(0.5, True), (2.0, False)])
def test_replicates_frozen_at_the_bound(rig, door_solver, turn, frozen):
    """Replicates all turned from the answer by half / twice FROZEN_DEG: the answer returned
    unchanged, or not."""
    import replication.rig.solve_and_judge as est

    C, S = _poses(rig)
    noisy = C @ so3.matrix_from_rotation_vector(np.random.default_rng(3).normal(scale=np.radians(0.3), size=(len(C),
                                                                                                             3)))
    first = {}
    step = so3.matrix_from_rotation_vector(np.radians(turn * est.FROZEN_DEG) * np.array([0.0, 0.0, 1.0]))
    name = door_solver(lambda R, call: first.setdefault("R", R) if call == 0 else step @ first["R"])
    r = calibrate_poses(noisy, S, method=name, n_bootstrap=20, diagnose=False)
    assert ("bootstrap_answers" in _reasons(r)) is frozen
