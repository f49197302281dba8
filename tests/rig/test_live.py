"""The live front end and the command line's online path: the batch options honoured, short
recordings handled, the usual input mistakes named online, ready at the pair's formation time, and
the online results in the report."""
import json
import math
import re

import jsonschema
import numpy as np
import pandas as pd
import pytest

from replication.cli import main
from replication.core import so3
from replication.rig.live import OFFSET_RESOLUTION, LiveRig, replay
from replication.rig.online import OnlineCalibrator
from replication.rig.report import RADIUS_COVERS  # noqa: E402
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import rig_streams

SCHEMA = json.loads((__import__("pathlib").Path(__file__).resolve().parents[2] / "docs"
                     / "calibration_report.schema.json").read_text())


@pytest.fixture(scope="module")
def rig():
    return rig_streams(90.0, rng=np.random.default_rng(7), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)


def _summary(camera, sensor, R0=None, **kw):
    rows = replay(camera, sensor, OnlineCalibrator(), reference=R0, **kw)
    return rows, rows.attrs["summary"]


def _fails(summary):
    return {r["check"]: r["message"] for r in summary["verdict"]["reasons"] if r["level"] == "fail"}


@pytest.mark.parametrize("kwargs, message", [
    ({"interval": 0}, "interval must be > 0"), ({"max_offset": -1}, "max_offset must be > 0"),
    ({"offset": float("nan")}, "offset must be a finite number"), ({"stride": 0}, "stride must be >= 1"),
    ({"offset_window": 1.2}, "offset_window must exceed 2 max_offset"), ({"correct_offset": "no"}, "correct_offset"),
    ({"on_pair": 3}, "on_pair must be callable"), ({"diagnose": 1}, "diagnose must be True or False"),
])
def test_live_rig_parameters_are_validated_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        LiveRig(OnlineCalibrator(), **kwargs)
    with pytest.raises(ValueError, match="calibrator must be an OnlineCalibrator"):
        LiveRig(object())


def test_a_gyro_and_an_orientation_sensor_do_not_mix(rig):
    live = LiveRig(OnlineCalibrator(), offset=0.0)
    live.add_gyro(0.0, np.zeros(3))
    with pytest.raises(ValueError, match="this rig's sensor gives gyro samples"):
        live.add_orientation(0.1, np.eye(3))


def test_clean_rig_is_ready_at_the_pairs_formation_time(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera, gyro, R0)
    first = rows.index[rows["ready"]][0]
    assert summary["ready"] and summary["ready_at_s"] == pytest.approx(rows.loc[first, "t_seen"] - camera.t[0])
    assert summary["ready_at_s"] >= 20.0 > summary["ready_pair_end_s"]  # the first pairs wait for the offset window
    assert summary["verdict"]["level"] == "ok" and summary["events"] == [] and rows["error_deg"].iloc[-1] < 0.05
    assert rows[["qw", "radius_deg", "error_deg"]].iloc[:9].isna().all().all()  # no estimate yet: empty, not identity
    assert rows[["qw", "radius_deg", "error_deg"]].iloc[9:].notna().all().all()


def test_the_summary_holds_python_numbers_not_numpy_scalars(rig):
    """What the summary prints and the report writes: every number a Python one (a numpy scalar
    printed as ``np.float64(57.0)`` in the summary)."""
    R0, camera, gyro, _ = rig
    _, summary = _summary(camera, gyro, R0)

    def walk(v, where):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(x, f"{where}.{k}")
        elif isinstance(v, (list, tuple)):
            for i, x in enumerate(v):
                walk(x, f"{where}[{i}]")
        else:
            assert not isinstance(v, np.generic), (where, type(v))

    walk(summary, "summary")
    assert type(summary["effective_pairs"]) is float and "np." not in repr(summary)


def test_a_short_recording_is_paired_at_its_end(rig):
    """15 s of both streams, shorter than the 20 s offset window: the offset is estimated when the
    streams end."""
    R0, camera, gyro, _ = rig
    keep = gyro.t < 16.0
    rows, summary = _summary(camera.between(0.0, 15.0), GyroStream(gyro.t[keep], gyro.omega[keep], "gyro"), R0)
    assert 12 <= len(rows) <= 15 and summary["clock_offset_s"] == pytest.approx(0.0, abs=1e-3)
    assert summary["note"] is None and rows["t_seen"].min() >= 15.0  # formed when the streams ended


def test_a_too_short_recording_says_why_and_forms_no_pair(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera.between(0.0, 0.3), gyro, R0)
    assert len(rows) == 0 and not summary["ready"] and "no clock offset" in summary["note"]


def test_the_max_offset_and_keep_clock_options_are_honoured(rig):
    R0, camera, gyro, _ = rig
    late = GyroStream(gyro.t + 3.0, gyro.omega, "gyro")  # the sensor clock 3 s ahead
    rows, summary = _summary(camera, late, R0, max_offset=4.0)
    assert summary["clock_offset_s"] == pytest.approx(3.0, abs=1e-3) and summary["ready"]
    rows, summary = _summary(camera, late, R0, max_offset=4.0, correct_offset=False)
    assert summary["clock_offset_s"] == pytest.approx(3.0, abs=1e-3) and not summary["ready"]
    assert "offset_left_ms" in {r["check"] for r in summary["verdict"]["reasons"]}
    rows, summary = _summary(camera, late, R0)  # the default search (0.2 s) cannot find it: said, never ready
    assert not rows["ready"].any() and "offset_at_bound" in _fails(summary)


def test_the_stride_is_honoured(rig):
    R0, camera, gyro, _ = rig
    every, _ = _summary(camera, gyro, R0, diagnose=False)
    second, summary = _summary(camera, gyro, R0, stride=2, diagnose=False)
    assert len(second) == pytest.approx(len(every) / 2, abs=1) and summary["pairs_formed"] >= len(every) - 1


@pytest.mark.parametrize("mistake, check, named", [
    ("camera inverted", "input_mistake", "camera_from_world"),
    ("gyro in deg/s", "input_mistake", "gyro rates in deg/s read as rad/s"),
    ("sensor inverted", "input_mistake", "sensor_from_world"),
    ("rig at rest", "motion_median_deg", "barely moves"),
])
def test_the_usual_mistakes_are_named_online_and_never_ready(rig, mistake, check, named):
    R0, camera, gyro, sensor = rig
    inv = lambda s: OrientationStream(s.t, np.swapaxes(s.world_from_body, -1, -2), s.source)  # noqa: E731
    rest = OrientationStream(camera.t, np.broadcast_to(np.eye(3), camera.R.shape), "camera")
    cases = {"camera inverted": (inv(camera), gyro),
             "gyro in deg/s": (camera, GyroStream(gyro.t, np.degrees(gyro.omega), "gyro")),
             "sensor inverted": (camera, inv(sensor)),
             "rig at rest": (rest, GyroStream(gyro.t, np.zeros_like(gyro.omega), "gyro"))}
    rows, summary = _summary(*cases[mistake], R0)
    assert not rows["ready"].any() and summary["verdict"]["level"] == "fail"
    assert named in _fails(summary)[check]


