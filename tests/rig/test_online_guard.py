"""``ready`` means still right: the online estimator withdraws ``ready`` as soon as the recent pairs
agree on a rotation that its radius does not allow, before its change detector has decided anything;
each rule of the guard (:mod:`replication.rig.online_guard`) at its boundary."""
import math

import numpy as np
import pytest

from replication.core import so3
from replication.core.stats import chi2_quantile
from replication.rig.online import OnlineCalibrator
from replication.rig.online_causes import constant_speed
from replication.rig.online_events import pair_d2
from replication.rig.online_guard import (
    GUARD_EVERY,
    GUARD_K,
    GUARD_LEVEL,
    GUARD_MIN_PAIRS,
    GUARD_WINDOW,
    MisfitGuard,
    misfit_test,
)
from replication.rig.quality import Reason
from replication.study.live_study import pair_stream

AXIS = np.array([0.6, 0.0, 0.8])
GUARD_SAYS = "beyond what its radius allows"  # the guard's sentence in not_ready (MisfitGuard.describe)


def _guard_said(oc):
    """``not_ready`` holds the guard's sentence: its recent pairs misfit."""
    return any(GUARD_SAYS in m for m in oc.status()["not_ready"])


def _remounted(seed, step_deg, noise_deg, before=200, after=100):
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(step_deg) * AXIS)
    A1, B1 = pair_stream(rng, before, R0, noise_deg=noise_deg)
    A2, B2 = pair_stream(rng, after, R1, noise_deg=noise_deg)
    return R1, (A1, B1), (A2, B2)


def _first_withdrawal(oc, A, B):
    """Feed pairs one at a time; the index of the first not ready, with what held at that pair."""
    for k, (a, b) in enumerate(zip(A, B)):
        state = oc.update(a, b)
        if not state.ready:
            return k, state
    return None, None


def test_the_guard_constants():
    assert (GUARD_LEVEL, GUARD_MIN_PAIRS, GUARD_K, GUARD_WINDOW, GUARD_EVERY) == (0.9999, 3, 1.5, 20, 20)
    assert MisfitGuard(64).threshold == pytest.approx(chi2_quantile(0.9999, 3)) == pytest.approx(21.84, abs=0.01)


def test_a_1_deg_remount_withdraws_ready_within_a_few_pairs_before_the_detector_decides():
    """1 deg at 0.2 deg of noise: the CUSUM needs about 6 pairs to alarm and 10 more to confirm;
    ``ready`` goes at the 2nd-5th pair, withdrawn by the guard; in most runs by the guard alone (no
    alarm, fewer than 2 gross misfits, radius and verdict fine)."""
    alone = 0
    for seed in range(6):
        R1, (A1, B1), (A2, B2) = _remounted([21, seed], 1.0, 0.2)
        oc = OnlineCalibrator()
        oc.update_many(A1, B1)
        assert oc.ready and oc.error_deg(R1) > 0.9
        k, state = _first_withdrawal(oc, A2, B2)
        assert k is not None and k <= 5
        said = [m for m in oc.status()["not_ready"] if GUARD_SAYS in m]
        assert len(said) == (oc.radius != oc.status()["radius_deg"])  # said exactly when the radius is widened
        alone += (bool(said) and "agree on a rotation" in said[0] and oc.unresolved_end() is None
                  and oc.status()["radius_deg"] < oc.target_deg and oc.determined
                  and oc.current_verdict.level != "fail")
    assert alone >= 3


def test_a_shift_too_small_for_any_residual_is_seen_by_the_guard():
    """1 deg at 0.5 deg of noise: no pair's residual stands out (no gross misfit), the CUSUM has not
    alarmed; the guard withdraws ``ready`` within 30 pairs in each of 8 runs, by its run or by its
    window of the last 20 pairs (seed [22, 2]: the window, at the 29th pair)."""
    by = []
    for seed in range(8):
        R1, (A1, B1), (A2, B2) = _remounted([22, seed], 1.0, 0.5)
        oc = OnlineCalibrator()
        oc.update_many(A1, B1)
        assert oc.ready
        k, state = _first_withdrawal(oc, A2, B2)
        guard = oc._detector.guard
        assert k is not None and k < 30 and oc.unresolved_end() is None  # no alarm, fewer than 2 gross misfits
        assert oc.status()["radius_deg"] < 0.5 and oc.radius == pytest.approx(oc.status()["radius_deg"]
                                                                              + guard.misfit[1])  # widened
        by.append("window" if guard.run_misfit is None else "run")
        assert guard.misfit == (guard.run_misfit or guard.window_misfit or guard.long_misfit) is not None
    assert by.count("window") >= 1 and by.count("run") >= 5


