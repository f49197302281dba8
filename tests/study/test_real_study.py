"""The studies of the real recordings (replication.study.real_study) on a synthetic rig whose R0
is known."""
import math

import numpy as np
import pytest

from replication.core import so3
from replication.rig.streams import OrientationStream
from replication.study.real_study import (
    calibration_table,
    calibrations,
    protocol_table,
    sensitivity_table,
    solver_tables,
)

# ------------------------------------------------------------------------------------------------
# real-data studies

@pytest.fixture(scope="module")
def synthetic_rig():
    """A camera stream and a sensor stream of the same rigid motion, sensor = camera rotated by R0
    (no noise)."""
    rng = np.random.default_rng(5)
    R0 = so3.random_rotations(rng, ())
    t = np.arange(0.0, 40.0, 0.05)
    w = np.stack([np.sin(0.7 * t), np.sin(0.45 * t + 1.0), np.cos(0.3 * t)], axis=-1)
    world_from_camera = so3.matrix_from_rotation_vector(w)
    camera = OrientationStream(t, world_from_camera, "camera")
    sensor = OrientationStream(t, world_from_camera @ R0, "sensor")  # world_from_sensor = world_from_camera R0
    return R0, camera, sensor


def test_real_studies_recover_a_known_r0_and_shape_their_tables(synthetic_rig):
    R0, camera, sensor = synthetic_rig
    streams, refs = {"rig": (camera, sensor, "truth")}, {"truth": R0}
    C = np.swapaxes(camera.R[::40], -1, -2)  # body_from_world attitudes of 20 static poses
    poses = {"poses": (C, np.swapaxes(sensor.R[::40], -1, -2), "truth")}
    head = calibration_table(calibrations(streams, poses, refs, ("chordal_optimal",), seed=1))
    assert list(head.index) == [("rig", "chordal_optimal"), ("poses", "chordal_optimal")]
    # noise-free streams, interpolated between samples: errors measured up to 2.3e-7 deg
    assert (head["error_deg"] < 1e-5).all() and np.isnan(head.loc[("poses", "chordal_optimal"), "offset_ms"])
    solvers = solver_tables(streams, {}, refs)
    assert list(solvers.columns) == ["error_deg", "n_pairs", "warnings", "seconds"]
    assert solvers.loc[("rig", "chordal_optimal"), "error_deg"] < 1e-5
    assert solvers.loc[("rig", "opencv_park"), "n_pairs"] < solvers.loc[("rig", "chordal_optimal"), "n_pairs"]
    proto = protocol_table(streams, refs, intervals=(1.0,))
    assert proto.index.names == ["data", "interval (s)"] and proto.loc[("rig", 1.0), "default: error (deg)"] < 1e-5
    sens = sensitivity_table(camera, sensor, R0, intervals=(0.5,), shares=(0.5,), methods=("chordal_optimal",),
                             n_bootstrap=5, seed=1)
    assert len(sens) == 2 and (sens["error_deg"] < 1e-5).all()


def test_the_floor_table_reads_within_beyond_and_one_reference():
    from types import SimpleNamespace

    from replication.study.real_study import reference_floor_table

    ref_a, ref_b = np.eye(3), so3.matrix_from_rotation_vector(np.radians([0.0, 0.0, 0.3]))  # 0.3 deg apart: the floor

    def at(deg):  # an estimate turned about x, off both references' z-axis disagreement
        return SimpleNamespace(R=so3.matrix_from_rotation_vector(np.radians([deg, 0.0, 0.15])))

    results = {("inside", "m"): at(0.25), ("outside", "m"): at(0.27), ("robot", "m"): at(0.0)}
    table = reference_floor_table(results, {"inside": "rig", "outside": "rig", "robot": "arm"},
                                  {"rig": {"a": ref_a, "b": ref_b}, "arm": {"a": ref_a}})
    assert table.loc[("inside", "m"), "references apart (deg)"] == pytest.approx(0.3)
    assert table.loc[("inside", "m"), "to a (deg)"] == pytest.approx(math.hypot(0.25, 0.15), rel=1e-4)
    assert table.loc[("inside", "m"), "reading"] == "within the floor"  # 0.2915 deg from each, below 0.3
    assert table.loc[("outside", "m"), "reading"] == "beyond the floor"  # 0.3089 deg from each, above 0.3
    assert table.loc[("robot", "m"), "reading"] == "one reference"
    assert math.isnan(table.loc[("robot", "m"), "to b (deg)"]) and math.isnan(table.loc[("robot", "m"),
                                                                                         "references apart (deg)"])
