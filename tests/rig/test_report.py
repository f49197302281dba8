"""What a calibration reports (:mod:`replication.rig.report`): strict JSON (``json_safe``), every
field of ``to_dict`` and every line of ``summary``, for streams and static poses, with and without a
change test, a reference, an offset. Mutation testing (scripts/mutation) found these unguarded by
the fast tests."""
import json
import math

import numpy as np
import pytest

from conftest import MAGIC
from replication import __version__
from replication.core.motions import MotionObservability
from replication.rig.calibration import calibrate
from replication.rig.quality import Reason, Verdict
from replication.rig.report import OFFSET_CONVENTION, RADIUS_COVERS, CalibrationResult, json_safe

OBS = MotionObservability(kron_singular_values=np.ones(9), spectral_ratio=np.float64(0.5), two_step_rate=0.9,
                          camera_axis_spread_deg=np.float64(12.34), sensor_axis_spread_deg=np.float64(11.0),
                          camera_rms_motion_deg=20.0, symmetric_gap=0.3, inconsistency=0.01)
R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _result(**kw):
    base = dict(R=R, quaternion_wxyz=np.array([0.5, 0.5, 0.5, 0.5]), euler_zyx_deg=np.array([90.0, 1.5, -2.25]),
                method="chordal_optimal", interval_s=0.5, n_pairs=42, time_offset_s=0.0123,
                time_offset_correlation=0.98765, time_offset_applied=True,
                residual_deg={"mean": 0.2, "median": 0.125, "rms": 0.25, "p95": 0.5, "max": 1.0},
                bootstrap_ci95_deg=0.3456, observability=OBS)
    base.update(kw)
    return CalibrationResult(**base)


def test_json_safe_makes_native_types_and_nulls():
    got = json_safe({1: np.float32(1.5), "a": (np.int64(3), [np.nan, np.inf, -np.inf, 2.0]), "b": np.bool_(True),
                     "c": np.array([[1, 2]]), "d": None, "e": "s", "f": True, "g": 7, "h": np.float64(np.nan)})
    assert got == {"1": 1.5, "a": [3, [None, None, None, 2.0]], "b": True, "c": [[1, 2]], "d": None, "e": "s",
                   "f": True, "g": 7, "h": None}
    assert type(got["a"][0]) is int and type(got["b"]) is bool and type(got["1"]) is float
    assert type(got["c"][0][0]) is int and type(got["f"]) is bool and type(got["g"]) is int
    json.dumps(got, allow_nan=False)


def test_to_dict_holds_every_field():
    reason = Reason("n_pairs", "warning", 42.0, 30.0, "m")
    res = _result(verdict=Verdict.of([reason]), warnings=("W: x",), parameters={"p": 1}, inputs={"i": 2},
                  reference_error_deg=0.75, time_offset_ci95_s=(0.01, np.inf), time_offset_peak_margin=0.4,
                  reference_errors_deg=(0.75, 0.5), reference_disagreement_deg=0.3, reference_reading="r",
                  bootstrap_resamples="pairs in moving blocks of 4", pose_residual_median_deg=[0.1, np.nan],
                  station_repeats={"stations": 3, "distinct": 2, "groups": [[0, 2]]},
                  change_test={"run": False, "note": "n"}, segments={"run": False, "note": "s"}, online={"o": 1})
    d = res.to_dict()
    assert d == {
        "package": {"name": "replication", "version": __version__},
        "R0_camera_from_sensor": R.tolist(),
        "quaternion_wxyz": [0.5, 0.5, 0.5, 0.5],
        "euler_zyx_deg": {"yaw": 90.0, "pitch": 1.5, "roll": -2.25},
        "conventions": "R0 maps sensor-frame vectors into the camera frame (A_j R0 = R0 B_j); quaternion scalar "
                       "first; Euler intrinsic z-y'-x'' (yaw, pitch, roll)",
        "verdict": {"level": "warning", "reasons": [reason.to_dict()]},
        "warnings": ["W: x"],
        "method": "chordal_optimal",
        "parameters": {"p": 1},
        "inputs": {"i": 2},
        "interval_s": 0.5,
        "n_pairs": 42,
        "time_offset_s": 0.0123,
        "time_offset_correlation": 0.98765,
        "time_offset_applied": True,
        "time_offset_convention": OFFSET_CONVENTION,
        "time_offset_ci95_s": [0.01, None],
        "time_offset_peak_margin": 0.4,
        "residual_deg": {"mean": 0.2, "median": 0.125, "rms": 0.25, "p95": 0.5, "max": 1.0},
        "bootstrap_ci95_deg": 0.3456,
        "bootstrap_resamples": "pairs in moving blocks of 4",
        "bootstrap_covers": RADIUS_COVERS,
        "pose_residual_median_deg": [0.1, None],
        "station_repeats": {"stations": 3, "distinct": 2, "groups": [[0, 2]]},
        "change_test": {"run": False, "note": "n"},
        "segments": {"run": False, "note": "s"},
        "online": {"o": 1},
        "observability": {"spectral_ratio": 0.5, "camera_axis_spread_deg": 12.34, "sensor_axis_spread_deg": 11.0},
        "reference_error_deg": 0.75,
        "reference_errors_deg": [0.75, 0.5],
        "reference_disagreement_deg": 0.3,
        "reference_reading": "r",
        "gyro_bias_rad_s": None, "gyro_bias_ci95_rad_s": None, "clock_drift_ppm": None, "clock_drift_ci95_ppm": None,
        "gyro_scale": None, "gyro_scale_ci95": None, "gyro_misalignment": None, "gyro_misalignment_ci95": None,
        "sensor_model": None,
    }
    json.dumps(d, allow_nan=False)