def test_clean_streams_keep_ready():
    """No change: after the first ready, ready is withdrawn at fewer than 0.3 % of pairs (measured
    36 of 39,820 at 0.2 deg of noise and 36 of 39,630 at 0.5 deg, 2000 pairs for each of seeds [7,
    0..19]; here seeds [70, 0..2])."""
    lost = total = 0
    for seed in range(3):
        rng = np.random.default_rng([70, seed])
        R0 = so3.random_rotations(rng, ())
        states = OnlineCalibrator().update_many(*pair_stream(rng, 1500, R0, noise_deg=0.5))
        first = next(i for i, s in enumerate(states) if s.ready)
        lost += sum(not s.ready for s in states[first:])
        total += len(states) - first
    assert lost <= 0.003 * total


def _guard_pairs(rng, n, offset_deg=1.0, noise_deg=0.2):
    R = so3.random_rotations(rng, ())
    A, B = pair_stream(rng, n, R @ so3.matrix_from_rotation_vector(np.radians(offset_deg) * AXIS), noise_deg=noise_deg)
    return R, A, B


def test_the_statistic_equals_the_gauss_newton_step_in_numpy(rng):
    R, A, B = _guard_pairs(rng, 12)
    cov, s2 = np.diag([1e-8, 2e-8, 3e-8]), math.radians(0.2) ** 2
    E = R.T @ A @ R @ np.swapaxes(B, -1, -2)
    r = 0.5 * np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], -1)
    H = sum(2 * np.eye(3) - b - b.T for b in B)
    w = np.linalg.solve(H, sum(x - b.T @ x for x, b in zip(r, B)))
    C = s2 / 3 * np.linalg.inv(H) + cov
    stat, angle = misfit_test(R, cov, s2, A, B)
    assert stat == pytest.approx(w @ np.linalg.solve(C, w), rel=1e-9)
    assert angle == pytest.approx(np.degrees(np.linalg.norm(w)), rel=1e-9)
    assert misfit_test(R, None, s2, A, B)[0] > stat  # the estimate's own uncertainty lowers the statistic


def test_the_run_bound_never_understates_the_statistic(rng):
    """The run is solved only when its sum of 1.5 d^2 / s^2 exceeds the threshold: that sum bounds
    the statistic."""
    for _ in range(200):
        n = int(rng.integers(3, 30))
        R, A, B = _guard_pairs(rng, n, offset_deg=rng.uniform(0, 5), noise_deg=rng.uniform(0.05, 1.0))
        s2 = math.radians(rng.uniform(0.05, 1.0)) ** 2
        stat, _ = misfit_test(R, None, s2, A, B)
        assert stat <= 1.5 * pair_d2(R, A, B).sum() / s2 * (1 + 1e-12)


def _feed(guard, R, A, B, s2, cov=None):
    for a, b in zip(A, B):
        guard.add(a, b, float(pair_d2(R, a[None], b[None])[0]), R, cov, s2)


@pytest.mark.parametrize("just, withdrawn", [(1 - 1e-9, True), (1 + 1e-9, False)])
def test_the_run_is_withdrawn_just_past_the_threshold(rng, just, withdrawn):
    R, A, B = _guard_pairs(rng, 6, offset_deg=3.0)
    s2 = math.radians(0.2) ** 2
    stats = [misfit_test(R, None, s2, A[:n], B[:n])[0] for n in range(GUARD_MIN_PAIRS, 7)]
    guard = MisfitGuard(64)
    guard.threshold = max(stats) * just
    _feed(guard, R, A, B, s2)
    assert len(guard.pairs) == 6 and (guard.misfit is not None) is withdrawn
    if withdrawn:
        n, angle, stat, threshold = guard.misfit
        assert n == GUARD_MIN_PAIRS + int(np.argmax(stats)) and stat == pytest.approx(max(stats), rel=1e-9)


@pytest.mark.parametrize("n, tested", [(GUARD_MIN_PAIRS - 1, False), (GUARD_MIN_PAIRS, True)])
def test_the_run_is_tested_from_its_third_pair(rng, n, tested):
    R, A, B = _guard_pairs(rng, n, offset_deg=20.0)
    guard = MisfitGuard(64)
    _feed(guard, R, A, B, math.radians(0.2) ** 2)
    assert len(guard.pairs) == n and (guard.misfit is not None) is tested


