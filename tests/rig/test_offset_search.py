"""The clock offset's numerical core, :mod:`replication.rig.offset_search`: the parabola's vertex,
which maxima count, the overlap's ten samples, the bootstrap's replicates, and the search in
blocks (bounded memory, bit-identical to the search over all offsets at once).

Mutation testing (scripts/mutation) found the pieces' boundaries unguarded by the fast tests.
"""
import math
import tracemalloc
import warnings

import numpy as np
import pytest

from conftest import turning_streams
from replication.core import so3
from replication.rig import association, offset_search
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro

# --------------------------------------------------------------------------------------------------
# the search's pieces at their boundaries


def test_vertex_of_the_parabola_through_the_maximum_and_its_neighbours():
    x = np.array([0.0, 1.0, 2.0, 4.0, 5.0])
    y = -(x - 2.3) ** 2  # a parabola: its vertex exactly, though the points are unequally spaced
    assert offset_search.vertex(x, y) == pytest.approx(2.3, abs=1e-12)
    ys = np.stack([y, -(x - 0.8) ** 2, -(x - 4.4) ** 2])
    assert offset_search.vertex(x, ys) == pytest.approx([2.3, 0.8, 4.4], abs=1e-12)
    # a maximum at either end is not refined; nor a flat (non-concave) top; no finite value: NaN
    assert offset_search.vertex(x, x) == 5.0 and offset_search.vertex(x, -x) == 0.0
    lone = np.array([np.nan, 1.0, np.nan, 0.0, 0.0])  # no finite neighbours: no parabola
    assert offset_search.vertex(x, lone) == 1.0
    assert math.isnan(offset_search.vertex(x, np.full(5, np.nan)))
    with_nan = np.array([np.nan, 1.0, 3.0, 2.0, np.nan])
    assert 1.0 < offset_search.vertex(x, with_nan) < 4.0
    # the vertex is clipped to the three points' span
    skew = np.array([0.0, 0.0, 1.0, 0.999, 0.0])
    v = offset_search.vertex(x, skew)
    assert 1.0 <= v <= 4.0 and v == pytest.approx(
        0.5 * (1 + 2) - (1.0 / 1.0) / (2 * ((0.999 - 1.0) / 2.0 - 1.0) / 3.0))


def test_local_maxima_are_interior_strict_on_the_left():
    c = np.array([0.0, 1.0, 0.5, 0.5, 0.7, 0.7, 0.2, 0.9])
    assert offset_search.local_maxima(c).tolist() == [1, 4]  # 5 ties 4 from the left: not a maximum; 7 is an end
    assert offset_search.local_maxima(np.array([3.0, 2.0, 1.0])).tolist() == []


def test_the_overlap_needs_ten_camera_samples_inside_the_shifted_sensor_stream():
    cam, sen = turning_streams(n_cam=40)
    t, speed = offset_search.overlap(cam, sen, 0.2)
    assert np.array_equal(t, cam.t) and speed.shape == (39,)
    assert np.allclose(speed, np.linalg.norm([0.4, 0.9, -0.3]))
    # the sensor covers camera times 0 .. 0.45 + 0.2 exactly: ten samples (0 .. 0.45), inclusive at
    # both ends
    sen10 = OrientationStream(np.linspace(-0.2, 0.65, 86), so3.matrix_from_rotation_vector(np.linspace(-0.2, 0.65,
                                                                                                       86)[:, None]
                                                                         * np.array([0.4, 0.9, -0.3])))
    t, _ = offset_search.overlap(cam, sen10, 0.2)
    assert len(t) == 10 and t[0] == 0.0 and t[-1] == pytest.approx(0.45)
    sen9 = OrientationStream(np.linspace(-0.2, 0.6, 81), so3.matrix_from_rotation_vector(np.linspace(-0.2, 0.6,
                                                                                                     81)[:, None]
                                                                        * np.array([0.4, 0.9, -0.3])))
    with pytest.raises(ValueError, match=r"the streams overlap in fewer than 10 camera samples \(overlap "
                                         r"0\.000\.\.0\.400 s\)$"):
        offset_search.overlap(cam, sen9, 0.2)


