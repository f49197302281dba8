"""The input-mistake diagnosis (:mod:`replication.rig.diagnose`) at its boundaries, with a stand-in calibration whose
residual per hypothesis the test sets: which mistakes are tried on which streams and how each is undone, when a
hypothesis fits (strictly below both shares), which fits tie, how a reference splits a tie, and the sentence.
Mutation testing (scripts/mutation) found these rules unguarded by the fast tests."""
from types import SimpleNamespace

import numpy as np
import pytest

from replication.core import so3
from replication.rig import diagnose
from replication.rig.diagnose import FIT_SHARE, FIT_TO_MOTION, POSE_FIT_SHARE, TIE_ATOL, TIE_SHARE
from replication.rig.quality import THRESHOLDS
from replication.rig.streams import GyroStream, OrientationStream

RNG = np.random.default_rng(3)
T = np.arange(6) * 0.1
CAM = OrientationStream(T, so3.random_rotations(RNG, 6), "cam")
ORI = OrientationStream(T, so3.random_rotations(RNG, 6), "ori")
GYRO = GyroStream(T, RNG.standard_normal((6, 3)), "gyro")
BASE, MOTION = 10.0, 30.0


class FakeCalibrate:
    """Records each call; returns the residual, motion, R and correlation set for the hypothesis at that call."""

    def __init__(self, residuals, motion=MOTION, R=None, raise_at=()):
        self.residuals, self.motion, self.R, self.raise_at, self.calls = residuals, motion, R or {}, raise_at, []

    def __call__(self, camera, sensor, **kwargs):
        k = len(self.calls)
        self.calls.append((camera, sensor, kwargs))
        if k in self.raise_at:
            raise ValueError("refused")
        return SimpleNamespace(residual_deg={"median": self.residuals.get(k, BASE)},
                               diagnostics={"motion_median_deg": self.motion}, R=self.R.get(k, np.eye(3)),
                               time_offset_correlation=0.5 + k / 100)


def _run(sensor, fake, reference=None):
    return diagnose.input_mistakes(CAM, sensor, base_residual_deg=BASE, motion_deg=MOTION, interval=0.7,
                                   max_offset=0.3, calibrate=fake, reference=reference)


def _q(stream):
    return so3.quaternion_from_matrix(stream.world_from_body)


def test_each_hypothesis_is_undone_on_orientation_streams():
    fake = FakeCalibrate({})
    assert _run(ORI, fake) == []
    assert len(fake.calls) == 7  # every hypothesis but the gyro units
    for camera, sensor, kwargs in fake.calls:
        assert kwargs == {"interval": 0.7, "max_offset": 0.3, "n_bootstrap": 0, "diagnose": False}
        assert np.array_equal(camera.t, T) and np.array_equal(sensor.t, T)
        assert camera.source == "cam" and sensor.source == "ori"
    cams = [c for c, _, _ in fake.calls]
    sens = [s for _, s, _ in fake.calls]
    assert np.allclose(_q(cams[0]), so3.quaternion_from_matrix(so3.matrix_from_quaternion(_q(CAM)[:, [1, 2, 3, 0]])))
    assert np.allclose(_q(cams[1]), so3.quaternion_from_matrix(so3.matrix_from_quaternion(_q(CAM)[:, [3, 0, 1, 2]])))
    assert np.allclose(cams[2].world_from_body, np.swapaxes(CAM.world_from_body, -1, -2))
    for k in (0, 1, 2):
        assert sens[k] is ORI
    for k in (3, 4, 5):
        assert cams[k] is CAM
    assert np.allclose(_q(sens[3]), so3.quaternion_from_matrix(so3.matrix_from_quaternion(_q(ORI)[:, [1, 2, 3, 0]])))
    assert np.allclose(_q(sens[4]), so3.quaternion_from_matrix(so3.matrix_from_quaternion(_q(ORI)[:, [3, 0, 1, 2]])))
    assert np.allclose(sens[5].world_from_body, np.swapaxes(ORI.world_from_body, -1, -2))
    assert np.allclose(cams[6].world_from_body, np.swapaxes(CAM.world_from_body, -1, -2))
    assert np.allclose(sens[6].world_from_body, np.swapaxes(ORI.world_from_body, -1, -2))


