"""Orientation and gyro streams: the cached slerp, the world_from_body field, gyro integration, a
light import."""
import dataclasses
import subprocess
import sys

import numpy as np
import pytest
import scipy.spatial.transform as sst

from conftest import NUMPY_REPR
from replication.core import so3
from replication.rig import streams
from replication.rig.live import LiveRig
from replication.rig.online import OnlineCalibrator
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro


@pytest.fixture
def stream(rng):
    t = np.sort(rng.uniform(0.0, 10.0, 50))
    return OrientationStream(t, so3.random_rotations(rng, 50), "test")


def test_at_is_bit_identical_to_a_fresh_slerp_and_builds_it_once(stream, rng, monkeypatch):
    times = rng.uniform(stream.t[0], stream.t[-1], 200)
    expected = sst.Slerp(stream.t, sst.Rotation.from_matrix(stream.R))(times).as_matrix()
    built = []

    class CountingSlerp(sst.Slerp):
        def __init__(self, *args, **kwargs):
            built.append(1)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(sst, "Slerp", CountingSlerp)
    first = stream.at(times)
    second = stream.at(times[::-1])
    assert np.array_equal(first, expected) and np.array_equal(second, expected[::-1])
    assert len(built) == 1  # the second call used the first's interpolator
    np.testing.assert_allclose(stream.at(stream.t), stream.R, rtol=0, atol=1e-14)  # at the samples: the samples
    assert np.array_equal(first, so3.slerp(stream.t, stream.R, times))


def test_the_cache_is_not_part_of_the_value(stream):
    stream.at(stream.t[1:3])
    assert "_interpolator" not in repr(stream)
    copy = dataclasses.replace(stream)
    assert copy._interpolator is None and copy.world_from_body is stream.world_from_body
    part = stream.between(stream.t[5], stream.t[20])
    assert part._interpolator is None and len(part.t) == 16


def test_R_is_world_from_body_and_read_only(stream, rng):
    assert stream.R is stream.world_from_body
    same = OrientationStream(t=stream.t, world_from_body=stream.R, source="kw")
    assert np.array_equal(same.R, stream.R)
    with pytest.raises(AttributeError, match="cannot assign to field 'R'"):
        stream.R = so3.random_rotations(rng, 50)
    with pytest.raises(dataclasses.FrozenInstanceError, match="cannot assign to field 'world_from_body'"):
        stream.world_from_body = stream.R
    with pytest.raises(ValueError, match="not a rotation matrix"):
        OrientationStream(stream.t, 2 * stream.R)
    with pytest.raises(ValueError, match="not strictly increasing at sample 1"):
        OrientationStream([0.0, 0.0], stream.R[:2])


def test_integrate_gyro_of_a_constant_rate_is_exp_of_w_t():
    t = np.linspace(0.0, 2.0, 401) ** 1.5  # uneven steps
    w = np.array([0.3, -0.2, 0.5])
    Q = integrate_gyro(GyroStream(t, np.tile(w, (len(t), 1)), "imu"))
    assert isinstance(Q, OrientationStream) and Q.source == "integrated imu"
    assert np.array_equal(Q.R[0], np.eye(3))
    np.testing.assert_allclose(Q.R, so3.matrix_from_rotation_vector(t[:, None] * w), rtol=0, atol=1e-13)


def test_gyro_stream_validation():
    with pytest.raises(ValueError, match="NaN or inf"):
        GyroStream([0.0, 1.0], [[0, 0, 0], [0, np.nan, 0]])
    with pytest.raises(ValueError, match=r"omega of shape \(N, 3\)"):
        GyroStream([0.0, 1.0], [[0, 0], [0, 0]])


def test_importing_streams_loads_no_solver_and_no_optimiser():
    code = ("import sys, replication.rig.streams as s; import numpy as np; "
            "s.OrientationStream([0.0, 1.0], np.stack([np.eye(3)] * 2)).at([0.5]); "
            "bad = [m for m in sys.modules if m.startswith(('scipy.optimize', 'replication.core.solvers', "
            "'replication.rig.calibration', 'replication.core.handeye'))]; print(bad)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    assert streams.__name__ == "replication.rig.streams"


def test_integrate_gyro_constant_rate():
    t = np.linspace(0.0, 1.0, 201)
    g = GyroStream(t, np.tile([0.0, 0.0, 0.5], (201, 1)))
    Q = integrate_gyro(g).R
    np.testing.assert_allclose(so3.rotation_angle_deg(Q[-1]), np.degrees(0.5), atol=1e-9)
    np.testing.assert_allclose(Q[-1][:2, :2], [[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]], atol=1e-12)


def test_refusals_of_time_stamps_carry_no_numpy_reprs():
    """Streams and the live front end refuse time going back; the numbers in their messages are
    plain."""
    t = np.array([0.0, 0.5, 0.5, 1.0])
    messages = []
    for build in (lambda: OrientationStream(t, np.tile(np.eye(3), (4, 1, 1)), "s"),
                  lambda: GyroStream(t, np.zeros((4, 3)), "g")):
        with pytest.raises(ValueError) as err:
            build()
        messages.append(str(err.value))
    live = LiveRig(OnlineCalibrator(), interval=1.0)
    live.add_camera(np.float64(1.0), np.eye(3))
    with pytest.raises(ValueError) as err:
        live.add_camera(np.float64(0.5), np.eye(3))
    messages.append(str(err.value))
    live.add_orientation(np.float64(1.0), np.eye(3))
    with pytest.raises(ValueError) as err:
        live.add_orientation(np.float64(1.0), np.eye(3))
    messages.append(str(err.value))
    with pytest.raises(ValueError) as err:
        live.add_gyro(2.0, np.array([np.nan, 0.0]))
    messages.append(str(err.value))
    assert all(not NUMPY_REPR.search(m) for m in messages), messages
    assert "0.5 after 1.0" in messages[2] and "1.0 after 1.0" in messages[3]