@pytest.mark.parametrize("z, opens", [(GUARD_K, False), (GUARD_K * (1 + 1e-9), True)])
def test_the_run_opens_only_above_the_allowance(z, opens):
    guard = MisfitGuard(64)
    s2 = 1e-4
    guard.add(np.eye(3), np.eye(3), 2.0 * z * s2, np.eye(3), None, s2)
    assert (guard.sum > 0) is opens and len(guard.pairs) == int(opens)


def test_the_run_and_its_withdrawal_end_when_its_sum_returns_to_zero(rng):
    R, A, B = _guard_pairs(rng, 5, offset_deg=20.0)
    guard = MisfitGuard(64)
    s2 = math.radians(0.2) ** 2
    _feed(guard, R, A, B, s2)
    assert guard.run_misfit is not None
    total = guard.sum
    guard.add(np.eye(3), np.eye(3), 2.0 * s2 * (GUARD_K - total) + 1e-15, R, None, s2)  # sum just above 0
    assert guard.run_misfit is not None and guard.sum > 0
    guard.add(np.eye(3), np.eye(3), 2.0 * s2 * (GUARD_K - guard.sum), R, None, s2)  # sum exactly 0
    assert guard.sum == 0.0 and guard.run_misfit is None and len(guard.pairs) == 0


def test_the_window_is_tested_every_guard_every_pairs_on_the_last_guard_window(rng):
    from collections import deque

    R, A, B = _guard_pairs(rng, 2 * GUARD_WINDOW, offset_deg=2.0)
    s2 = math.radians(0.2) ** 2
    guard, recent = MisfitGuard(64), deque(maxlen=50)
    for k, (a, b) in enumerate(zip(A, B), 1):
        recent.append((a, b))
        guard.add(a, b, 0.0, R, None, s2, recent)  # residuals of 0: no run; only the window sees the shift
        due = k % GUARD_EVERY == 0 and k >= GUARD_WINDOW
        assert (guard.window_misfit is not None) is (k >= GUARD_WINDOW)  # 2 deg off: withdrawn from the first test
        if due:
            stat, angle = misfit_test(R, None, s2, A[k - GUARD_WINDOW:k], B[k - GUARD_WINDOW:k])
            assert guard.window_misfit == (GUARD_WINDOW, pytest.approx(angle), pytest.approx(stat), guard.threshold)
    guard.clear()
    assert guard.misfit is None


# ------------------------------------------------------------------------------------------------
# every rule of ready
# ready = determined (excitation, distinct pairs) and the radius below the target and no change
# being confirmed and fewer than 2 gross misfits and the guard's recent pairs fit and the verdict
# not fail. Each test below holds every other condition and fails if its own is dropped; the radius
# (test_online.py::test_ready_at_the_radius_target), the gross misfits
# (::test_ready_is_withdrawn_at_the_second_gross_misfit_and_said) and the verdict
# (::test_ready_needs_the_verdict_not_to_fail) are guarded there, the guard above.

def _others_hold(oc, *, determined=True):
    return (oc.radius < oc.target_deg and oc.unresolved_end() is None  # no alarm, fewer than 2 gross misfits
            and not _guard_said(oc) and oc.current_verdict.level != "fail"
            and oc.determined is determined)


def _excited(excitation_deg, n_z=20, n_x=20):
    """Noise-free motions about z (20-40 deg) and about x by small angles scaled to the given
    excitation (R0 = I)."""
    u = np.linspace(0.5, 1.5, n_x)
    target = math.radians(excitation_deg) ** 2 * (n_z + n_x)
    lo, hi = 0.0, 1.0
    for _ in range(100):
        c = 0.5 * (lo + hi)
        lo, hi = (c, hi) if np.sum(4 * np.sin(c * u / 2) ** 2) < target else (lo, c)
    return np.concatenate([so3.matrix_from_rotation_vector(np.outer(np.radians(np.linspace(20, 40, n_z)), [0, 0, 1])),
                           so3.matrix_from_rotation_vector(np.outer(c * u, [1, 0, 0]))])