# ------------------------------------------------------------------ the bootstrap's replicates

def _spike(n=10, seed=1):
    """Camera speeds with a spike at sample 0 (and an exact 0 at sample 1), and sensor rows at three
    offsets: the first matches the spike only, the last matches the rest only, the middle
    neither."""
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
        out = offset_search.bootstrap_offsets(a, rows, x, 200, 1, np.random.default_rng(0))
    # with the spike drawn the first offset matches best (-inf), without it the last (+inf); every
    # sample, the first too, is drawn with probability 1 - 0.9^10 = 65 % per replicate
    assert np.all(np.isinf(out))
    assert 110 <= np.sum(out == -np.inf) <= 150 and np.sum(out == np.inf) == 200 - np.sum(out == -np.inf)


def test_a_replicate_peaking_inside_is_refined_near_that_offset():
    rng = np.random.default_rng(2)
    a = rng.standard_normal(40)
    z = rng.standard_normal(40)
    x = np.arange(5) * 0.001
    for k in (1, 2, 3):
        rows = np.stack([a + 0.2 * abs(j - k) * z for j in range(5)])
        out = offset_search.bootstrap_offsets(a, rows, x, 30, 4, np.random.default_rng(0))
        assert np.all(np.abs(out - x[k]) < 0.001), (k, out)


def test_the_replicates_do_not_depend_on_the_speeds_scale():
    rng = np.random.default_rng(3)
    a = rng.standard_normal(40)
    x = np.arange(5) * 0.001
    rows = np.stack([a + 0.3 * abs(j - 2.4) * rng.standard_normal(40) for j in range(5)])
    out = offset_search.bootstrap_offsets(a, rows, x, 30, 4, np.random.default_rng(0))
    small = offset_search.bootstrap_offsets(1e-3 * a, 1e-3 * rows, x, 30, 4, np.random.default_rng(0))
    assert np.allclose(small, out, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------------------------------
# The offset search in blocks: bounded memory, bit-identical to the search over all offsets at once
# (figures behind the block size: benchmarks/bench_bounded.py).


def _offset_streams(seconds=30.0, offset=0.0123):
    rng = np.random.default_rng(8)
    R0 = so3.random_rotations(rng, ())

    def attitude(t):
        return so3.matrix_from_rotation_vector(np.stack([np.sin(0.7 * t) + 0.2 * np.sin(3.1 * t),
                                                         np.sin(0.45 * t + 1.0),
                                     np.cos(0.3 * t) + 0.1 * np.sin(4.1 * t)], axis=-1))

    tc, tg = np.arange(0.0, seconds, 0.05), np.arange(-1.0, seconds + 1.0, 0.005)
    Q = attitude(np.concatenate([tg[:1] - 0.005, tg, tg[-1:] + 0.005]) - offset) @ R0
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-2], -1, -2) @ Q[2:]) / 0.01
    return OrientationStream(tc, attitude(tc), "camera"), integrate_gyro(GyroStream(tg, omega, "gyro"))


def _correlations_before(cam, sensor, t, offsets):
    """The correlation of before (all offsets in one array)."""
    Qs = sensor.at((t[None, :] + offsets[:, None]).ravel()).reshape(len(offsets), len(t), 3, 3)
    sen = offset_search.speed(Qs, t)
    a = cam - cam.mean()
    b = sen - sen.mean(axis=1, keepdims=True)
    return (b @ a) / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))


@pytest.fixture(scope="module")
def offset_problem():
    camera, sensor = _offset_streams()
    keep = (camera.t >= sensor.t[0] + 1.0) & (camera.t <= sensor.t[-1] - 1.0)
    t = camera.t[keep]
    return camera, sensor, t, offset_search.speed(camera.R[keep], t)


