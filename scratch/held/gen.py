"""Synthetic rigs for the red-team-5 probes (camera 20 Hz, gyro 200 Hz unless told), built on
replication.testing.rig_motion; gyro scale, bias, clock steps/drift applied here."""
import sys
import warnings

import numpy as np

from replication.core.so3 import angle_between_deg
from replication.core.so3 import matrix_from_rotation_vector as exp_map
from replication.core.so3 import rotation_vector_from_matrix as log_map
from replication.core.stats import wilson_interval
from replication.rig.calibration import calibrate
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import RIG_R0, rig_motion

FLOOR = 0.343


def make(seed, seconds=40.0, scale=(1, 1, 1), bias=(0, 0, 0), cam_deg=0.05, gyro_deg_s=0.2, R0=RIG_R0,
         offset=0.0, ppm=0.0, rate=200.0, axis=None, rest=None, wobble=0.02, R0t=None):
    """(camera, gyro): rig_motion with random phases; gyro reads scale*omega + bias + noise.
    axis: 'z' -> motion about one camera axis mostly (plus a small wobble); rest: list of (t0, t1) at rest."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)

    def f(t):
        if axis is None:
            M = rig_motion(t, phase)
        else:
            v = np.zeros(np.shape(t) + (3,))
            v[..., 2] = 1.2 * np.sin(0.6 * t + phase[0])
            v[..., 0] = wobble * np.sin(0.9 * t + phase[1])
            v[..., 1] = wobble * np.cos(0.5 * t + phase[2])
            M = exp_map(v)
            if axis == "sx":  # the dominant turn about the sensor's x axis (camera axis R0 e_x)
                P = np.eye(3)[[1, 2, 0]].T  # maps camera z to camera x ... then to the sensor x axis through R0
                Rm = R0 @ P
                M = Rm @ M @ Rm.T
        return M

    def frozen(t):
        t = np.asarray(t, float).copy()
        if rest:
            # time warp: motion stops inside each rest span
            tt = t.copy()
            for a, b in rest:
                tt = np.where(t > a, tt - (np.minimum(t, b) - a), tt)
            return tt
        return t

    t_cam = np.arange(0.0, seconds, 0.05)
    C = f(frozen(t_cam))
    if cam_deg:
        C = C @ exp_map(rng.normal(0.0, np.radians(cam_deg) / np.sqrt(3.0), (len(t_cam), 3)))
    dt = 1.0 / rate
    t_imu = np.arange(-1.0, seconds + 1.0, dt)
    Q = f(frozen(t_imu)) @ (R0 if R0t is None else R0t(t_imu))
    omega = log_map(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / dt
    omega = omega * np.asarray(scale, float) + np.asarray(bias, float)
    if gyro_deg_s:
        omega = omega + rng.normal(0.0, np.radians(gyro_deg_s), omega.shape)
    t = 0.5 * (t_imu[1:] + t_imu[:-1])
    stamps = t + offset + ppm * 1e-6 * (t - 0.5 * seconds)
    return OrientationStream(t_cam, C, "camera"), GyroStream(stamps, omega, "gyro")


def cal(camera, sensor, **kw):
    kw.setdefault("n_bootstrap", 30)
    kw.setdefault("diagnose", False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, sensor, **kw)


def W(k, n):
    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} [{lo:.2f},{hi:.2f}]"


def err(r, R0=RIG_R0):
    return float(angle_between_deg(r.R, R0))


def row(r, R0=RIG_R0):
    d = r.to_dict()
    return dict(level=r.verdict.level, err=err(r, R0), checks=[x.check for x in r.verdict.reasons],
                scale=d.get("gyro_scale"), scale_ci=d.get("gyro_scale_ci95"), bias=d.get("gyro_bias_rad_s"),
                jumps=(d.get("segments") or {}).get("clock_jumps"))


def lie(r, R0=RIG_R0):
    return r.verdict.level == "ok" and err(r, R0) > FLOOR