def test_each_hypothesis_is_undone_on_a_gyro_stream():
    fake = FakeCalibrate({})
    _run(GYRO, fake)
    assert len(fake.calls) == 4  # camera orders, camera direction, gyro units
    for _, sensor, _ in fake.calls[:3]:
        assert sensor is GYRO
    camera, sensor, _ = fake.calls[3]
    assert camera is CAM and isinstance(sensor, GyroStream) and sensor.source == "gyro"
    assert np.allclose(sensor.omega, np.radians(GYRO.omega)) and np.array_equal(sensor.t, T)


def test_a_hypothesis_fits_only_strictly_below_both_shares():
    # FIT_SHARE of the base residual (2.0 deg) and FIT_TO_MOTION of the motion (3.0 deg): the stricter one rules
    at_share = FIT_SHARE * BASE
    assert _run(ORI, FakeCalibrate({0: at_share})) == []
    (r,) = _run(ORI, FakeCalibrate({0: at_share * (1 - 1e-9)}))
    assert (r.check, r.level, r.threshold) == ("input_mistake", "fail", BASE)
    assert r.measured == pytest.approx(at_share * (1 - 1e-9))
    at_motion = 1.5  # with a motion of 15 deg the motion share is the stricter: 1.5 deg
    assert _run(ORI, FakeCalibrate({0: at_motion}, motion=at_motion / FIT_TO_MOTION)) == []
    assert _run(ORI, FakeCalibrate({0: at_motion * (1 - 1e-9)}, motion=at_motion / FIT_TO_MOTION)) != []


def test_a_refused_hypothesis_is_skipped():
    fake = FakeCalibrate({0: 0.1, 1: 0.1}, raise_at=(0,))
    (r,) = _run(ORI, fake)
    assert len(fake.calls) == 7
    assert "the camera file holds quaternions in (x, y, z, w) order read as (w, x, y, z)" in r.message
    assert "(w, x, y, z) order read as (x, y, z, w)" not in r.message


def test_the_sentence_names_the_mistake_the_residuals_and_the_correlation():
    (r,) = _run(ORI, FakeCalibrate({5: 0.25}))
    assert r.measured == 0.25
    assert r.message == ("likely input mistake: the sensor file holds sensor_from_world poses where world_from_sensor "
                         "belongs; with that undone the median pair residual falls from 10 deg to 0.25 deg (median "
                         "motion 30 deg) and the time-offset correlation is 0.550")


def test_ties_within_the_share_plus_the_atol_are_named_together_in_the_fixed_order():
    best = 0.5
    edge = TIE_SHARE * best + TIE_ATOL
    # hypotheses 6 (best), 2 (exactly at the tie edge), 0 (just beyond it): 2 and 6 named, in HYPOTHESES order
    (r,) = _run(ORI, FakeCalibrate({6: best, 2: edge, 0: edge * (1 + 1e-9)}))
    assert r.message.startswith("likely input mistake: the camera file holds camera_from_world poses where "
                                "world_from_camera belongs, or the camera and sensor file holds inverted poses "
                                "(body_from_world) in both: the data cannot tell which; a reference can; with that "
                                "undone the median pair residual falls from 10 deg to 0.5 deg")
    assert r.measured == best
    assert "time-offset correlation is 0.520" in r.message  # the first named hypothesis's correlation
    # exact fits (noise-free): residuals within TIE_ATOL tie whatever their ratio
    (r,) = _run(ORI, FakeCalibrate({1: 1e-14, 4: TIE_ATOL}))
    assert ", or " in r.message
    (r,) = _run(ORI, FakeCalibrate({1: 1e-14, 4: TIE_ATOL * 1.01}))
    assert ", or " not in r.message and "(x, y, z, w) order read as (w, x, y, z)" in r.message