def test_to_dict_rounds_the_rotation_to_12_digits():
    c, s = 0.123456789012345, math.sqrt(1 - 0.123456789012345 ** 2)
    Rf = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q = np.array([0.987654321098765, 0.0, 0.0, math.sqrt(1 - 0.987654321098765 ** 2)])
    d = _result(R=Rf + 1e-13, quaternion_wxyz=q + 1e-13).to_dict()
    assert d["R0_camera_from_sensor"] == np.round(Rf + 1e-13, 12).tolist()
    assert d["R0_camera_from_sensor"][0][0] == 0.123456789012
    assert d["quaternion_wxyz"] == np.round(q + 1e-13, 12).tolist() and d["quaternion_wxyz"][0] == 0.987654321099


def test_summary_of_a_stream_calibration_line_by_line():
    res = _result(verdict=Verdict.of([Reason("x", "warning", 1.0, 2.0, "a reason")]),
                  time_offset_ci95_s=(0.0101, 0.0145), reference_error_deg=0.5,
                  bootstrap_resamples="pairs in moving blocks of 4",
                  change_test={"run": True, "split_time_s": 12.34, "angle_deg": 0.1234, "significant": False,
                               "p_value": 0.25, "level": 0.01, "splits_from_s": 3.04, "splits_to_s": 57.06})
    assert res.summary().split("\n") == [
        "verdict: WARNING",
        "  warning: a reason",
        "R0 (camera_from_sensor), chordal_optimal, 42 pairs at 0.5 s:",
        "  [+0.000000  -1.000000  +0.000000]",
        "  [+1.000000  +0.000000  +0.000000]",
        "  [+0.000000  +0.000000  +1.000000]",
        "quaternion (w, x, y, z): [0.5 0.5 0.5 0.5]",
        "yaw / pitch / roll (z-y'-x''): 90.000 / 1.500 / -2.250 deg",
        "time offset: +12.30 ms: the sensor sample stamped t + 12.30 ms matches the camera sample stamped t (sensor "
        "clock ahead of the camera's by 12.30 ms, 95 % interval [+10.10, +14.50] ms excludes 0; Kalibr's "
        "timeshift_cam_imu, t_imu = t_cam + shift) (correlation 0.9877, applied)",
        "pair residuals: median 0.125 deg, rms 0.250 deg",
        f"bootstrap 95% radius: 0.346 deg (resampling pairs in moving blocks of 4); it covers {RADIUS_COVERS}",
        "axis spread camera 12.3 deg",
        "change test: R0 before and after 12.3 s differ by 0.123 deg, within their noise (p = 0.25 >= the test's level "
        "0.01; splits tested from 3.0 to 57.1 s: a change outside cannot be told)",
        "angle to the reference: 0.500 deg",
    ]


def test_summary_prints_the_quaternion_to_six_decimals():
    q = np.array([0.123456789, 0.2, 0.3, 0.923456789])
    line = next(x for x in _result(quaternion_wxyz=q).summary().split("\n") if x.startswith("quaternion"))
    assert line == "quaternion (w, x, y, z): [0.123457 0.2      0.3      0.923457]"