@pytest.mark.parametrize("excitation, ready", [(0.5, False), (0.75, False), (0.98, False), (1.02, True)])
def test_ready_needs_the_motion_to_determine_r0_even_with_a_small_radius(excitation, ready):
    """Noise-free motion with 0.5-0.98 deg of excitation has a finite radius (the noise floor over
    the weak axis, 0.1-0.2 deg) below the 0.5 deg target and a verdict that does not fail: only "the
    motion determines R0" keeps ``ready`` false; just above the threshold it is ready."""
    A = _excited(excitation)
    oc = OnlineCalibrator()
    states = oc.update_many(A, A.copy())
    oc.estimate()
    assert oc.excitation_deg == pytest.approx(excitation, rel=1e-6)
    assert 0.02 < oc.radius < 0.25 and _others_hold(oc, determined=ready)
    assert oc.ready is ready and states[-1].ready is ready
    assert any("does not determine R0" in m for m in oc.status()["not_ready"]) is (not ready)


@pytest.mark.parametrize("distinct, ready", [(9, False), (10, True)])
def test_ready_needs_min_pairs_distinct_pairs_however_often_repeated(rng, distinct, ready):
    R0 = so3.random_rotations(rng, ())
    A, B = pair_stream(rng, distinct, R0, noise_deg=0.02, motion_deg=(40.0, 60.0))
    oc = OnlineCalibrator()
    states = oc.update_many(np.tile(A, (20, 1, 1)), np.tile(B, (20, 1, 1)))
    assert oc.n_pairs == distinct and oc.duplicates == 19 * distinct
    assert states[-1].ready is ready and oc.determined is ready
    if not ready:
        assert oc.radius == math.inf and f"9.0 effective distinct pairs < 10 ({19 * distinct} repeated pairs refused)" \
            in oc.status()["not_ready"][0]


def test_ready_waits_while_a_change_is_being_confirmed(rng):
    """An alarm being confirmed (here raised by hand on in-control pairs): not ready, every other
    condition holding; ready again once the window is decided (outliers: nothing changed)."""
    R0 = so3.random_rotations(rng, ())
    A, B = pair_stream(rng, 300, R0)
    oc = OnlineCalibrator()
    oc.update_many(A[:200], B[:200])
    assert oc.ready and _others_hold(oc)
    oc._detector._alarm(oc.n_total - 1, "cusum")
    states = oc.update_many(A[200:205], B[200:205])
    assert oc.checking and not any(s.ready for s in states) and _others_hold(oc) is False
    assert oc.radius < oc.target_deg and not _guard_said(oc) and oc._detector.misfits < 2
    assert any("a change is being confirmed" in m for m in oc.status()["not_ready"])
    oc.update_many(A[205:260], B[205:260])
    assert not oc.checking and oc.ready and [e.kind for e in oc.events] != ["remount"]


def test_a_window_withdrawal_holds_until_a_window_fits_as_usual(rng):
    from replication.rig.online_guard import GUARD_CLEAR_LEVEL

    R, A, B = _guard_pairs(rng, GUARD_WINDOW, offset_deg=2.0)
    s2, recent = math.radians(0.2) ** 2, list(zip(A, B))
    stat = misfit_test(R, None, s2, A, B)[0]
    guard = MisfitGuard(64)
    assert guard.clear_threshold == pytest.approx(chi2_quantile(GUARD_CLEAR_LEVEL, 3)) and GUARD_CLEAR_LEVEL == 0.95

    def scan():  # GUARD_EVERY pairs of residual 0 (no run): the window is tested once, at the last
        assert GUARD_EVERY == GUARD_WINDOW
        for a, b in recent:
            guard.add(a, b, 0.0, R, None, s2, recent)

    guard.threshold = stat * (1 + 1e-9)
    scan()
    assert guard.window_misfit is None
    guard.threshold = stat * (1 - 1e-9)
    scan()
    assert guard.window_misfit is not None and guard.window_misfit[2] == pytest.approx(stat)
    guard.threshold, guard.clear_threshold = 2 * stat, stat * (1 - 1e-9)  # between the two levels: still withdrawn
    scan()
    assert guard.window_misfit is not None
    guard.clear_threshold = stat  # at the clearing level: it fits as usual
    scan()
    assert guard.window_misfit is None