def test_a_reference_tells_tied_hypotheses_apart_at_the_fail_bound():
    bound = THRESHOLDS["reference_error_deg"][1]
    ref = np.eye(3)
    at = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, np.radians(bound)]))
    beyond = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, np.radians(bound * 1.001)]))
    far = so3.matrix_from_rotation_vector(np.array([0.0, np.radians(90.0), 0.0]))
    # two tied: the one at exactly the bound agrees with the reference, the far one does not
    (r,) = _run(ORI, FakeCalibrate({0: 0.5, 3: 0.5}, R={0: far, 3: at}), reference=ref)
    assert r.message.startswith("likely input mistake: the sensor file holds quaternions in (w, x, y, z) order read "
                                "as (x, y, z, w); the reference tells them apart: the camera file holds quaternions "
                                "in (w, x, y, z) order read as (x, y, z, w) 90 deg from it, the sensor file holds "
                                "quaternions in (w, x, y, z) order read as (x, y, z, w) 5 deg from it; with that "
                                "undone")
    # none agrees, or all agree: the tie stands, no note
    for R in ({0: far, 3: beyond}, {0: at, 3: at}):
        (r,) = _run(ORI, FakeCalibrate({0: 0.5, 3: 0.5}, R=R), reference=ref)
        assert "the reference tells them apart" not in r.message and ": the data cannot tell which" in r.message
    # a single fit: no note even with a reference that disagrees
    (r,) = _run(ORI, FakeCalibrate({0: 0.5}, R={0: far}), reference=ref)
    assert r.message.startswith("likely input mistake: the camera file holds quaternions in (w, x, y, z) order read "
                                "as (x, y, z, w); with that undone")


class FakePoses:
    def __init__(self, residuals, raise_at=()):
        self.residuals, self.raise_at, self.calls = residuals, raise_at, []

    def __call__(self, C, S, **kwargs):
        k = len(self.calls)
        self.calls.append((C, S, kwargs))
        if k in self.raise_at:
            raise ValueError("refused")
        return SimpleNamespace(residual_deg={"median": self.residuals.get(k, BASE)}, R=np.eye(3))


def _poses(fake):
    C, S = so3.random_rotations(RNG, 4), so3.random_rotations(RNG, 4)
    out = diagnose.pose_direction(C, S, base_residual_deg=BASE, pairs="all", min_motion_deg=2.0, calibrate_poses=fake)
    return C, S, out


def test_pose_direction_tries_each_side_inverted_and_fits_below_the_share():
    fake = FakePoses({})
    C, S, out = _poses(fake)
    assert out == [] and len(fake.calls) == 2
    (c0, s0, kw), (c1, s1, _) = fake.calls
    assert kw == {"pairs": "all", "min_motion_deg": 2.0, "n_bootstrap": 0, "diagnose": False}
    assert np.allclose(c0, np.swapaxes(C, -1, -2)) and s0 is S and c1 is C and np.allclose(s1, np.swapaxes(S, -1, -2))
    assert _poses(FakePoses({1: POSE_FIT_SHARE * BASE}))[2] == []
    (r,) = _poses(FakePoses({1: POSE_FIT_SHARE * BASE * (1 - 1e-9)}))[2]
    assert (r.check, r.level, r.threshold) == ("input_mistake", "fail", BASE)
    assert r.message.startswith("likely input mistake: robot poses inverted (base_from_hand where hand_from_base "
                                "belongs); with that undone the median pair residual falls from 10 deg to 6 deg")
    (r,) = _poses(FakePoses({0: 1.0, 1: 1.0}, raise_at=(0,)))[2]
    assert r.message.startswith("likely input mistake: robot poses inverted")
    (r,) = _poses(FakePoses({0: 1.0, 1: 1.0}))[2]
    assert r.message.startswith("likely input mistake: camera poses inverted (target_from_camera where "
                                "camera_from_target belongs), or robot poses inverted")
    assert r.measured == 1.0