def test_summary_variants():
    lines = _result(time_offset_applied=False, time_offset_ci95_s=(math.nan, 0.02), bootstrap_ci95_deg=math.nan,
                    change_test={"run": True, "split_time_s": 3.0, "angle_deg": 2.0, "significant": True,
                                 "p_value": 1e-5, "splits_from_s": 1.0, "splits_to_s": 9.0}).summary().split("\n")
    assert lines[0] == "verdict: OK"
    offset = next(line for line in lines if line.startswith("time offset: "))
    assert offset.startswith("time offset: +12.30 ms, no direction resolved: its 95 % interval [+nan, +20.00] ms "
                             "is not fully measured, so the data do not say whether the sensor clock is ahead or")
    assert offset.endswith(" (correlation 0.9877, not applied)")
    assert "bootstrap 95% radius: not available (resampling none); it covers " in "\n".join(lines)
    assert lines[-1] == ("change test: R0 before and after 3.0 s differ by 2.000 deg, beyond their noise (p = 1e-05; "
                         "splits tested from 1.0 to 9.0 s: a change outside cannot be told)")
    lines = _result(time_offset_ci95_s=(-math.inf, math.inf), change_test={"run": False, "note": "too short"})\
        .summary().split("\n")
    offset = next(line for line in lines if line.startswith("time offset: "))
    assert offset.startswith("time offset: no offset resolved: +12.30 ms, its 95 % interval [-inf, +inf] ms includes 0")
    assert offset.endswith("shift) (correlation 0.9877, applied)")
    assert lines[-1] == "change test: too short"
    assert not any(line.startswith("angle to the reference") for line in lines)


def test_summary_of_static_poses_has_no_clock():
    lines = _result(interval_s=math.nan, time_offset_s=math.nan, time_offset_correlation=math.nan).summary().split("\n")
    assert "R0 (camera_from_sensor), chordal_optimal, 42 pairs of static poses:" in lines
    assert not any(line.startswith("time offset") or line.startswith("change test") for line in lines)


def test_defaults_of_a_result():
    res = _result()
    assert res.verdict.level == "ok" and res.verdict.reasons == ()
    assert res.bootstrap_resamples == "none" and res.bootstrap_covers == RADIUS_COVERS
    assert res.warnings == () and res.parameters == {} and res.inputs == {} and res.diagnostics == {}
    assert all(math.isnan(v) for v in res.time_offset_ci95_s) and math.isnan(res.time_offset_peak_margin)
    assert res.reference_error_deg is None and res.change_test is None and res.online is None