def test_cli_online_writes_its_results_into_the_report_and_figure(tmp_path, rig, capsys):
    R0, camera, gyro, _ = rig
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(camera.R)
    np.savetxt(cam_file, np.column_stack([camera.t + 1e3, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]]),
               fmt="%.9f")
    late = gyro.t + 1e3 + 2.0  # a 2 s clock offset: only found with --max-offset
    np.savetxt(imu_file, np.column_stack([np.round(late * 1e9), gyro.omega, np.zeros((len(gyro.t), 3))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    out, track, fig = tmp_path / "r.json", tmp_path / "track.csv", tmp_path / "fig.png"
    code = main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro",
                 "--max-offset", "3", "--online", "--track", str(track), "--out", str(out), "--plot", str(fig),
                 "--bootstrap", "20", "--quiet"])
    text = capsys.readouterr().out
    assert code == 0 and "events: none" in text and "alarms at []" not in text
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    online = report["online"]
    assert online["ready"] and online["clock_offset_s"] == pytest.approx(2.0, abs=1e-3)
    assert online["ready_at_s"] == pytest.approx(float(text.split("after the camera's")[0].split(",")[-1].split()[0]),
                                                 abs=0.05)
    assert "own noise only" in online["radius_covers"] and online["verdict"]["level"] == "ok"
    rows = pd.read_csv(track)
    assert rows["qw"].iloc[:9].isna().all() and rows["ready"].iloc[-1] and fig.stat().st_size > 10_000


def test_cli_online_on_a_short_recording_writes_the_report(tmp_path, rig):
    R0, camera, gyro, _ = rig
    cam = camera.between(0.0, 15.0)
    cam_file, imu_file, out = tmp_path / "cam.txt", tmp_path / "imu.csv", tmp_path / "r.json"
    q = so3.quaternion_from_matrix(cam.R)
    np.savetxt(cam_file, np.column_stack([cam.t + 1e3, np.zeros((len(cam.t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    keep = gyro.t < 16.0
    np.savetxt(imu_file, np.column_stack([np.round((gyro.t[keep] + 1e3) * 1e9), gyro.omega[keep],
                                          np.zeros((keep.sum(), 3))]), fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    code = main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro",
                 "--online", "--out", str(out), "--bootstrap", "0", "--quiet", "--accept"])
    assert code == 0
    online = json.loads(out.read_text())["online"]
    assert 12 <= online["pairs"] <= 15 and online["clock_offset_s"] == pytest.approx(0.0, abs=1e-3)  # 14; -0.1 ms

# --------------------------------------------------------------------------------------------------
# The live front end (:class:`replication.rig.live.LiveRig`) on an orientation sensor, exactly:
# which poses pair (``interval`` reached exactly, no shared pose, the stride), the sensor slerped to
# the camera time plus the clock offset (``B = R0^T A R0`` to rounding for a constant-rate motion),
# gaps at ``GAP_FACTOR`` typical steps, the buffer and the early window kept, the refusals, and the
# evidence it adds to the verdict. Mutation testing (scripts/mutation) found these unguarded by the
# fast tests.


R0 = so3.matrix_from_rotation_vector(np.array([0.3, -0.5, 0.8]))
W = np.array([0.2, 0.9, -0.4])  # rad/s, a constant rate about a fixed axis: slerp between samples is exact
DT_CAM, DT_SEN = 1 / 32, 1 / 128  # binary fractions: time stamps and differences are exact


def _C(t):
    return so3.matrix_from_rotation_vector(W * t)  # world_from_camera


def _feed(rig, t_end, offset=0.0, sensor_skip=()):
    """Camera poses every DT_CAM and sensor orientations every DT_SEN (stamped t + offset) up to
    t_end, in time order; sensor samples whose index is in ``sensor_skip`` are left out (a gap)."""
    events = [(k * DT_CAM, 1, k) for k in range(int(round(t_end / DT_CAM)) + 1)]
    events += [(k * DT_SEN + offset, 0, k) for k in range(-128, int(round((t_end + 1) / DT_SEN)) + 1)
               if k not in sensor_skip]
    for t, kind, _k in sorted(events):
        if kind:
            rig.add_camera(t, _C(t))
        else:
            rig.add_orientation(t, _C(t - offset) @ R0)


def _rig(**kw):
    pairs = []
    kw.setdefault("offset", 0.0)
    rig = LiveRig(OnlineCalibrator(), interval=kw.pop("interval", 0.25), diagnose=False,
                  on_pair=lambda t, A, B: pairs.append((t, A, B)), **kw)
    return rig, pairs


@pytest.mark.parametrize("offset", [0.0, 0.0123, -0.04])
def test_pairs_are_exact_at_the_offset_and_share_no_pose(offset):
    rig, pairs = _rig(offset=offset)
    _feed(rig, 3.0, offset=offset)
    rig.finish()
    # the interval (8 camera steps) is reached exactly: pairs end at poses 8, 17, 26, ...
    assert [t for t, _, _ in pairs] == [k * 9 * DT_CAM - DT_CAM for k in range(1, len(pairs) + 1)]
    assert len(pairs) == 10 and rig.pairs_formed == 10 and rig.pairs_dropped == 0
    for t, A, B in pairs:
        assert np.allclose(A, _C(t).T @ _C(t - 8 * DT_CAM), atol=1e-12)
        assert np.allclose(B, R0.T @ A @ R0, atol=1e-9)
    assert len(rig.events) == 10  # every pair reaches the calibrator (which counts these equal motions as repeats)


def test_the_stride_uses_every_other_pair_formed():
    rig, pairs = _rig(stride=2)
    _feed(rig, 3.0)
    assert rig.pairs_formed == 10 and len(pairs) == 5
    assert [t for t, _, _ in pairs] == [(k * 18 + 8) * DT_CAM for k in range(5)]
    assert rig.evidence()["pairs_before_gaps"] == 5


def test_a_pair_across_a_sensor_gap_is_dropped_at_five_typical_steps():
    # pair 2 runs over poses 9..17 (t 0.28..0.53); leave sensor samples out in the middle of it
    rig, pairs = _rig()
    _feed(rig, 1.2, sensor_skip=set(range(50, 55)))  # a 6-step hole: beyond 5 typical steps
    assert rig.pairs_dropped == 1 and [round(t / DT_CAM) for t, _, _ in pairs] == [8, 26, 35]
    assert rig.evidence()["pairs_dropped_at_gaps"] == 1
    rig, pairs = _rig()
    _feed(rig, 1.2, sensor_skip=set(range(50, 54)))  # a 5-step hole: not a gap
    assert rig.pairs_dropped == 0 and len(pairs) == 4


def test_a_gap_at_a_pair_end_drops_it_too():
    rig, pairs = _rig()
    _feed(rig, 1.2, sensor_skip=set(range(66, 71)))  # the hole holds the end of pair 2 (t = 17/32 = 68/128)
    assert rig.pairs_dropped == 1 and [round(t / DT_CAM) for t, _, _ in pairs] == [8, 26, 35]


def _integrated(samples, t0, t1):
    """The sensor's rotation over ``[t0, t1]`` as the pair formed there sees it (``B^T``): gyro
    ``samples`` ``(t, omega)``, camera poses at ``t0`` and ``t1`` (no bias estimate: the rates as
    given)."""
    rig, pairs = _rig(interval=t1 - t0, gyro_bias=False)
    for t, w in samples:
        rig.add_gyro(t, w)
    rig.add_camera(t0, R0)
    rig.add_camera(t1, R0)
    assert len(pairs) == 1
    return pairs[0][2].T  # B = Q(t1)^T Q(t0)


def test_the_typical_sensor_step_is_a_running_average():
    rig, _ = _rig()
    assert rig._gyro_dt is None
    rig.add_orientation(0.0, R0)
    assert rig._gyro_dt is None
    rig.add_orientation(0.5, R0)
    assert rig._gyro_dt == 0.5
    rig.add_orientation(0.75, R0)
    assert rig._gyro_dt == pytest.approx(0.99 * 0.5 + 0.01 * 0.25, abs=1e-15)


def test_gyro_samples_are_integrated_by_the_trapezoidal_rule_and_refused_when_bad():
    rig, _ = _rig()
    w0, w1 = np.array([0.1, 0.2, 0.3]), np.array([0.5, -0.1, 0.1])
    rig.add_gyro(1.0, w0)
    rig.add_gyro(1.5, w1)
    step = _integrated([(0.5, w0), (1.0, w0), (1.5, w1)], 1.0, 1.5)
    assert np.allclose(step, so3.matrix_from_rotation_vector(0.5 * (w0 + w1) * 0.5), rtol=0, atol=1e-15)
    assert rig.evidence()["gyro_rate_hz"] == 2.0
    rig.add_gyro(1.75, [0, 0, 0])
    assert 1 / rig.evidence()["gyro_rate_hz"] == pytest.approx(0.99 * 0.5 + 0.01 * 0.25, abs=1e-15)
    assert rig.evidence()["gyro_rate_hz"] == pytest.approx(1 / (0.99 * 0.5 + 0.01 * 0.25))
    for t in (1.75, 1.5):
        with pytest.raises(ValueError, match=rf"gyro time going backwards.*{t!r} after 1\.75"):
            rig.add_gyro(t, w0)
    for t, w in ((2.0, [0.0, 0.0]), (2.0, [0.0, math.nan, 0.0]), (math.inf, [0.0, 0.0, 0.0]), (2.0, [1j, 0.0, 0.0])):
        with pytest.raises(ValueError, match=r"a gyro sample is a finite time and 3 finite rates.*got t="):
            rig.add_gyro(t, w)  # a complex rate is refused, not cast to its real part
    # the refused samples left no step
    assert 1 / rig.evidence()["gyro_rate_hz"] == pytest.approx(0.99 * 0.5 + 0.01 * 0.25, abs=1e-15)
    rig.add_gyro(2.0, [[0.5, -0.1, 0.1]])  # 3 rates in any shape: a 1 x 3 row
    assert rig._last_gyro[1] == (0.5, -0.1, 0.1)
    assert 1 / rig.evidence()["gyro_rate_hz"] == pytest.approx(0.99 * (0.99 * 0.5 + 0.01 * 0.25) + 0.01 * 0.25,
                                                                abs=1e-15)


def test_orientation_samples_are_refused_when_not_later_or_not_one_rotation():
    rig, _ = _rig()
    rig.add_orientation(1.0, R0)
    for t in (1.0, 0.5):
        with pytest.raises(ValueError, match=rf"sensor time going backwards.*{t!r} after 1\.0"):
            rig.add_orientation(t, R0)
    with pytest.raises(ValueError, match=r"a sensor pose is a finite time and one 3x3 rotation.*t=2\.0, shape "
                                         r"\(2, 3, 3\)"):
        rig.add_orientation(2.0, np.stack([R0, R0]))
    with pytest.raises(ValueError, match=r"a sensor pose is a finite time and one 3x3 rotation.*t=nan"):
        rig.add_orientation(math.nan, R0)
    with pytest.raises(ValueError, match="world_from_sensor is not a rotation matrix"):
        rig.add_orientation(2.0, 2 * R0)
    with pytest.raises(ValueError, match=r"sensor gives orientation samples.*got a gyro sample"):
        rig.add_gyro(3.0, np.zeros(3))
    rig2, _ = _rig()
    rig2.add_gyro(0.0, np.zeros(3))
    with pytest.raises(ValueError, match=r"sensor gives gyro samples.*orientation sample"):
        rig2.add_orientation(1.0, R0)


def test_the_buffer_keeps_the_last_interval_plus_the_offset_search_plus_a_second():
    rig, _ = _rig(interval=0.25, max_offset=0.125)
    keep = 0.25 + 2 * 0.125 + 1.0
    for k in range(800):
        rig.add_orientation(k * DT_SEN, R0)
    t = 799 * DT_SEN
    times = [g[0] for g in rig._gyro]
    assert times[0] == t - keep and times[-1] == t  # a sample exactly keep seconds old stays
    rig2, _ = _rig(offset=None, offset_window=4.0, max_offset=0.125, interval=0.25)
    for k in range(800):
        rig2.add_orientation(k * DT_SEN, R0)
    assert [g[0] for g in rig2._gyro][0] == max(0.0, t - keep - 4.0)  # unknown offset: the window is held too


def test_the_early_window_keeps_samples_up_to_offset_window_inclusive():
    rig, _ = _rig(offset_window=1.0)
    for k in range(200):
        rig.add_orientation(k * DT_SEN, R0)
        rig.add_camera(k * DT_SEN + 1 / 256, _C(k * DT_SEN))
    assert [s[0] for s in rig._early_sensor] == [k * DT_SEN for k in range(129)]
    assert rig._early_camera[0][0] == 1 / 256 and rig._early_camera[-1][0] == 128 * DT_SEN + 1 / 256
    cam, sen = rig._streams()
    assert np.array_equal(cam.t, [c[0] for c in rig._early_camera]) and cam.source == "camera (live)"
    assert np.array_equal(sen.t, [s[0] for s in rig._early_sensor]) and sen.source == "sensor (live)"
    assert np.allclose(sen.world_from_body, R0) and type(sen).__name__ == "OrientationStream"
    rig2, _ = _rig(offset_window=1.0)
    for k in range(3):
        rig2.add_gyro(k * 0.5, np.array([0.0, 0.0, k]))
        rig2.add_camera(k * 0.5, np.eye(3))
    cam, sen = rig2._streams()
    assert type(sen).__name__ == "GyroStream" and sen.source == "gyro (live)"
    assert np.array_equal(sen.omega, [[0, 0, 0], [0, 0, 1], [0, 0, 2]])


def test_used_offset_and_the_evidence():
    assert _rig(offset=None)[0].used_offset is None
    assert _rig(offset=0.25)[0].used_offset == 0.25
    assert _rig(offset=0.25, correct_offset=False)[0].used_offset == 0.25  # a given offset is always used
    rig, _ = _rig(offset=None, correct_offset=False)
    rig.offset = 0.5
    assert rig.used_offset == 0.0
    assert rig.evidence() == {"interval_s": 0.25, "pairs_dropped_at_gaps": 0, "pairs_before_gaps": 1,
                               "offset_s": 0.5, "offset_correlation": None, "max_offset_s": 0.2,
                               "offset_resolution_s": OFFSET_RESOLUTION, "offset_applied": False}
    rig.correct_offset = True
    assert rig.used_offset == 0.5 and rig.evidence()["offset_applied"] is True
    given, _ = _rig(offset=0.5)
    assert given.evidence() == {"interval_s": 0.25, "pairs_dropped_at_gaps": 0, "pairs_before_gaps": 1}
    gyro, _ = _rig()
    gyro.add_gyro(0.0, np.zeros(3))
    gyro.add_gyro(0.01, np.zeros(3))
    assert gyro.evidence()["gyro_rate_hz"] == pytest.approx(100.0)
    ori, _ = _rig()
    ori.add_orientation(0.0, R0)
    ori.add_orientation(0.01, R0)
    assert "gyro_rate_hz" not in ori.evidence()


def test_the_evidence_is_a_read_only_copy_of_what_the_rig_measured():
    rig, pairs = _rig(offset=None, offset_window=2.0, max_offset=0.1)
    _feed(rig, 3.0, offset=0.0123)
    rig.finish()
    assert rig.offset is not None and len(pairs) > 0
    before = (rig.summary(), rig.calibrator.evidence(), rig.pairs_formed, rig.pairs_dropped)
    first = rig.evidence()
    first["pairs_before_gaps"] = -1  # a copy: changing it changes nothing in the rig
    for _ in range(3):
        assert rig.evidence() == {**first, "pairs_before_gaps": max(1, -(-rig.pairs_formed // rig.stride))}
    assert (rig.summary(), rig.calibrator.evidence(), rig.pairs_formed, rig.pairs_dropped) == before
    assert rig.evidence()["offset_s"] == rig.offset and rig.evidence()["offset_correlation"] == rig.offset_correlation


@pytest.mark.parametrize("t0", [0.0, 100.0])
def test_the_offset_is_estimated_once_both_streams_span_the_window(t0):
    rig, pairs = _rig(offset=None, offset_window=2.0, max_offset=0.1)
    motion = lambda t: so3.matrix_from_rotation_vector(np.array([math.sin(3 * t), math.cos(2 * t),
                                                                 0.5 * math.sin(5 * t)]))  # noqa: E731
    for k in range(int(2.0 / DT_SEN)):  # just short of the window on the sensor side
        rig.add_orientation(t0 + k * DT_SEN, motion(k * DT_SEN) @ R0)
        if k % 4 == 0:
            rig.add_camera(t0 + k * DT_SEN, motion(k * DT_SEN))
    assert rig.offset is None and pairs == []
    rig.add_camera(t0 + 2.0, motion(2.0))
    assert rig.offset is None
    rig.add_orientation(t0 + 2.0, motion(2.0) @ R0)
    assert rig.offset == pytest.approx(0.0, abs=2 * OFFSET_RESOLUTION) and rig.offset_correlation > 0.99
    assert len(pairs) > 0
    assert rig.evidence()["offset_correlation"] == rig.offset_correlation  # the verdict judges the estimate's own


def test_finish_estimates_the_offset_on_what_arrived_or_says_why_not():
    rig, pairs = _rig(offset=None, offset_window=30.0)
    _feed(rig, 0.1)
    assert rig.offset is None
    rig.finish()
    assert rig.offset is None and rig.offset_note.startswith(
        "no clock offset: the streams ended after 1.1 s of camera data, before the 30 s offset window (")
    rig.finish()  # idempotent
    assert pairs == []


def _motion(t):
    return so3.matrix_from_rotation_vector(np.array([math.sin(1.3 * t), math.cos(0.7 * t),
                                                     0.8 * math.sin(0.5 * t + 1.0)]))


def _streams(t_end=20.0, t0=100.0):
    tc = t0 + np.arange(0, t_end, DT_CAM)
    ts = t0 + np.arange(-1.0, t_end + 1.0, 1 / 64)
    cam = OrientationStream(tc, np.array([_motion(t - t0) for t in tc]), "cam")
    sen = OrientationStream(ts, np.array([_motion(t - t0) @ R0 for t in ts]), "sen")
    return cam, sen


def test_replay_rows_and_summary_of_a_clean_rig():
    cam, sen = _streams()
    cal = OnlineCalibrator(target_deg=2.0)
    out = replay(cam, sen, cal, interval=0.25, offset=0.0, reference=R0)
    assert list(out.columns) == ["t", "t_seen", "n_pairs", "radius_deg", "ready", "alarm", "event", "determined",
                                 "checking", "qw", "qx", "qy", "qz", "error_deg"]
    assert len(out) > 60
    assert np.allclose(np.diff(out["t"]), 9 * DT_CAM)  # pairs share no pose
    flags = out[["ready", "alarm", "determined", "checking"]]
    assert not flags.isna().any().any() and all(out[c].dtype == bool for c in flags.columns)
    assert set(out["event"]) == {""} and out["n_pairs"].iloc[-1] == cal.n_pairs
    first = out.iloc[0]
    assert math.isnan(first["qw"]) and math.isnan(first["radius_deg"]) and math.isnan(first["error_deg"])
    last = out.iloc[-1]
    assert last["ready"] and last["determined"] and not last["checking"] and last["error_deg"] < 0.2
    assert 0 < last["radius_deg"] < 2.0  # known: the radius, under the target
    q = so3.quaternion_from_matrix(cal.R)
    assert [last["qw"], last["qx"], last["qy"], last["qz"]] == pytest.approx(list(q))
    assert out.attrs["offset_s"] == 0.0 and out.attrs["pairs_dropped"] == 0 and out.attrs["alarms"] == []
    s = out.attrs["summary"]
    ready_row = out[out["ready"]].iloc[0]
    assert s["ready"] is True and s["ready_at_s"] == ready_row["t_seen"] - 100.0
    assert s["ready_pair_end_s"] == ready_row["t"] - 100.0
    assert s["target_deg"] == 2.0 and s["pairs"] == cal.n_total and s["pairs_formed"] == len(out)
    assert (s["repeated_pairs"], s["pairs_dropped_outliers"], s["pairs_dropped_at_gaps"]) == (0, 0, 0)
    assert s["R0_camera_from_sensor"] == np.round(cal.R, 12).tolist()
    assert s["quaternion_wxyz"] == np.round(q, 12).tolist()
    assert s["radius_deg"] == cal.radius and s["radius_level"] == 0.95 and s["radius_covers"] == RADIUS_COVERS
    status = cal.status()
    assert s["excitation_deg"] == status["excitation_deg"] and s["effective_pairs"] == status["effective_pairs"]
    assert (s["clock_offset_s"], s["clock_offset_given"], s["clock_offset_correlation"]) == (0.0, True, None)
    assert s["clock_offset_applied"] is True and s["note"] is None and s["events"] == [] and s["not_ready"] == []
    assert s["verdict"]["level"] == "ok"
    assert isinstance(s["pairs"], int) and isinstance(s["ready"], bool)


def test_replay_with_an_estimated_offset_and_a_remount():
    cam, sen = _streams(36.0)
    cal = OnlineCalibrator(target_deg=2.0)
    R_re = so3.matrix_from_rotation_vector(np.radians(10.0) * np.array([0.0, 1.0, 0.0]))
    out = replay(cam, sen, cal, interval=0.25, offset=None, offset_window=8.0, max_offset=0.1, reference=R0,
                 remount=(118.0, R_re))
    s = out.attrs["summary"]
    assert abs(s["clock_offset_s"]) < 2e-3 and s["clock_offset_given"] is False and s["clock_offset_correlation"] > 0.9
    assert s["clock_offset_applied"] is (s["clock_offset_s"] != 0.0)
    assert out["t_seen"].iloc[0] >= 100.0 + 8.0 > out["t"].iloc[0]  # held until the offset window was full
    assert cal.alarms and out.attrs["alarms"] == cal.alarms and "remount" in out.attrs["events"]
    alarm_row = out[out["alarm"]].iloc[0]
    assert alarm_row["t"] > 118.0 and alarm_row["event"] == "remount"
    after = out[out["t"] > alarm_row["t"] + 5.0]
    # the reference follows the re-mount: the error is against R0 R_re after it
    assert after["error_deg"].dropna().iloc[-1] < 0.5
    ev = s["events"][0]
    assert ev["kind"] == "remount" and ev["pair_end_s"] > 18.0 and ev["t_s"] >= ev["pair_end_s"]
    assert ev["alarm_t_s"] <= ev["t_s"] and ev["angle_deg"] == pytest.approx(10.0, abs=1.0)
    row = out[out["event"] == "remount"].iloc[0]
    assert ev["t_s"] == row["t_seen"] - 100.0 and ev["pair_end_s"] == row["t"] - 100.0
    assert ev["alarm_t_s"] == out["t_seen"].iloc[cal.events[0].alarm_pair] - 100.0
    assert ev["threshold_deg"] < ev["angle_deg"] and ev["message"].startswith("the ")
    assert ev["pairs_dropped"] == cal.events[0].pairs_dropped


def test_summary_times_default_to_the_clock_itself():
    rig, _ = _rig(offset=0.0)
    rig.calibrator.target_deg = 2.0
    for k in range(int(12.0 / DT_CAM)):
        t = k * DT_CAM
        for j in range(4):
            ts = t + j * DT_SEN
            rig.add_orientation(ts - 1.0 if k == 0 and j == 0 else ts,
                                _motion(ts - 1.0 if k == 0 and j == 0 else ts) @ R0)
        rig.add_camera(t, _motion(t))
    assert rig.ready_at is not None
    s = rig.summary()
    assert s["ready_at_s"] == rig.ready_at[1] and s["ready_pair_end_s"] == rig.ready_at[0]
    assert rig.summary(t0=2.0)["ready_at_s"] == rig.ready_at[1] - 2.0


def test_the_offset_search_spans_the_rigs_max_offset():
    rig, _ = _rig(offset=None, offset_window=6.0, max_offset=0.3)
    d = 0.25  # beyond the default search of 0.2 s
    for k in range(int(7.0 / DT_SEN)):
        t = k * DT_SEN
        rig.add_orientation(t + d, _motion(t) @ R0)
        if k % 4 == 0:
            rig.add_camera(t, _motion(t))
    assert rig.offset == pytest.approx(d, abs=1e-3) and rig.offset_correlation > 0.99


def test_the_rigs_options_are_checked():
    cal = OnlineCalibrator()
    with pytest.raises(ValueError, match=r"calibrator must be an OnlineCalibrator.*got dict"):
        LiveRig({})
    for kw, msg in (({"interval": 0}, r"\binterval must be > 0\b.*got 0"),
                    ({"max_offset": 0}, r"max_offset must be > 0\b.*got 0"),
                    ({"offset": math.nan}, r"\boffset must be a finite number.*got nan"),
                    ({"offset": 0.0, "offset_window": 0}, r"offset_window must be > 0\b.*got 0"),
                    ({"stride": 0}, r"stride must be >= 1\b.*got 0"),
                    ({"stride": 1.5}, r"stride must be a finite integer.*got 1\.5"),
                    ({"correct_offset": 1}, r"correct_offset must be True or False.*got 1"),
                    ({"diagnose": "yes"}, r"diagnose must be True or False.*got 'yes'"),
                    ({"on_pair": 5}, r"on_pair must be callable or None.*got 5")):
        with pytest.raises(ValueError, match=msg):
            LiveRig(cal, **kw)
    # the offset window must exceed the search both ways plus a second, only when the offset is
    # estimated
    with pytest.raises(ValueError, match=r"offset_window must exceed 2 max_offset \+ 1 s = 1\.6 s.*got 1\.6"):
        LiveRig(cal, max_offset=0.3, offset_window=1.6)
    assert LiveRig(cal, max_offset=0.3, offset_window=1.6000001).offset_window == 1.6000001
    assert LiveRig(cal, offset=0.1, max_offset=0.3, offset_window=1.0).offset_window == 1.0
    rig = LiveRig(cal, max_offset=0.3, stride=np.int64(2), correct_offset=np.bool_(False))
    assert rig.offset_window == 20.0 and rig.stride == 2 and rig.correct_offset is False
    assert LiveRig(cal, max_offset=6.0).offset_window == 22.0  # max(20, 2 max_offset + 10)
    rig = LiveRig(cal)
    assert (rig.interval, rig.max_offset, rig.offset, rig.offset_given, rig.stride, rig.diagnose) == (
        1.0, 0.2, None, False, 1, True)
    assert rig.correct_offset is True and rig.on_pair is None and rig.GAP_FACTOR == 5.0


# ---------------------------------------------------------- pairing boundaries, gaps and the buffer
def _feed_orientations(rig, cam_times, sen_times, offset=0.0):
    """The constant-rate rig: camera poses at ``cam_times``, sensor orientations stamped ``t`` (true
    time ``t - offset``) at ``sen_times``, merged in time order (a sensor sample before a camera
    pose at the same time)."""
    events = sorted([(t, 1) for t in cam_times] + [(t, 0) for t in sen_times])
    for t, kind in events:
        if kind:
            rig.add_camera(t, _C(t))
        else:
            rig.add_orientation(t, _C(t - offset) @ R0)


def test_a_pair_forms_as_soon_as_the_sensor_reaches_its_last_pose_exactly():
    rig, pairs = _rig()
    _feed_orientations(rig, [k * DT_CAM for k in range(18)], [k * DT_SEN for k in range(-8, 69)])  # to 68/128 = 17/32
    assert [round(t / DT_CAM) for t, _, _ in pairs] == [8, 17]
    assert rig.events[-1][:2] == (17 * DT_CAM, 17 * DT_CAM)  # formed the moment the pose arrived


def test_poses_the_interval_apart_to_within_a_nanosecond_form_a_pair():
    rig, pairs = _rig()
    end = 0.25 - 1e-9
    _feed_orientations(rig, [0.0, end], [k * DT_SEN for k in range(-8, 48)])
    assert [t for t, _, _ in pairs] == [end]
    rig, pairs = _rig()
    _feed_orientations(rig, [0.0, 0.25 - 2e-9], [k * DT_SEN for k in range(-8, 48)])
    assert pairs == [] and rig.pairs_formed == 0


def test_a_stride_of_three_uses_the_first_of_every_three_pairs():
    rig, pairs = _rig(stride=3)
    _feed(rig, 3.0)
    assert rig.pairs_formed == 10 and [round(t / DT_CAM) for t, _, _ in pairs] == [8, 35, 62, 89]


def test_the_pairs_held_for_the_offset_are_all_formed_when_it_is_known_past_skips_and_drops():
    rig, pairs = _rig(offset=None, offset_window=2.0, max_offset=0.1, stride=2)
    hole = {k for k in range(int(2.0 / DT_SEN)) if 0.6 < k * DT_SEN < 0.66}  # a gap inside the second used pair
    for k in range(int(2.0 / DT_SEN) + 1):
        if k not in hole:
            rig.add_orientation(k * DT_SEN, _motion(k * DT_SEN) @ R0)
        if k % 4 == 0:
            rig.add_camera(k * DT_SEN, _motion(k * DT_SEN))
    assert rig.offset is not None  # estimated at t = 2 s, on the sensor sample that filled the window
    assert rig.pairs_formed == 7 and rig.pairs_dropped == 1 and len(pairs) == 3
    assert [e[1] for e in rig.events] == [2.0, 2.0, 2.0]


@pytest.mark.parametrize("hole, dropped", [
    (range(22, 28), [8]),       # sensor time 30..35/128: inside pair 1's span only (pair 2's starts at 44/128)
    (range(61, 67), [17]),      # sensor time 69..74/128: inside pair 2's span [44, 76]/128, short of its end
    (list(range(22, 28)) + list(range(61, 67)), [8, 17]),
])
def test_the_gap_check_spans_the_sensor_interval_at_the_offset(hole, dropped):
    offset = 1 / 16
    rig, pairs = _rig(offset=offset)
    _feed(rig, 1.2, offset=offset, sensor_skip=set(hole))
    assert rig.pairs_dropped == len(dropped)
    assert [round(t / DT_CAM) for t, _, _ in pairs] == [k for k in (8, 17, 26, 35) if k not in dropped]


def test_a_gap_starting_at_a_pairs_first_sensor_sample_drops_it():
    rig, pairs = _rig()
    _feed(rig, 1.2, sensor_skip=set(range(37, 43)))  # pair 2 starts at 9/32 = 36/128: the hole runs 36..43
    assert rig.pairs_dropped == 1 and [round(t / DT_CAM) for t, _, _ in pairs] == [8, 26, 35]


def test_a_gap_between_the_only_two_samples_inside_a_pair_drops_it():
    rig, pairs = _rig(interval=1 / 16, offset=1 / 256)  # spans fall half-way between sensor samples
    sen = [k * DT_SEN for k in range(-8, 40) if k not in range(2, 8)]  # hole: 1 -> 8 (7 steps)
    _feed_orientations(rig, [0.0, 1 / 16, 3 / 32, 5 / 32], sen)
    # pair 1 spans [0.5, 8.5]/128: its ends are bracketed by (0, 1) and (8, 9), only 1 and 8 lie
    # inside
    assert rig.pairs_dropped == 1 and [t for t, _, _ in pairs] == [5 / 32]


def test_a_sensor_slower_than_the_pairs_is_slerped_not_refused():
    rig, pairs = _rig(interval=0.25)
    _feed_orientations(rig, [k / 8 for k in range(17)], [k / 2 for k in range(-1, 6)])  # 2 Hz: 0 or 1 inside a span
    assert rig.pairs_dropped == 0 and len(pairs) == 5
    for _t, A, B in pairs:
        assert np.allclose(B, R0.T @ A @ R0, atol=1e-12)


def test_a_sensor_slower_than_the_buffer_still_brackets_a_pose_with_its_last_two_samples():
    # keep = interval + 2 max_offset + 1 = 2.2 s < the 3 s sensor step: the buffer holds the last
    # two samples
    rig, pairs = _rig(interval=1.0, max_offset=0.1)
    _feed_orientations(rig, [0.5, 1.5], [0.0, 3.0])
    assert [g[0] for g in rig._gyro] == [0.0, 3.0]
    assert len(pairs) == 1 and np.allclose(pairs[0][2], R0.T @ pairs[0][1] @ R0, atol=1e-12)
    # a pose that arrives after the sensor moved two samples on is no longer bracketed: dropped
    late, late_pairs = _rig(interval=1.0, max_offset=0.1)
    _feed_orientations(late, [], [0.0, 3.0, 6.0])
    assert [g[0] for g in late._gyro] == [3.0, 6.0]
    _feed_orientations(late, [0.5, 1.5], [])
    assert late_pairs == [] and late.pairs_dropped == 1


def test_a_pose_before_the_first_sensor_sample_is_dropped():
    rig, pairs = _rig()
    _feed_orientations(rig, [k * DT_CAM for k in range(27)], [k * DT_SEN for k in range(4, 120)])
    assert rig.pairs_dropped == 1 and [round(t / DT_CAM) for t, _, _ in pairs] == [17, 26]


def test_integrating_a_very_slow_rotation_stays_exact():
    w = np.array([3e-6, -4e-6, 5e-6])  # rad/s: steps of 7e-9 rad, under the second-order branch
    slow = _integrated([(k * 1e-3, w) for k in range(201)], 1e-3, 0.2)
    assert np.allclose(slow, so3.matrix_from_rotation_vector(w * 0.199), rtol=0, atol=1e-13)
    w = np.array([10.0, -4.0, 6.0])  # steps of 0.6 rad: Rodrigues, not the second-order branch
    fast = _integrated([(-0.05, w), (0.0, w), (0.05, w)], 0.0, 0.05)
    assert np.allclose(fast, so3.matrix_from_rotation_vector(w * 0.05), rtol=0, atol=1e-15)


# ------------------------------------------------------------------ camera input, finish
def test_camera_poses_are_refused_when_not_later_or_not_one_rotation():
    rig, _ = _rig()
    rig.add_camera(1.0, R0)
    for t in (1.0, 0.5):
        with pytest.raises(ValueError, match=rf"camera time going backwards.*{t!r} after 1\.0"):
            rig.add_camera(t, R0)
    with pytest.raises(ValueError, match=r"a camera pose is a finite time and one 3x3 rotation.*t=2\.0, shape "
                                         r"\(2, 3, 3\)"):
        rig.add_camera(2.0, np.stack([R0, R0]))
    with pytest.raises(ValueError, match=r"a camera pose is a finite time and one 3x3 rotation.*t=nan, shape "
                                         r"\(3, 3\)"):
        rig.add_camera(math.nan, R0)
    with pytest.raises(ValueError, match="world_from_camera is not a rotation matrix"):
        rig.add_camera(2.0, 2 * R0)
    assert [c[0] for c in rig._early_camera] == [1.0]


def test_finish_names_how_much_camera_data_came_before_the_window():
    rig, _ = _rig(offset=None, offset_window=30.0)
    _feed_orientations(rig, [100.0, 100.5, 101.0], [99.0 + k / 10 for k in range(24)])  # the sensor ends at 101.3
    rig.finish()
    assert rig.offset_note.startswith(
        "no clock offset: the streams ended after 1.3 s of camera data, before the 30 s offset window (")


def test_finish_keeps_a_given_offset():
    rig, pairs = _rig(offset=0.0123)
    _feed(rig, 1.0, offset=0.0123)
    _feed_orientations(rig, [3.0, 3.5], [])  # poses the sensor (up to 2 s) never reaches: still held at the end
    rig.finish()
    assert (rig.offset, rig.offset_correlation, rig.offset_note) == (0.0123, None, None)
    assert len(pairs) == 3


def test_after_finish_a_rig_without_an_offset_estimates_none():
    rig, pairs = _rig(offset=None, offset_window=2.0, max_offset=0.1)
    stamps = [k * DT_SEN for k in range(int(3.0 / DT_SEN))]
    _feed_orientations(rig, stamps[:64:4], stamps[:64], offset=0.0)
    rig.finish()
    assert rig.offset is None and rig.offset_note is not None
    _feed_orientations(rig, stamps[64::4], stamps[64:], offset=0.0)  # samples after the end spanning the window
    rig.finish()
    assert rig.offset is None and pairs == []


# ------------------------------------------------------------------ summary
def test_the_summary_reports_no_estimate_before_min_pairs_and_one_at_min_pairs():
    cal = OnlineCalibrator(min_pairs=6)
    rig = LiveRig(cal, interval=0.25, offset=0.0, diagnose=False)
    s = rig.summary()
    assert (s["ready"], s["ready_at_s"], s["ready_pair_end_s"], s["R0_camera_from_sensor"]) == (False, None, None, None)
    seen = []
    k = 0
    while cal.n_pairs < 6:
        for j in range(4):
            rig.add_orientation((4 * k + j) * DT_SEN, _motion((4 * k + j) * DT_SEN) @ R0)
        rig.add_camera(k * DT_CAM, _motion(k * DT_CAM))
        k += 1
        if rig.events and rig.events[-1][2].n_pairs not in seen:
            seen.append(rig.events[-1][2].n_pairs)
            s = rig.summary()
            assert (s["R0_camera_from_sensor"] is None) is (cal.n_pairs < 6)
            assert (s["quaternion_wxyz"] is None) is (cal.n_pairs < 6)
            assert s["ready_at_s"] is None and s["ready_pair_end_s"] is None
    assert seen == [1, 2, 3, 4, 5, 6]
    assert s["R0_camera_from_sensor"] == np.round(cal.R, 12).tolist()


def test_the_summary_says_whether_an_estimated_offset_was_applied():
    rig, _ = _rig(offset=None, offset_window=2.0, max_offset=0.1, correct_offset=False)
    for k in range(int(2.5 / DT_SEN)):
        rig.add_orientation(k * DT_SEN, _motion(k * DT_SEN) @ R0)
        if k % 4 == 0:
            rig.add_camera(k * DT_SEN, _motion(k * DT_SEN))
    s = rig.summary()
    assert s["clock_offset_s"] is not None and s["clock_offset_given"] is False
    assert s["clock_offset_applied"] is False and rig.used_offset == 0.0
    short, _ = _rig(offset=None, offset_window=30.0)
    _feed(short, 0.1)
    short.finish()
    s = short.summary()
    assert s["clock_offset_s"] is None and s["clock_offset_applied"] is False and s["note"] == short.offset_note


# ----------------------------------------------------------- replay's options, columns and re-mount
def test_replay_passes_its_options_to_the_rig():
    cam, sen = _streams(3.0)
    seen = []
    out = replay(cam, sen, OnlineCalibrator(), interval=0.25, offset=None, offset_window=2.0, max_offset=0.1,
                 correct_offset=False, stride=2, on_pair=lambda t, A, B: seen.append(t))
    assert list(out.columns) == ["t", "t_seen", "n_pairs", "radius_deg", "ready", "alarm", "event", "determined",
                                 "checking", "qw", "qx", "qy", "qz"]  # no reference, no error column
    assert seen == list(out["t"]) and out.attrs["summary"]["pairs_formed"] in (2 * len(out) - 1, 2 * len(out))
    assert out.attrs["summary"]["clock_offset_applied"] is False
    with pytest.raises(ValueError, match=r"offset_window must exceed 2 max_offset \+ 1 s = 3 s"):
        replay(cam, sen, OnlineCalibrator(), max_offset=1.0, offset_window=2.5)
    out = replay(cam, sen, OnlineCalibrator(), interval=0.25, offset_window=1.5)  # > 2 x 0.2 s (the default) + 1 s
    assert out.attrs["offset_s"] == pytest.approx(0.0, abs=2 * OFFSET_RESOLUTION)


def test_replay_without_pairs_has_the_columns_and_no_rows():
    cam, sen = _streams(0.2)
    out = replay(cam, sen, OnlineCalibrator(), interval=0.25, offset=0.0, reference=R0)
    assert len(out) == 0 and list(out.columns) == ["t", "t_seen", "n_pairs", "radius_deg", "ready", "alarm", "event",
                                                   "determined", "checking", "qw", "qx", "qy", "qz", "error_deg"]


def test_replay_before_any_estimate_has_nan_numbers():
    cam, sen = _streams(1.0)
    out = replay(cam, sen, OnlineCalibrator(), interval=0.25, offset=0.0, reference=R0)
    assert len(out) == 3
    for column in ("radius_deg", "qw", "qx", "qy", "qz", "error_deg"):
        assert out[column].dtype == float and out[column].isna().all()


def test_replay_remounts_from_the_remount_time_inclusive():
    cam, sen = _streams(1.6)
    R_re = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, math.pi / 2]))
    pairs = []
    t_re = 100.0 + 35 * DT_CAM  # the end of pair 4 (the first estimate, at min_pairs), a sensor sample time
    out = replay(cam, sen, OnlineCalibrator(min_pairs=4), interval=0.25, offset=0.0, reference=R0,
                 remount=(t_re, R_re), on_pair=lambda t, A, B: pairs.append((t, A, B)))
    assert [t for t, _, _ in pairs] == list(out["t"]) and len(pairs) == 5
    t, A, B = pairs[3]
    assert t == t_re and np.allclose(B, R_re.T @ R0.T @ A @ R0, atol=1e-9)  # its end orientation is re-mounted
    t, A, B = pairs[4]
    assert np.allclose(B, R_re.T @ R0.T @ A @ R0 @ R_re, atol=1e-9)
    row = out.iloc[3]
    assert row["t"] == t_re and row["error_deg"] > 45  # the estimate there, near R0, against R0 R_re: about 90 deg


def test_replay_remounts_a_gyro_by_its_rates():
    t = np.arange(0.0, 3.0, DT_CAM)
    ts = np.arange(-1.0, 4.0, DT_SEN)
    cam = OrientationStream(t, np.array([_C(x) for x in t]), "cam")
    gyro = GyroStream(ts, np.tile(R0.T @ W, (len(ts), 1)), "gyro")  # world_from_sensor = C R0: body rate R0^T W
    R_re = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, math.pi / 2]))
    pairs = []
    replay(cam, gyro, OnlineCalibrator(), interval=0.25, offset=0.0, remount=(1.0, R_re),
           on_pair=lambda t, A, B: pairs.append((t, A, B)))
    for t_end, A, B in pairs:
        expected = R0.T @ A @ R0 if t_end < 1.0 else R_re.T @ R0.T @ A @ R0 @ R_re if t_end - 0.25 > 1.0 else None
        if expected is not None:
            assert np.allclose(B, expected, atol=1e-9)
    assert sum(t_end - 0.25 > 1.0 for t_end, _, _ in pairs) >= 4


# ------------------------------------------------------------------ the input-mistake diagnosis
def _gyro_in_deg_per_s(seconds=5.0):
    """Camera poses at 8 Hz and a 32 Hz gyro of the same motion whose rates are in deg/s (read as
    rad/s)."""
    tc, ts = np.arange(0.0, seconds, 1 / 8), np.arange(-0.5, seconds + 0.5, 1 / 32)
    S = np.array([_motion(t) @ R0 for t in ts])
    w = so3.rotation_vector_from_matrix(np.swapaxes(S[:-1], -1, -2) @ S[1:]) * 32
    return (OrientationStream(tc, np.array([_motion(t) for t in tc]), "cam"),
            GyroStream(ts[:-1] + 1 / 64, np.degrees(w), "gyro"))


def _fails_ml(out):
    return {r["check"]: r["message"] for r in out.attrs["summary"]["verdict"]["reasons"] if r["level"] == "fail"}


def test_a_failing_online_verdict_names_the_input_mistake():
    cam, gyro = _gyro_in_deg_per_s()
    out = replay(cam, gyro, OnlineCalibrator(), interval=0.25, offset=0.0, offset_window=2.5, max_offset=0.05)
    assert "gyro rates in deg/s read as rad/s" in _fails_ml(out)["input_mistake"]


def test_without_diagnose_a_failing_verdict_names_no_input_mistake():
    cam, gyro = _gyro_in_deg_per_s()
    out = replay(cam, gyro, OnlineCalibrator(), interval=0.25, offset=0.0, offset_window=2.5, max_offset=0.05,
                 diagnose=False)
    assert _fails_ml(out) and "input_mistake" not in _fails_ml(out)


def test_the_pair_times_kept_for_the_events_are_bounded():
    cal = OnlineCalibrator(confirm_pairs=5)  # keeps at most 4 x 5 + 256 = 276 pair times, then forgets the older half
    rig = LiveRig(cal, interval=0.125, offset=0.0, diagnose=False)
    t = np.arange(-2, 555) / 8
    C = so3.matrix_from_rotation_vector(np.stack([np.sin(1.3 * t), np.cos(0.7 * t), 0.8 * np.sin(0.5 * t + 1.0)],
                                                 axis=1))
    S = C @ R0
    for k in range(len(t)):  # camera poses at 8 Hz from t = 0 form pairs (0, 1), (2, 3), ...; the sensor at 4 Hz
        if k % 2 == 0:
            rig.add_orientation(t[k], S[k])
        if k == 554:  # the sample after pose 551 formed the 276th pair
            assert cal.n_total == 276 and sorted(rig._times) == list(range(276))
        if k >= 2:
            rig.add_camera(t[k], C[k])
    assert cal.n_total == 277 and sorted(rig._times) == list(range(138, 277))
    assert rig._times[276] == (rig.events[-1][0], rig.events[-1][1])


def test_an_event_of_pairs_the_rig_did_not_form_has_no_times():
    rng = np.random.default_rng(5)
    cal = OnlineCalibrator(confirm_pairs=5)
    R_re = so3.matrix_from_rotation_vector(np.radians(10.0) * np.array([0.0, 1.0, 0.0]))
    for j in range(60):  # pairs given to the calibrator directly, a re-mount half-way
        R = R0 if j < 30 else R0 @ R_re
        A = so3.matrix_from_rotation_vector(rng.normal(size=3) * 0.5)
        cal.update(A, so3.matrix_from_rotation_vector(rng.normal(size=3) * math.radians(0.1)) @ R.T @ A @ R)
    assert [e.kind for e in cal.events] == ["remount"]
    ev = LiveRig(cal, offset=0.0, diagnose=False).summary()["events"][0]
    assert ev["kind"] == "remount" and math.isnan(ev["t_s"]) and math.isnan(ev["pair_end_s"])
    assert math.isnan(ev["alarm_t_s"])


def test_a_sensor_step_of_exactly_five_typical_steps_is_not_a_gap():
    # sample times whose step 1 -> T2 is exactly GAP_FACTOR x the running typical step (0.99 x 1 +
    # 0.01 x step) in floating point, and T2 -> T3 leaves the typical step there (found by search
    # over the last bits)
    T2, T3 = 6.2105263157894735, 7.252631578947368
    slow = lambda t: so3.matrix_from_rotation_vector(0.1 * W * t)  # noqa: E731  (0.52 rad over the long step: slerp stays exact)
    for (t0, t1), samples in (((1.5, 2.5), (0.0, 1.0, T2)),   # both poses bracketed by the long step
                              ((0.5, 7.0), (0.0, 1.0, T2, T3))):  # the long step inside the pair
        rig, pairs = _rig(interval=t1 - t0)
        for t, kind in sorted([(t, 0) for t in samples] + [(t0, 1), (t1, 1)]):
            if kind:
                rig.add_camera(t, slow(t))
            else:
                rig.add_orientation(t, slow(t) @ R0)
        assert 5.0 * rig._gyro_dt == T2 - 1.0
        assert rig.pairs_dropped == 0 and len(pairs) == 1
        assert np.allclose(pairs[0][2], R0.T @ pairs[0][1] @ R0, atol=1e-12)


@pytest.mark.parametrize("formed, used", [(9, 3), (10, 4), (11, 4), (12, 4), (1, 1)])
def test_the_pairs_before_gaps_count_the_pairs_a_stride_uses_like_the_batch(formed, used):
    """Pairs 1, 1 + stride, 1 + 2 stride, ... are used: ceil(formed / stride), as the batch's
    len(A[::stride])."""
    from replication.rig.live import LiveRig

    rig = LiveRig(OnlineCalibrator(), stride=3, offset=0.0)
    rig.pairs_formed = formed
    assert rig.evidence()["pairs_before_gaps"] == used == len(range(formed)[::3])


# ------------------------------------------------------------------ rules pinned at their values
# The summary's drift rate, the clock watch after an event, the gyro correction, the time units
# named on the rates and on the spans, the no-overlap note, replay's options and its radius column:
# each rule at the values where a changed sign, index, bound or name would show.
def _event(kind, pair, alarm_pair=0, onset_pair=0, rate=None):
    from replication.rig.online_events import OnlineEvent

    return OnlineEvent(kind, pair, alarm_pair, "cusum", onset_pair, 10, 1.0, 0.5, 1.0, 1.0, 0, np.eye(3), np.eye(3),
                       f"a {kind}", rate)


@pytest.mark.parametrize("pair, onset, onset_times, rate", [
    (10, 4, None, 0.25 * 6 / 7.2),        # no event at the onset: the pairs taken as even from the first pair's end
    (1, 0, None, 0.25 * 1 / 12.0),        # one pair since the first: the span is all of it
    (10, 4, (9.0, 11.0), 0.25 * 6 / 5.0),  # the onset's own pair end: a span of 5 s
    (10, 4, (13.5, 20.0), 0.25 * 6 / 0.5),  # half a second: still a rate
    (10, 4, (14.0, 20.0), None),          # no time between them: no rate
    (10, 4, (15.0, 20.0), None),          # the onset after the end: no rate
])
def test_the_summary_gives_a_drifts_rate_per_second_over_the_span_since_its_onset(pair, onset, onset_times, rate):
    """A drift of 0.25 deg per pair decided at the pair ending at 14 s, the first pair ending at 2 s
    (formed at 3 s): its rate per second is the rate per pair times the pairs since its onset over
    the seconds since then (the onset's pair end where an event was decided there, else the pairs
    taken as evenly spaced since the first one)."""
    cal = OnlineCalibrator()
    rig = LiveRig(cal, offset=0.0, diagnose=False)
    cal.events = [_event("drift", pair, onset_pair=onset, rate=0.25), _event("remount", 3, alarm_pair=2)]
    rig.events = [(2.0, 3.0, None), (2.5, 3.5, None)]
    rig._event_times = {3: (4.0, 5.0), pair: (14.0, 15.0)}
    if onset_times is not None:
        rig._event_times[onset] = onset_times
    drift, remount = rig.summary(t0=1.0)["events"]
    assert remount["rate_deg_s"] is None and "rate_deg_s" in remount and remount["kind"] == "remount"
    assert (drift["kind"], drift["t_s"], drift["pair_end_s"]) == ("drift", 14.0, 13.0)
    if rate is None:
        assert drift["rate_deg_s"] is None
    else:
        assert drift["rate_deg_s"] == pytest.approx(rate, rel=1e-12)


def test_a_stream_ending_undecided_withholds_ready_and_says_so(monkeypatch):
    from replication.rig.quality import Reason

    cal = OnlineCalibrator()
    rig = LiveRig(cal, offset=0.0, diagnose=False)
    end = Reason("end_undecided", "warning", 3.0, 5.0, "the stream ended while an alarm was being confirmed")
    monkeypatch.setattr(cal, "unresolved_end", lambda: end)
    s = rig.summary()
    assert not s["ready"] and end.to_dict() in s["verdict"]["reasons"]
    assert [r["check"] for r in s["verdict"]["reasons"]].count("end_undecided") == 1


@pytest.mark.parametrize("kind, watched", [("noise_change", True), ("outliers", True), ("remount", False),
                                           (None, False)])
@pytest.mark.parametrize("alarm_formed", [True, False])
def test_an_event_that_may_be_a_clock_step_is_watched_from_its_alarm_pairs_end(kind, watched, alarm_formed,
                                                                              monkeypatch):
    """A ``noise_change`` or ``outliers`` event (a clock step?) is checked from the end of its alarm
    pair (the pair's end, not when it was formed; the pair just formed where the rig formed no such
    pair), with its index in the calibrator's events."""
    from replication.rig.online import OnlineState

    cal = OnlineCalibrator()
    rig = LiveRig(cal, offset=0.0, diagnose=False)
    rig._times.update({3: (5.0, 7.5), 4: (6.0, 8.5)})
    cal.events = [_event("remount", 1, alarm_pair=3), _event("outliers", 2, alarm_pair=4)]
    last = _event(kind or "none", 5, alarm_pair=3 if alarm_formed else 99)

    def update(A, B):
        if kind is not None:
            cal.events.append(last)
        return OnlineState(1, np.eye(3), math.inf, False, False, kind)

    monkeypatch.setattr(cal, "update", update)
    rig._now = 12.0
    rig._pair(10.0, np.eye(3), np.eye(3))
    assert rig._clock.pending == ([(5.0 if alarm_formed else 10.0, 2)] if watched else [])


def test_the_clock_watch_measures_its_baseline_on_what_both_streams_gave():
    """With a given offset (0) and a sensor 12.3 ms late, the clock watch's starting offset is
    measured on the held orientations of both streams at the rig's offset resolution (a failed
    measurement would fall back on the given 0)."""
    rig, pairs = _rig(interval=2.0, gyro_bias=False)  # the first pair (its first poll) at 2 s
    for k in range(-16, int(3.0 / DT_SEN)):
        t = k * DT_SEN
        rig.add_orientation(t + 0.0123, _motion(t) @ R0)
        if k % 4 == 0 and k >= 0:
            rig.add_camera(t, _motion(t))
    assert pairs and rig._clock.baseline == pytest.approx(0.0123, abs=1e-3)


def test_the_offset_search_and_the_diagnosis_run_at_the_resolution_the_evidence_reports(monkeypatch):
    from replication.rig import association, live

    monkeypatch.setattr(live, "OFFSET_RESOLUTION", 4e-3)
    real, used = association.estimate_time_offset, []

    def spy(camera, sensor, **kw):
        used.append(kw.get("resolution", "the default"))
        return real(camera, sensor, **kw)

    monkeypatch.setattr(association, "estimate_time_offset", spy)
    rig, _ = _rig(offset=None, offset_window=2.0, max_offset=0.1)
    _feed(rig, 2.5, offset=0.0123)
    assert used[0] == 4e-3 and rig.evidence()["offset_resolution_s"] == 4e-3
    diagnosed = []
    monkeypatch.setattr(live, "run_diagnosis", lambda r, resolution: diagnosed.append(resolution))
    cam, gyro = _gyro_in_deg_per_s()
    replay(cam, gyro, OnlineCalibrator(), interval=0.25, offset=0.0, offset_window=2.5, max_offset=0.05)
    assert diagnosed and set(diagnosed) == {4e-3}


def test_gyro_rates_are_corrected_by_the_models_bias_and_inverse_axes():
    """Each rate becomes ``T^-1 (omega - b)`` (binary fractions: exact)."""
    rig, _ = _rig(gyro_bias=False)
    rig._b = (0.5, -0.25, 0.125)
    rig._Ti = ((1.0, 0.5, 0.25), (-0.5, 2.0, 0.75), (0.125, -0.375, 1.5))
    rig.add_gyro(0.0, [1.0, 2.0, 3.0])
    u = np.array([0.5, 2.25, 2.875])
    assert rig._last_gyro[1] == tuple(np.array(rig._Ti) @ u) == (2.34375, 6.406250, 3.53125)
    assert np.array_equal(rig._early_sensor[-1][1], [2.34375, 6.40625, 3.53125])


@pytest.mark.parametrize("omega, shown", [
    ([0.0, 0.0], r"omega=\[0\.0, 0\.0\]"),                  # not 3 rates
    ([1e308, 1e308, 0.0], r"omega=\[1e\+308, 1e\+308, 0\.0\]"),  # finite rates whose sum with the time overflows
    ([1e308, 0.0, 1e308], r"omega=\[1e\+308, 0\.0, 1e\+308\]"),
    ([0.0, 1e308, 1e308], r"omega=\[0\.0, 1e\+308, 1e\+308\]"),
])
def test_a_refused_gyro_sample_is_shown_as_given(omega, shown):
    rig, _ = _rig()
    with pytest.raises(ValueError, match=r"a gyro sample is a finite time and 3 finite rates, got t=2\.0, " + shown):
        rig.add_gyro(2.0, omega)
    assert rig._last_gyro is None


@pytest.mark.parametrize("first", [True, False])
@pytest.mark.parametrize("omega, refused", [([1e200, 0.0, 0.0], True), ([0.0, 0.0, 1.4e154], True),
                                            ([1.3e154, 1.3e154, 0.0], True), ([1.3e154, 0.0, 1.3e154], True),
                                            ([1.3e154, 0.0, 0.0], False)])
def test_rates_whose_square_overflows_are_refused_naming_them(first, omega, refused):
    """Finite rates whose rotation cannot be formed (|omega|^2 beyond the floats) are refused with
    the rates and their unit, first sample or not; just below, they integrate."""
    rig, _ = _rig()
    if not first:
        rig.add_gyro(1.0, [0.0, 0.0, 0.0])
    if refused:
        with pytest.raises(ValueError, match=r"^gyro rates too large to integrate \(\|omega\|\^2 overflows\): omega="):
            rig.add_gyro(2.0, omega)
    else:
        rig.add_gyro(2.0, omega)


def test_the_time_units_are_named_once_on_the_spans_of_both_streams():
    """Camera poses over 10 s, sensor orientations over 10000 s (ms read as s): the verdict names
    the time unit once, with the ratio of the spans from each stream's first sample to its latest
    (exactly 1000)."""
    rig, _ = _rig(interval=1.0, gyro_bias=False)
    rig.add_orientation(0.0, R0)
    for t in (0.0, 5.0, 10.0):
        rig.add_camera(t, _C(t))
    assert not any(r["check"] == "time_unit" for r in rig.verdict().to_dict()["reasons"])  # the sensor: one sample
    for t in (5000.0, 9999.0, 9999.5, 10000.0):
        rig.add_orientation(t, R0)
    for _ in range(2):
        units = [r for r in rig.verdict().to_dict()["reasons"] if r["check"] == "time_unit"]
    assert len(units) == 1 and (units[0]["level"], units[0]["measured"], units[0]["threshold"]) == (
        "fail", 1000.0, 1000.0)
    assert "the camera stream spans 10 s and the sensor stream 1e+04 s" in units[0]["message"]


def test_without_sensor_samples_the_verdict_names_no_time_unit():
    rig, _ = _rig(interval=1.0)
    for t in (0.0, 5.0, 10.0):
        rig.add_camera(t, _C(t))
    assert not any(r["check"] == "time_unit" for r in rig.verdict().to_dict()["reasons"])


def _no_overlap(sensor_dt):
    """Two camera poses 0.05 s apart and 20 sensor orientations ``sensor_dt`` apart, then the
    end: too little for the offset search."""
    rig, _ = _rig(offset=None, offset_window=30.0, gyro_bias=False)
    for k in range(20):
        rig.add_orientation(k * sensor_dt, _motion(k * 0.05) @ R0)
        if k < 2:
            rig.add_camera(k * 0.05, _motion(k * 0.05))
    rig.finish()
    return rig, {r["check"]: r for r in rig.verdict().to_dict()["reasons"]}


def test_no_overlap_with_sample_rates_in_different_units_names_the_unit_not_the_overlap():
    rig, reasons = _no_overlap(5.0)  # a sensor every 5 s, the camera every 0.05 s: ms read as s
    unit = reasons["time_unit"]
    assert (unit["level"], unit["measured"], unit["threshold"]) == ("fail", 100.0, 1000.0)
    assert "overlap" not in reasons and rig.offset is None
    assert rig.offset_note.startswith("no clock offset: the streams ended after 95.0 s of camera data, before the "
                                      "30 s offset window (the streams overlap in fewer than 10 camera samples")
    assert rig.offset_note.endswith(f"; {unit['message']})") and rig.offset_note.count("no clock offset") == 1


def test_no_overlap_at_plausible_rates_names_the_overlap():
    rig, reasons = _no_overlap(0.05)
    assert "time_unit" not in reasons
    overlap = reasons["overlap"]
    assert overlap["level"] == "fail" and re.fullmatch(
        r"no clock offset: the streams overlap in fewer than 10 camera samples \(overlap [0-9.]+\.\.[0-9.]+ s\)",
        overlap["message"])
    err = overlap["message"].removeprefix("no clock offset: ")
    assert rig.offset_note == ("no clock offset: the streams ended after 1.0 s of camera data, before the 30 s offset "
                               f"window ({err})")


def test_a_camera_turning_at_constant_speed_is_named_when_the_offset_is_sought():
    rig, _ = _rig(offset=None, offset_window=2.0, max_offset=0.1, interval=0.125)
    _feed(rig, 3.0)
    assert "constant_speed" in {r["check"] for r in rig.verdict().to_dict()["reasons"]}


class _Scripted(OnlineCalibrator):
    """A calibrator whose states after each pair are given (its own work done, then replaced)."""

    def __init__(self, states):
        super().__init__()
        self.script = iter(states)

    def update(self, A, B):
        super().update(A, B)
        return next(self.script)


def test_replay_gives_a_radius_only_for_an_estimate_and_only_when_finite():
    from replication.rig.online import OnlineState

    states = [OnlineState(1, R0, 1.5, False, False, estimated=False), OnlineState(2, R0, math.inf, False, False,
                                                                                   estimated=True),
              OnlineState(3, R0, 1.5, False, False, estimated=True)]
    cam, sen = _streams(1.0)
    out = replay(cam, sen, _Scripted(states), interval=0.25, offset=0.0, reference=R0)
    assert len(out) == 3 and out["radius_deg"].isna().tolist() == [True, True, False]
    assert out["radius_deg"].iloc[2] == 1.5


def test_replay_without_pandas_names_what_needs_it(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pandas", None)
    cam, sen = _streams(1.0)
    with pytest.raises(ImportError, match=r"^replay \(its table of pairs; calibrate --online\) needs pandas"):
        replay(cam, sen, OnlineCalibrator(), interval=0.25, offset=0.0)


@pytest.mark.parametrize("kw, estimated", [({}, True), ({"gyro_bias": False}, False)])
def test_replay_estimates_the_gyros_bias_by_default_and_not_when_told(kw, estimated):
    cam, gyro = _gyro_rig_streams()
    out = replay(cam, gyro, OnlineCalibrator(), interval=0.25, offset=0.0, offset_window=2.5, max_offset=0.05,
                 diagnose=False, **kw)
    assert (out.attrs["summary"]["gyro_bias_rad_s"] is not None) is estimated


def test_finish_after_a_single_camera_pose_names_no_offset_and_raises_nothing():
    """A live camera that gave one pose before the end: no offset, said in the note, no exception
    (the offset search's own errors never raise) and no warning (no median of an empty step
    list)."""
    import warnings

    rig, pairs = _rig(offset=None, offset_window=30.0, gyro_bias=False)
    for k in range(20):
        rig.add_orientation(k * 0.05, _motion(k * 0.05) @ R0)
    rig.add_camera(0.1, _motion(0.1))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rig.finish()
    assert rig.offset is None and rig.offset_note.startswith("no clock offset") and pairs == []
    assert "(camera: need at least 2 samples, got 1)" in rig.offset_note


def test_finish_after_a_single_sensor_sample_names_the_sensor_stream():
    """The mirror of the single camera pose: one sensor orientation before the end."""
    rig, pairs = _rig(offset=None, offset_window=30.0, gyro_bias=False)
    rig.add_orientation(0.0, _motion(0.0) @ R0)
    for k in range(20):
        rig.add_camera(k * 0.05, _motion(k * 0.05))
    rig.finish()
    assert rig.offset is None and "(sensor: need at least 2 samples, got 1)" in rig.offset_note and pairs == []


def _gyro_rig_streams(seconds=5.0):
    """Camera poses at 8 Hz and a 32 Hz gyro (rad/s) of the same motion."""
    tc, ts = np.arange(0.0, seconds, 1 / 8), np.arange(-0.5, seconds + 0.5, 1 / 32)
    S = np.array([_motion(t) @ R0 for t in ts])
    w = so3.rotation_vector_from_matrix(np.swapaxes(S[:-1], -1, -2) @ S[1:]) * 32
    return OrientationStream(tc, np.array([_motion(t) for t in tc]), "cam"), GyroStream(ts[:-1] + 1 / 64, w, "gyro")


def test_a_gyros_bias_is_estimated_by_default_while_streaming_and_pairs_wait_for_it():
    """A gyro, a given offset, a 2.5 s window: the integrated buffer holds the window until the bias
    is estimated (on it, while the streams run, not at their end), and the pairs wait for it."""
    cam, gyro = _gyro_rig_streams()
    pairs = []
    rig = LiveRig(OnlineCalibrator(), interval=0.25, offset=0.0, offset_window=2.5, max_offset=0.05, diagnose=False,
                  on_pair=lambda t, A, B: pairs.append(t))
    for t, kind, k in sorted([(t, 1, k) for k, t in enumerate(cam.t)] + [(t, 0, k) for k, t in enumerate(gyro.t)]):
        if kind:
            rig.add_camera(t, cam.world_from_body[k])
        else:
            rig.add_gyro(t, gyro.omega[k])
    assert rig.bias is not None and rig._raw is None and np.abs(rig.bias.bias_rad_s).max() < 0.01
    assert pairs and pairs[0] < 2.5 <= rig.events[0][1]  # the first pair formed once the window was held


@pytest.mark.parametrize("name", ["correct_offset", "diagnose", "gyro_bias"])
def test_the_rigs_flags_are_named_when_not_booleans(name):
    with pytest.raises(ValueError, match=rf"^{name} must be True or False, got 1$"):
        LiveRig(OnlineCalibrator(), **{name: 1})


def test_no_overlap_found_on_a_full_window_is_named_once_and_not_sought_again():
    """The sensor stamped 1000 s after the camera: the search on the first window finds no overlap;
    the later samples do not search again (one ``overlap`` reason, no pair)."""
    rig, pairs = _rig(offset=None, offset_window=2.0, max_offset=0.1)
    for t in np.arange(0.0, 3.0, DT_CAM):
        rig.add_camera(t, _C(t))
    for t in np.arange(1000.0, 1003.0, DT_SEN):
        rig.add_orientation(t, _C(t - 1000.0) @ R0)
    checks = [r["check"] for r in rig.verdict().to_dict()["reasons"]]
    assert checks.count("overlap") == 1 and rig.offset is None and pairs == []


def test_a_pair_whose_start_falls_inside_a_sensor_gap_is_dropped():
    rig, pairs = _rig()
    _feed(rig, 1.2, sensor_skip=set(range(34, 42)))  # pair 2 starts at 9/32 = 36/128, inside the hole 33 -> 42
    assert rig.pairs_dropped == 1 and [round(t / DT_CAM) for t, _, _ in pairs] == [8, 26, 35]
