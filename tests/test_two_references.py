"""Two references (issue 35.4): ``calibrate(reference=<two>)`` and ``calibrate --reference A --reference B`` report
the error to each, their disagreement (the reference floor) and which reading applies; one reference works as
before."""
from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from replication.__main__ import main
from replication.core import so3
from replication.rig.calibration import calibrate
from replication.rig.estimate import reference_reading
from replication.rig.poses import calibrate_poses
from replication.study.simulation import rig_streams
from replication.testing import write_euroc_imu, write_tum_trajectory

SCHEMA = json.loads((Path(__file__).resolve().parents[1] / "docs" / "calibration_report.schema.json").read_text())
EPS = 1e-9


def _turned(R, deg, axis=(1.0, 0.0, 0.0)):
    return R @ so3.matrix_from_rotation_vector(np.radians(deg) * np.asarray(axis))


@pytest.fixture(scope="module")
def rig():
    R0, camera, gyro, _ = rig_streams(40.0, rng=np.random.default_rng(35), camera_noise_deg=0.02)
    return R0, camera, gyro


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
    ((0.5, 9.5), 10.0, 0.1, "closer to reference 1"),                   # red team: was "agreement, not accuracy"
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


def test_two_references_in_the_result_the_report_and_the_summary(rig):
    R0, camera, gyro = rig
    refs = np.stack([_turned(R0, 0.15), _turned(R0, -0.15)])  # 0.3 deg apart, the estimate between them
    r = calibrate(camera, gyro, n_bootstrap=20, reference=refs)
    e1, e2 = r.reference_errors_deg
    assert r.reference_disagreement_deg == pytest.approx(0.3, abs=1e-9)
    assert r.reference_error_deg == e1 and max(e1, e2) < 0.3  # the first stays the single error
    assert r.reference_reading.startswith("agreement, not accuracy")
    report = json.loads(json.dumps(r.to_dict(), allow_nan=False))
    jsonschema.validate(report, SCHEMA)
    assert report["reference_errors_deg"] == [e1, e2] and report["reference_disagreement_deg"] == pytest.approx(0.3)
    assert report["reference_reading"] == r.reference_reading
    assert np.allclose(report["inputs"]["reference_camera_from_sensor"], refs[0], atol=1e-12)
    assert np.allclose(report["inputs"]["second_reference_camera_from_sensor"], refs[1], atol=1e-12)
    lines = r.summary().split("\n")
    assert f"angle to reference 1: {e1:.3f} deg, to reference 2: {e2:.3f} deg; the references disagree by 0.300 deg " \
           "(the reference floor)" in lines
    assert any(line.startswith("reading: agreement, not accuracy") for line in lines)
    assert not any(line.startswith("angle to the reference:") for line in lines)


def test_one_reference_works_as_before(rig):
    R0, camera, gyro = rig
    r = calibrate(camera, gyro, n_bootstrap=0, reference=_turned(R0, 0.15))
    assert r.reference_errors_deg is None and r.reference_disagreement_deg is None and r.reference_reading is None
    report = r.to_dict()
    jsonschema.validate(json.loads(json.dumps(report)), SCHEMA)
    assert report["reference_errors_deg"] is None and "second_reference_camera_from_sensor" not in report["inputs"]
    assert f"angle to the reference: {r.reference_error_deg:.3f} deg" in r.summary().split("\n")
    assert np.allclose(report["inputs"]["reference_camera_from_sensor"], _turned(R0, 0.15), atol=1e-12)


@pytest.mark.parametrize("second_deg, level", [(0.9, None), (1.1, "warning"), (5.1, "fail")])
def test_the_second_reference_is_judged_as_the_first(rig, second_deg, level):
    R0, camera, gyro = rig
    r = calibrate(camera, gyro, n_bootstrap=0, reference=np.stack([R0, _turned(R0, second_deg, (0.0, 0.6, 0.8))]))
    reasons = {x.check: x for x in r.verdict.reasons}
    assert "reference_error_deg" not in reasons
    if level is None:
        assert "second_reference_error_deg" not in reasons
        return
    reason = reasons["second_reference_error_deg"]
    assert reason.level == level and reason.message.startswith("angle to the second reference ")
    assert r.reference_reading.startswith("closer to reference 1")