def test_plot_returns_the_figure_and_writes_it_at_110_dpi_only_when_asked(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from replication._io import png_bytes
    from replication.rig import figure as figures

    fig = Figure(figsize=(2, 1))
    fig.add_subplot().plot([0, 1], [0, 1])
    monkeypatch.setattr(figures, "calibration_figure", lambda res, **_: fig)
    monkeypatch.chdir(tmp_path)
    assert _result().plot() is fig and list(tmp_path.iterdir()) == []
    assert _result().plot(tmp_path / "f.png") is fig
    data = (tmp_path / "f.png").read_bytes()
    assert data == png_bytes(fig, dpi=110) and data != png_bytes(fig, dpi=100)


def test_the_api_plot_honours_the_extension_or_refuses_before_drawing(cli_rig, tmp_path, monkeypatch):
    _, camera, gyro, _ = cli_rig
    result = calibrate(camera, gyro, n_bootstrap=0)
    for suffix, magic in MAGIC.items():
        result.plot(tmp_path / f"f{suffix}")
        assert (tmp_path / f"f{suffix}").read_bytes().startswith(magic)
    import replication.rig.figure as figures

    monkeypatch.setattr(figures, "calibration_figure", lambda *a: pytest.fail("drawn before the format was checked"))
    with pytest.raises(ValueError, match=r"f\.jpeg: unknown figure format \.jpeg; supported: \.png, \.pdf, \.svg"):
        result.plot(tmp_path / "f.jpeg")
    assert not (tmp_path / "f.jpeg").exists()


def _segments(p_whole, left_out):
    """A segment test's report of 4 segments of 10 s, the second disagreeing by its own test
    (p 1e-9) where ``left_out``, with ``use="consistent"``."""
    from replication.rig.segments import Segment, SegmentTest, report

    seg = tuple(Segment(10.0 * i, 10.0 * (i + 1), 180, R, 0.1, 1.0 if i == 1 and left_out else 0.05, 1.0,
                        1e-9 if i == 1 and left_out else 0.5, i == 1 and left_out) for i in range(4))
    keep = (0, 2, 3) if left_out else (0, 1, 2, 3)
    test = SegmentTest(seg, p_whole < 0.01, 1.0, 2.0, p_whole, 0.01, 9, 1.0, 50.0, R, 0.05, 0.2, keep,
                       1.0 if left_out else 0.0)
    kept = 30.0 if left_out else 40.0
    return report(test, None, 0.0, {"kept_s": kept, "dropped_s": 40.0 - kept, "pairs_kept": 7})


def test_summary_names_each_segments_own_test_beside_the_test_of_all_together():
    lines = _result(segments=_segments(0.87, True)).summary().split("\n")
    line = next(x for x in lines if x.startswith("segments: "))
    assert "disagree: 10.0-20.0 s (each by its own test, p = 1e-09; all the segments together p = 0.87)" in line
    lines = _result(segments=_segments(0.87, False)).summary().split("\n")
    assert "segments: 4 of about 10 s (1 s pairs) agree (p = 0.87); " in "\n".join(lines)


def test_summary_of_use_consistent_says_when_nothing_was_left_out():
    """Nothing left out: no 'majority, not known to be right' nor an angle 'if the part left out
    is'; one segment left out: both."""
    text = "\n".join(_result(segments=_segments(0.87, False)).summary().split("\n"))
    assert "use='consistent': every segment agrees, nothing left out: R0 from all of 0.0-40.0 s (7 pairs)" in text
    assert "not known to be right" not in text and "left out is" not in text
    text = "\n".join(_result(segments=_segments(0.87, True)).summary().split("\n"))
    assert "use='consistent': R0 from 0.0-10.0 s, 20.0-40.0 s (7 pairs; the majority, not known to be right" in text
    assert "nothing left out" not in text


def _sensor_model(**details):
    """A gyro's sensor-model fields as the report holds them: bias 0.01, -0.02, 0.03 rad/s, drift
    12.34 ppm, scale and misalignment resolved on x and xy only."""
    base = {"note": "n", "drift_resolved": True, "bias_applied": True,
            "scale_held_ci95": [None, [0.98765, 1.01234], None], "scale_note": None}
    base.update(details)
    return {"gyro_bias_rad_s": [0.01, -0.02, 0.03],
            "gyro_bias_ci95_rad_s": [[0.009, 0.011], [-0.021, -0.019], [0.029, 0.031]],
            "clock_drift_ppm": 12.34, "clock_drift_ci95_ppm": [-1.26, 25.74],
            "gyro_scale": [1.00123, 1.0, 1.0], "gyro_scale_ci95": [[0.99987, 1.00259], None, None],
            "gyro_misalignment": [0.00456, 0.0, 0.0], "gyro_misalignment_ci95": [[-0.00111, 0.01023], None, None],
            "sensor_model": base}


def _lines(**kw):
    return _result(**kw).summary().split("\n")


def _line(lines, start):
    return next(x for x in lines if x.startswith(start))


def test_summary_of_a_gyros_bias_drift_and_scale_per_axis():
    lines = _lines(sensor_model=_sensor_model())
    bias = _line(lines, "gyro bias (x, y, z)")
    assert "deg/s with 95 % intervals: +0.573 [+0.516, +0.630], -1.146 [-1.203, -1.089], +1.719 [+1.662, +1.776] " \
           "(removed)" in bias
    assert _line(lines, "clock drift:") == "clock drift: +12.3 ppm, 95 % interval [-1.3, +25.7] ppm"
    scale = _line(lines, "gyro scale")
    assert ("with 95 % intervals: 1.0012 [0.9999, 1.0026], 1 (held: not resolved; fitted free, it "
            "lies in [0.9877, 1.0123]), 1 (held: not resolved) (removed)") in scale and scale.endswith("(removed)")
    mis = _line(lines, "gyro misalignment (xy, xz, yz")
    assert ("with 95 % intervals: +0.0046 [-0.0011, +0.0102], 0 (held: not resolved), 0 (held: not resolved) "
            "(removed)") in mis


def test_summary_of_a_sensor_model_says_measured_not_removed_and_unresolved_drift():
    lines = _lines(sensor_model=_sensor_model(bias_applied=False, drift_resolved=False, scale_note="motion too slow"))
    assert _line(lines, "gyro bias (x, y, z)").endswith("(measured, not removed)")
    assert _line(lines, "clock drift:").endswith("[-1.3, +25.7] ppm (not resolved: it includes 0)")
    assert _line(lines, "gyro scale").endswith("(measured, not removed; motion too slow)")
    assert _line(lines, "gyro misalignment").endswith("(measured, not removed)")
    assert not any("removed)" in x and "(removed" in x for x in lines)


def test_summary_of_a_sensor_model_without_bias_drift_scale_or_held_intervals():
    model = _sensor_model()
    model["gyro_bias_rad_s"] = None
    assert _lines(sensor_model=model)[-1] == "gyro bias: not estimated (n)"
    model = _sensor_model(drift_note="beside a clock step")
    model["clock_drift_ppm"] = None
    lines = _lines(sensor_model=model)
    assert "clock drift: beside a clock step" in lines
    del model["sensor_model"]["drift_note"]
    assert "clock drift: not measured" in _lines(sensor_model=model)
    model = _sensor_model(scale_held_ci95=None)
    model["gyro_misalignment"] = None
    lines = _lines(sensor_model=model)
    assert _line(lines, "gyro scale").endswith("1 (held: not resolved), 1 (held: not resolved) (removed)")
    assert not any(x.startswith("gyro misalignment") for x in lines)
    model["gyro_scale"] = None
    assert not any(x.startswith("gyro scale") for x in _lines(sensor_model=model))
    assert not any(x.startswith("gyro") for x in _lines(sensor_model=None))


def _two_disagreeing_segments(**extra):
    segs = [{"start_s": 10.0 * i, "end_s": 10.0 * (i + 1), "p_value": p} for i, p in enumerate((0.5, 1e-9, 0.4, 2e-7))]
    return {"run": True, "segments": segs, "disagreeing": [1, 3], "p_value": 0.0123, "pairs_radius_deg": 0.1234,
            "between_radius_deg": 0.5678, **extra}


def test_summary_names_every_disagreeing_segment_and_each_clock_jump():
    lines = _lines(segments=_two_disagreeing_segments(
        clock_jumps=[{"time_s": 12.34, "size_s": 0.1234, "clock": "camera"}, {"time_s": 30.0, "size_s": -0.004}]))
    assert ("segments: 4 of about 10 s (1 s pairs) disagree: 10.0-20.0 s, 30.0-40.0 s (each by its own test, "
            "p = 1e-09, 2e-07; all the segments together p = 0.012); 95 % radius from the pairs 0.123 deg, from the "
            "spread between segments 0.568 deg") in lines
    assert lines[-2:] == ["clock jump at 12.3 s: +123.4 ms (clock: camera)",
                          "clock jump at 30.0 s: -4.0 ms (clock: sensor)"]


def test_summary_of_use_consistent_gives_the_angle_if_the_part_left_out_is_right():
    used = {"kept_s": 20.0, "pairs_kept": 9, "left_out_spans_s": [[10.0, 20.0]]}
    line = _lines(segments=_two_disagreeing_segments(use={**used, "R0_moves_deg_if_left_out_part_is_right": 1.234},
                                                     consistent_spans_s=[[0.0, 10.0], [20.0, 30.0]]))[-1]
    assert line == ("use='consistent': R0 from 0.0-10.0 s, 20.0-30.0 s (9 pairs; the majority, not known to be right: "
                    "1.23 deg away if the part left out is)")
    line = _lines(segments=_two_disagreeing_segments(use=used))[-1]
    assert line.startswith("use='consistent': R0 from  (9 pairs;") and "right: nan deg away" in line
    assert _lines(segments=_two_disagreeing_segments(use={"kept_s": None}))[-1].startswith("segments: 4 of")


def test_summary_with_two_references_gives_both_angles_their_disagreement_and_the_reading():
    lines = _lines(reference_errors_deg=(0.75, 0.5), reference_disagreement_deg=0.3, reference_error_deg=0.75,
                   reference_reading="both agree with R0 within their floor")
    assert lines[-2:] == ["angle to reference 1: 0.750 deg, to reference 2: 0.500 deg; the references disagree by "
                          "0.300 deg (the reference floor)", "reading: both agree with R0 within their floor"]
    assert not any(x.startswith("angle to the reference:") for x in lines)