# ------------------------------------------------------------------------------------------------
# the long windows
def _long_remount(seed, step_deg=0.7, noise_deg=1.0):
    R1, (A1, B1), (A2, B2) = _remounted([23, seed], step_deg, noise_deg, before=600, after=600)
    return R1, np.concatenate([A1, A2]), np.concatenate([B1, B2])


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_a_remount_smaller_than_the_noise_withdraws_ready_within_the_long_windows(seed):
    """0.7 deg at 1 deg of pair noise after 600 pairs (a case once found: ready while more than 0.5
    deg off on 301-739 of 1800 pairs, only an ``outliers`` event): no pair's residual and no 20
    pairs show it. Was ready while wrong on 280, 249 and 270 of the 600 pairs after it (seeds [23,
    1/3/4]); the long windows withdraw it within 150 pairs (the statistic of 0.7 deg in N pairs at 1
    deg of noise passes the 99.99 % level at N of about 100)."""
    R1, A, B = _long_remount(seed)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    wrong = [j for j, s in enumerate(states[600:]) if s.ready and so3.angle_between_deg(s.R, R1) > 0.5]
    assert len(wrong) <= 120 and max(wrong, default=0) < 150


def test_a_long_window_alone_keeps_ready_false_and_widens_the_radius():
    """The condition "recent pairs fit" by the long windows alone: on seed [23, 4] at pair 600 + 100
    the last 80-320 pairs misfit while every other condition of ``ready`` holds (determined, the
    estimate's radius below the target, no change being confirmed, no gross misfit, no run or
    20-pair window, verdict not fail); ``not_ready`` says it and the published radius includes the
    misfit's angle. Dropping the condition would leave ready true."""
    R1, A, B = _long_remount(4)
    oc = OnlineCalibrator()
    for j in range(len(A)):
        state = oc.update(A[j], B[j])
        guard = oc._detector.guard
        if j >= 600 and guard.long_misfit is not None and guard.run_misfit is None and guard.window_misfit is None:
            break
    else:
        raise AssertionError("no long window withdrew ready")
    n, angle, stat, threshold = guard.long_misfit
    assert n in (80, 160, 320) and stat > threshold == guard.threshold
    assert not state.ready and not oc.ready
    assert (oc.determined and oc.unresolved_end() is None and oc.current_verdict.level != "fail"
            and oc.status()["radius_deg"] < oc.target_deg)
    assert any(f"the last {n} pairs agree on a rotation" in m for m in oc.status()["not_ready"])
    assert oc.radius == pytest.approx(oc.status()["radius_deg"] + angle) and state.radius_deg == oc.radius
    assert oc.error_deg(R1) <= oc.radius  # the widened radius covers the error the estimate has


def test_the_long_windows_are_tested_at_their_cadence_on_their_last_pairs(rng):
    from replication.rig.online_guard import GUARD_LONG_EVERY, GUARD_LONG_WINDOWS

    assert GUARD_LONG_WINDOWS == (80, 160, 320) and GUARD_LONG_EVERY == 20
    R, A, B = _guard_pairs(rng, 340, offset_deg=0.5, noise_deg=1.0)
    s2 = math.radians(1.0) ** 2
    cov = np.diag([1e-8, 2e-8, 3e-8])
    guard = MisfitGuard(64)
    guard.threshold = 0.0  # every test withdraws: the recorded statistic shows which window was tested when
    for k, (a, b) in enumerate(zip(A, B), 1):
        before = dict(guard._long)
        guard.add(a, b, 0.0, R, cov, s2)  # residuals of 0: no run
        for n in GUARD_LONG_WINDOWS:
            tested = guard._long[n] is not before[n]
            assert tested is (k >= n and k % GUARD_LONG_EVERY == 0)
            if tested:  # the tail sums equal the window solved on its own
                stat, angle = misfit_test(R, cov, s2, A[k - n:k], B[k - n:k])
                assert guard._long[n] == (n, pytest.approx(angle, rel=1e-9), pytest.approx(stat, rel=1e-9), 0.0)
    assert guard.long_misfit[2] == max(m[2] for m in guard._long.values())


def test_a_decision_keeps_the_long_windows_and_a_remount_forgets_them(rng):
    R, A, B = _guard_pairs(rng, 80, offset_deg=2.0)
    s2 = math.radians(0.2) ** 2
    guard = MisfitGuard(64)
    for a, b in zip(A, B):
        guard.add(a, b, 0.0, R, None, s2)
    assert guard.long_misfit is not None and guard.long_misfit[0] == 80
    guard.clear()  # an outliers / noise decision: the pairs are still in the estimate
    assert guard.long_misfit is not None and guard.misfit == guard.long_misfit
    levels = guard.threshold, guard.clear_threshold
    guard.threshold = guard.clear_threshold = math.inf  # every window tested from now on fits
    for a, b in zip(A[:20], B[:20]):  # 20 more (GUARD_LONG_EVERY): the 80-pair window is tested again, which it
        guard.add(a, b, 0.0, R, None, s2)  # is only if the ring kept its pairs through clear()
    assert guard.long_misfit is None
    guard.threshold, guard.clear_threshold = levels
    guard.forget()
    assert guard.long_misfit is None and guard.misfit is None
    for a, b in zip(A[:-1], B[:-1]):  # the ring starts empty: 79 pairs are too few for the first window
        guard.add(a, b, 0.0, R, None, s2)
    assert guard.long_misfit is None
    guard.add(A[-1], B[-1], 0.0, R, None, s2)
    assert guard.long_misfit is not None and guard.long_misfit[0] == 80