def test_offset_blocks_are_bit_identical(offset_problem):
    _, sensor, t, cam = offset_problem
    offsets = np.arange(-0.3, 0.3 + 1e-12, 0.01)  # 61 offsets
    one = offset_search.correlations(cam, sensor, t, offsets, block_samples=len(offsets) * len(t))
    np.testing.assert_array_equal(one, _correlations_before(cam, sensor, t, offsets))  # one block: as before
    blocked = [offset_search.correlations(cam, sensor, t, offsets, block_samples=per * len(t))
               for per in (1, 4, 7, 60)]
    for other in blocked[1:]:
        np.testing.assert_array_equal(other, blocked[0])  # the block size does not touch an offset's arithmetic
    np.testing.assert_allclose(blocked[0], one, rtol=0, atol=1e-14)  # sum(b * a) vs BLAS's b @ a: a few ulp


def test_offset_search_in_small_blocks_finds_the_same_offset(offset_problem, monkeypatch):
    camera, sensor, _, _ = offset_problem
    default = association.estimate_time_offset(camera, sensor)
    assert abs(default[0] - 0.0123) < 0.5e-3
    monkeypatch.setattr(offset_search, "OFFSET_BLOCK_SAMPLES", 3000)  # about 5 offsets per block
    blocked = association.estimate_time_offset(camera, sensor)
    assert blocked[0] == default[0] and abs(blocked[1] - default[1]) < 1e-14


def test_offset_search_memory_does_not_grow_with_max_offset(offset_problem, monkeypatch):
    camera, sensor, _, _ = offset_problem
    monkeypatch.setattr(offset_search, "OFFSET_BLOCK_SAMPLES", 2 ** 14)
    peaks = []
    for max_offset in (0.3, 3.0):  # 61 and 601 candidate offsets
        tracemalloc.start()
        try:
            association.estimate_time_offset(camera, sensor, max_offset=max_offset)
            peaks.append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
    # in one array, 601 offsets x ~480 camera times x ~150 bytes would take ~40 MB
    assert peaks[1] < 1.3 * peaks[0] + 0.5e6 and peaks[1] < 10e6, peaks


@pytest.mark.parametrize("name, value", [("max_offset", 0), ("max_offset", -0.1), ("max_offset", np.nan),
                                         ("max_offset", np.inf), ("max_offset", "0.2"), ("max_offset", True),
                                         ("resolution", 0.0), ("resolution", -1e-3), ("resolution", np.inf),
                                         ("resolution", np.nan), ("resolution", None)])
def test_offset_search_refuses_bad_arguments(offset_problem, name, value):
    camera, sensor, _, _ = offset_problem
    with pytest.raises(ValueError, match=name):
        association.estimate_time_offset(camera, sensor, **{name: value})


# --------------------------------------------------------------------------------------------------
# the search's bookkeeping (_search) on a designed coarse curve, its refinements recorded


def test_a_search_with_no_finite_correlation_has_no_information(monkeypatch):
    camera, sensor = turning_streams(n_cam=40)
    monkeypatch.setattr(offset_search, "correlations", lambda cam, sensor, t, offsets: np.full(len(offsets), np.nan))
    out = offset_search._search(camera, sensor, 0.2, 0.5e-3, True)
    assert set(out) == {"t", "a", "grid", "offset", "corr", "second", "curve", "rows"}
    assert np.array_equal(out["t"], camera.t) and out["a"].shape == (39,) and np.allclose(out["a"], 0.0, atol=1e-6)
    assert out["grid"] == 0.0 and out["offset"] == 0.0 and out["rows"] is None
    assert math.isnan(out["corr"]) and len(out["second"]) == 2 and all(math.isnan(v) for v in out["second"])
    assert np.array_equal(out["curve"][0], np.arange(-0.2, 0.2 + 1e-12, 0.01)) and np.isnan(out["curve"][1]).all()