def test_two_references_for_static_poses_and_bad_shapes(rig):
    R0, camera, _ = rig
    C = np.swapaxes(camera.R[::40], -1, -2)
    S = np.swapaxes(camera.R[::40] @ R0, -1, -2)
    r = calibrate_poses(C, S, n_bootstrap=0, reference=np.stack([_turned(R0, 0.1), _turned(R0, -0.1)]))
    assert r.reference_disagreement_deg == pytest.approx(0.2) and len(r.reference_errors_deg) == 2
    with pytest.raises(ValueError, match=r"got shape \(3, 3, 3\) \(two references, e.g. two published"):
        calibrate_poses(C, S, n_bootstrap=0, reference=np.stack([R0] * 3))


def _camchain(path, R):
    T = np.eye(4)
    T[:3, :3] = R
    path.write_text("cam0:\n  T_cam_imu:\n" + "".join(f"  - {row.tolist()}\n" for row in T))
    return path




def test_cli_takes_reference_twice_not_three_times(rig, tmp_path, capsys):
    from replication.rig.streams import GyroStream, OrientationStream

    R0, camera, gyro = rig
    write_tum_trajectory(tmp_path / "cam.txt", OrientationStream(camera.t + 1e3, camera.R, "c"))
    write_euroc_imu(tmp_path / "imu.csv", GyroStream(gyro.t + 1e3, gyro.omega, "g"))
    a, b = _camchain(tmp_path / "a.yaml", _turned(R0, 0.15)), _camchain(tmp_path / "b.yaml", _turned(R0, -0.15))
    base = ["calibrate", "--camera", tmp_path / "cam.txt", "--sensor", tmp_path / "imu.csv", "--sensor-kind", "gyro",
            "--bootstrap", "0", "--quiet"]
    out, fig = tmp_path / "r.json", tmp_path / "r.png"
    assert main([str(x) for x in base + ["--reference", a, "--reference", b, "--out", out, "--plot", fig]]) == 0
    text = capsys.readouterr().out
    assert "angle to reference 1: " in text and "the references disagree by 0.300 deg (the reference floor)" in text
    assert "reading: agreement, not accuracy" in text
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["files"]["reference"]["sha256"] != report["files"]["reference2"]["sha256"]
    assert report["files"]["reference2"]["camera_entry"] == "cam0"
    assert report["reference_disagreement_deg"] == pytest.approx(0.3, abs=1e-6) and fig.stat().st_size > 1000
    assert main([str(x) for x in base + ["--reference", a, "--out", out]]) == 0  # once: as before
    report = json.loads(out.read_text())
    assert "reference2" not in report["files"] and report["reference_errors_deg"] is None
    assert "angle to the reference: " in capsys.readouterr().out
    assert main([str(x) for x in base + ["--reference", a, "--reference", b, "--reference", a]]) == 2
    assert "--reference given 3 times: at most two (two published calibrations)" in capsys.readouterr().err
    assert main([str(x) for x in base + ["--reference", a, "--reference", tmp_path / "missing.yaml"]]) == 2
    assert "--reference (the second)" in capsys.readouterr().err


def test_figure_states_both_references_and_the_reading(rig):
    import matplotlib.pyplot as plt

    R0, camera, gyro = rig
    r = calibrate(camera, gyro, n_bootstrap=0, reference=np.stack([_turned(R0, 0.15), _turned(R0, -0.15)]))
    fig = r.plot(reference_name="a.yaml and b.yaml")
    text = " ".join(" ".join(t.get_text() for ax in fig.axes for t in ax.texts).split())
    assert "reference 1 (a.yaml): quaternion" in text and "reference 2 (b.yaml): quaternion" in text
    assert f"angle between R0 and it: {r.reference_errors_deg[1]:.3f} deg" in text
    assert "reading: agreement, not accuracy" in text
    plt.close(fig)