@pytest.mark.parametrize("just, withdrawn", [(1 - 1e-9, True), (1 + 1e-9, False)])
def test_a_long_window_withdraws_just_past_the_threshold(rng, just, withdrawn):
    R, A, B = _guard_pairs(rng, 80, offset_deg=0.5, noise_deg=1.0)
    s2 = math.radians(1.0) ** 2
    guard = MisfitGuard(64)
    guard.threshold = misfit_test(R, None, s2, A, B)[0] * just
    for a, b in zip(A, B):
        guard.add(a, b, 0.0, R, None, s2)
    assert (guard.long_misfit is not None) is withdrawn


# ------------------------------------------------------------------------------------------------
# the online verdict names a rig turning at constant speed once: from its own motions, with the
# unexcited axis, or from a front end's reason (``extra``) in its place


def _steady(seed=3, n=60):
    """``n`` pairs turning 29.5-30.5 deg about one axis (0.5 deg of noise: none refused as a
    repeat)."""
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    return pair_stream(rng, n, R0, noise_deg=0.5, motion_deg=(29.5, 30.5), axis=[0.0, 0.6, 0.8])


@pytest.mark.parametrize("extra, own", [
    ((), True),
    ((Reason("time_unit", "fail", 1e-3, 1e3, "a cause named by the front end"),), True),  # another cause: its own too
    ((constant_speed(np.full(10, 30.0), 0.0, 1.0, None),), False),  # the front end's sentence, not a second one
], ids=["alone", "beside-another-cause", "named-by-the-front-end"])
def test_the_online_verdict_names_constant_speed_once(extra, own):
    A, B = _steady()
    oc = OnlineCalibrator()
    oc.update_many(A, B)
    oc.set_context(extra=extra)
    assert oc.excitation_deg < oc.min_excitation_deg and oc.n_pairs == 60 and oc.duplicates == 0
    verdict = oc.verdict()
    named = [r for r in verdict.reasons if r.check == "constant_speed"]
    assert len(named) == 1 and verdict.level == "fail" and oc.current_verdict == verdict
    axis = f"(sensor frame {np.round(oc.status()['least_excited_axis_sensor'], 3).tolist()})"
    assert (axis in named[0].message) is own and "turns at a constant speed" in named[0].message
    assert [r.check for r in verdict.reasons if r.check == "time_unit"] == [r.check for r in extra
                                                                             if r.check == "time_unit"]


def _noise_with_the_motion(seed, frac=0.03):
    """150 weak (1-3 deg) then 250 rich (5-60 deg) pairs of one R0, each side turned by noise whose
    sd is ``frac`` of the pair's motion angle (at least 0.01 deg): a noise level that changes."""
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    A, B = [], []
    for n, lo, hi in ((150, 1, 3), (250, 5, 60)):
        clean = [pair_stream(rng, 1, R0, noise_deg=0.0, motion_deg=(lo, hi)) for _ in range(n)]
        for a, b in ((x[0][0], x[1][0]) for x in clean):
            sd = np.radians(max(frac * float(so3.rotation_angle_deg(a)), 0.01)) / np.sqrt(6)
            A.append(so3.matrix_from_rotation_vector(rng.normal(0, sd, 3)) @ a)
            B.append(so3.matrix_from_rotation_vector(rng.normal(0, sd, 3)) @ b)
    return R0, np.array(A), np.array(B)


@pytest.mark.xfail(strict=True, reason="after a noise_change with noise that grows with the motion, the estimator "
                   "says ready while 0.94 deg off (target 0.5, radius 0.28): 4 of 20 seeds (9, 12, 14, 19)")
def test_no_ready_while_wrong_when_the_noise_grows_with_the_motion():
    R0, A, B = _noise_with_the_motion(9)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    assert not [j for j, s in enumerate(states) if s.ready and so3.angle_between_deg(s.R, R0) > oc.target_deg]