@pytest.mark.parametrize("name, value", [("max_offset", 0), ("max_offset", -0.1), ("resolution", 0.0),
                                         ("resolution", -1e-3)])
def test_the_search_refuses_offsets_and_resolutions_not_above_zero(name, value):
    camera, sensor = turning_streams(n_cam=40)
    args = dict(max_offset=0.2, resolution=0.5e-3) | {name: value}
    with pytest.raises(ValueError, match=rf"^{name} "):
        offset_search._search(camera, sensor, args["max_offset"], args["resolution"], False)


COARSE = np.arange(-0.2, 0.2 + 1e-12, 0.01)
TOP, EDGE, PEAK, RIVAL, LOW = 24, 29, 11, 36, 4  # coarse indices (offsets ~0.04, 0.09, -0.09, 0.16, -0.16)


def _designed_search(monkeypatch, keep_rows, refined_corr, refined_offset=None, peak_best=None):
    """``_search`` on a coarse curve with local maxima at TOP (0.5, the coarse maximum), EDGE (0.3,
    exactly PEAK_SEPARATION_S from TOP), PEAK (0.45), RIVAL (0.46), LOW (0.25, exactly
    RIVAL_REFINED_WITHIN below TOP); ``_refine`` a fake giving ``refined_corr[index]``; its
    calls."""
    c = np.zeros(len(COARSE))
    c[[TOP, EDGE, PEAK, RIVAL, LOW]] = 0.5, 0.3, 0.45, 0.46, 0.25
    monkeypatch.setattr(offset_search, "correlations", lambda cam, sensor, t, offsets: c.copy())
    monkeypatch.setattr(offset_search, "PEAK_SEPARATION_S", COARSE[EDGE] - COARSE[TOP])
    monkeypatch.setattr(offset_search, "RIVAL_REFINED_WITHIN", 0.25)
    index = {float(COARSE[i]): i for i in (TOP, PEAK, RIVAL)}
    calls = []

    def refine(a, sensor, t, best, max_offset, resolution, keep):
        calls.append((a, sensor, t, best, max_offset, resolution, keep))
        i = index[float(best)]
        fine = np.linspace(best - 0.01, best + 0.01, 5)
        off = best + 0.001 if refined_offset is None else refined_offset[i]
        return dict(best=best if peak_best is None or i != PEAK else peak_best, fine=fine,
                    x=np.append(fine, off), y=np.full(6, refined_corr[i]), grid=best + 0.0005, offset=off,
                    corr=refined_corr[i], rows=np.outer(fine, np.ones(39)) if keep else None, rows_x=fine)

    monkeypatch.setattr(offset_search, "_refine", refine)
    monkeypatch.setattr(offset_search, "_row_correlations",
                        lambda a, sensor, t, offsets, keep: (np.zeros(len(offsets)), np.outer(offsets, np.ones(39))))
    camera, sensor = turning_streams(n_cam=40)
    return offset_search._search(camera, sensor, 0.2, 0.5e-3, keep_rows), calls, sensor


@pytest.mark.parametrize("keep_rows", [True, False])
@pytest.mark.parametrize("top_corr, second", [(0.2, (COARSE[EDGE], 0.3)),  # a coarse rival, the peak's far maximum
                                              (0.35, (COARSE[TOP] + 0.001, 0.35))])  # the coarse maximum refined
def test_the_highest_refined_rival_is_the_peak_and_the_next_far_one_the_second(monkeypatch, keep_rows, top_corr,
                                                                                 second):
    out, calls, sensor = _designed_search(monkeypatch, keep_rows, {TOP: top_corr, PEAK: 0.9, RIVAL: 0.1})
    # refined: the coarse maximum (with the rows when asked), then the rivals farther than
    # PEAK_SEPARATION_S and less than RIVAL_REFINED_WITHIN below it, highest first (never EDGE,
    # LOW); a rival refined highest is refined again with its rows when they are asked
    expect = [(COARSE[TOP], keep_rows), (COARSE[RIVAL], False), (COARSE[PEAK], False)]
    expect += [(COARSE[PEAK], True)] if keep_rows else []
    assert [(call[3], call[6]) for call in calls] == expect
    for a, s, t, _, max_offset, resolution, keep in calls:
        assert a is out["a"] and s is sensor and t is out["t"] and max_offset == 0.2 and resolution == 0.5e-3
        assert type(keep) is bool and type(max_offset) is float and type(resolution) is float
    assert out["offset"] == COARSE[PEAK] + 0.001 and out["corr"] == 0.9 and out["grid"] == COARSE[PEAK] + 0.0005
    assert out["second"] == second
    assert set(out) == {"t", "a", "grid", "offset", "corr", "second", "curve"} | ({"boot_x", "rows"} if keep_rows
                                                                               else set())
    if keep_rows:  # the coarse offsets within BOOTSTRAP_SPAN_S of the peak's outside its fine ones, and those
        fine = np.linspace(COARSE[PEAK] - 0.01, COARSE[PEAK] + 0.01, 5)
        near = COARSE[[i for i in range(len(COARSE)) if 1 <= i <= 21 and i not in (10, 11, 12)]]
        np.testing.assert_array_equal(out["boot_x"], np.sort(np.concatenate([near, fine])))
        np.testing.assert_array_equal(out["rows"], np.outer(out["boot_x"], np.ones(39)))


def test_a_refined_rival_exactly_the_separation_away_is_not_the_second(monkeypatch):
    sep = COARSE[EDGE] - COARSE[TOP]
    out, _, _ = _designed_search(monkeypatch, False, {TOP: 0.35, PEAK: 0.9, RIVAL: 0.34},
                                 refined_offset={TOP: sep, PEAK: 0.0, RIVAL: -0.125})
    assert out["second"] == (-0.125, 0.34)


def test_a_coarse_maximum_exactly_the_separation_from_the_peak_is_not_the_second(monkeypatch):
    out, _, _ = _designed_search(monkeypatch, False, {TOP: 0.2, PEAK: 0.9, RIVAL: 0.1}, peak_best=COARSE[TOP])
    assert out["second"] == (COARSE[LOW], 0.25)  # EDGE is exactly PEAK_SEPARATION_S from the peak's coarse offset


def _parabola_rows(monkeypatch, top):
    """``_row_correlations`` faked: the curve ``-(x - top)^2``, rows tagged by their offset; its
    calls."""
    calls = []

    def rows(a, sensor, t, offsets, keep):
        calls.append((np.array(offsets), keep))
        return -(offsets - top) ** 2, np.outer(offsets, np.ones(3)) if keep else np.empty((0, 0))

    monkeypatch.setattr(offset_search, "_row_correlations", rows)
    return calls


@pytest.mark.parametrize("keep_rows", [True, False])
@pytest.mark.parametrize("best, top", [(0.0, 0.00123), (-0.2, -0.19988), (0.2, 0.19991)])
def test_the_refinement_searches_one_coarse_step_then_one_fine_step_around_the_peak(monkeypatch, keep_rows, best,
                                                                                     top):
    calls = _parabola_rows(monkeypatch, top)
    r = offset_search._refine(np.zeros(3), None, None, best, 0.2, 0.5e-3, keep_rows)
    fine, sub = calls[0][0], calls[1][0]
    # fine: every resolution within 10 ms of the coarse offset (both ends included), inside
    # +-max_offset
    inside = np.arange(best - 0.01, best + 0.01 + 1e-12, 0.5e-3)
    inside = inside[np.abs(inside) <= 0.2 + 1e-12]
    assert np.array_equal(r["fine"], fine) and len(fine) == len(inside) and np.allclose(fine, inside, atol=1e-12)
    assert fine.min() >= -0.2 and fine.max() <= 0.2
    # the sub-grid: resolution / SUBGRID_STEPS apart within one fine step of the fine maximum, not
    # on the fine grid
    assert r["grid"] == fine[np.argmax(-(fine - top) ** 2)] and abs(r["grid"] - top) <= 0.25e-3
    steps = [k for k in range(-9, 10) if k and abs(r["grid"] + k * 0.5e-4) <= 0.2 + 1e-12]
    assert len(sub) == len(steps) and np.allclose(sub, r["grid"] + np.array(steps) * 0.5e-4, rtol=0, atol=1e-12)
    assert sub.min() >= -0.2 and sub.max() <= 0.2
    # the parabola's vertex through the three highest (the curve is a parabola: its top), then its
    # correlation
    assert r["offset"] == pytest.approx(top, abs=1e-12) and calls[2][1] is False and len(calls) == 3
    assert calls[2][0].tolist() == [r["offset"]] and r["corr"] == -(r["offset"] - top) ** 2
    x = np.sort(np.concatenate([fine, sub]))
    assert np.array_equal(r["x"], np.append(x, r["offset"])) and np.array_equal(r["rows_x"], x)
    assert np.array_equal(r["y"], np.append(-(x - top) ** 2, r["corr"])) and r["best"] == best
    assert r["rows"] is None if not keep_rows else np.array_equal(r["rows"], np.outer(x, np.ones(3)))
    assert [k for _, k in calls[:2]] == [keep_rows, keep_rows]


@pytest.mark.parametrize("keep_rows", [True, False])
def test_the_rows_are_kept_only_when_asked(offset_problem, keep_rows):
    _, sensor, t, cam = offset_problem
    offsets = np.array([-0.01, 0.0, 0.0123, 0.02])
    a = cam - cam.mean()
    c, rows = offset_search._row_correlations(a, sensor, t, offsets, keep_rows)
    np.testing.assert_allclose(c, offset_search.correlations(cam, sensor, t, offsets), rtol=0, atol=1e-14)
    assert rows.shape == ((4, len(a)) if keep_rows else (0, 0))


def test_vertex_keeps_a_maximum_at_the_first_offset_and_each_curve_apart():
    x = np.array([0.0, 1.0, 2.0, 4.0, 5.0])
    # the first offset highest: not refined (the neighbours are not wrapped around from the end)
    assert offset_search.vertex(x, np.array([1.0, 0.9, 0.0, 0.0, -10.0])) == 0.0
    # a curve with no finite value is NaN beside finite ones
    out = offset_search.vertex(x, np.stack([np.full(5, np.nan), -(x - 2.3) ** 2]))
    assert math.isnan(out[0]) and out[1] == pytest.approx(2.3, abs=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a straight top (no parabola's vertex) is silent
        assert offset_search.vertex(x, x) == 5.0 and offset_search.vertex(x, 3 - x) == 0.0


def test_the_overlap_starts_max_offset_after_the_sensor():
    cam, sen = turning_streams(n_cam=40, sensor_span=(-0.1, 3.0))
    t, _ = offset_search.overlap(cam, sen, 0.2)
    assert t[0] == pytest.approx(0.1) and t[0] >= sen.t[0] + 0.2 - 1e-12 and t[-1] == cam.t[-1]


def test_the_correlations_hold_at_most_block_samples_at_once(offset_problem):
    _, sensor, t, cam = offset_problem
    offsets = np.arange(-0.3, 0.3 + 1e-12, 0.01)  # 61 offsets x ~480 times: one default block
    peaks = []
    for block in (None, 2 * len(t)):
        tracemalloc.start()
        try:
            offset_search.correlations(cam, sensor, t, offsets, block_samples=block)
            peaks.append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
    assert peaks[1] < 0.2 * peaks[0], peaks
