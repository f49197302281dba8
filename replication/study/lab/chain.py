"""The experiment's processing chain (Sec. III-B): attitudes from raw samples, motions, calibration,
Table II. Theory and measured numbers: ``docs/studies.md``, section
``replication.study.lab.chain``."""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import cv2
import numpy as np
import pandas as pd

from ...core.handeye import relative_rotations
from ...core.so3 import (
    angle_between_deg,
    matrix_from_quaternion,
    nearest_rotation,
    rotation_vector_from_matrix,
    yaw_pitch_roll_deg_from_matrix,
)
from ...core.solvers import ReplicationWarning, solve
from ...rig.streams import OrientationStream
from ..table2 import attitude_statistics
from .fastchain import _gauss_newton_pnp, ecompass_attitudes, madgwick_marg, refine_camera_orientations
from .recording import ACC_COLUMNS, GYR_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, LabRecording, marker_pixels
from .settings import TABLE2_SOLVERS

__all__ = ["camera_orientations", "camera_poses", "static_sensor_orientations", "dynamic_sensor_orientations",
           "static_motions", "LabResult", "run_lab"]


def camera_orientations(uv, rig, *, refine: str = "opencv") -> np.ndarray:
    """Camera attitudes ``C = camera_from_wand`` from marker pixels by PnP (the paper's ref. [38]).

    Parameters
    ----------
    uv : array_like, shape (M, N, 2)
        Pixels of the N wand markers in M images (distorted, as detected).
    rig : dict
        ``camera_matrix``, ``dist_coeffs``, ``wand_points`` (see :class:`LabRecording`).
    refine : {"opencv", "batched"}
        How the SQPnP solution is refined to the least reprojection error: ``cv2.solvePnPRefineLM``
        image by image, or Gauss-Newton on all images at once
        (:mod:`replication.study.lab.fastchain`: the same minimum to about 1e-6 deg,
        ``tests/study/test_lab_claims.py``; faster on many images).

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
        ``C_t`` (body-from-world, the wand frame being the camera's world).

    Raises
    ------
    ValueError
        If PnP fails or leaves a reprojection error above 5 px (wrong intrinsics,
        marker order or units).
    """
    return camera_poses(uv, rig, refine=refine)[0]


def camera_poses(uv, rig, *, refine: str = "opencv"):
    """:func:`camera_orientations` with the translations: ``(C, t)``, shapes (M, 3, 3) and (M, 3),
    ``x = C X + t``."""
    if refine not in ("opencv", "batched"):
        raise ValueError(f"refine must be 'opencv' or 'batched', got {refine!r}")
    K = np.asarray(rig["camera_matrix"], dtype=float)
    dist = np.asarray(rig["dist_coeffs"], dtype=float)
    X = np.asarray(rig["wand_points"], dtype=float)
    uv = np.ascontiguousarray(uv, dtype=float)
    out, trans = np.empty((len(uv), 3, 3)), np.empty((len(uv), 3))
    for m, x in enumerate(uv):
        ok, rvec, tvec = cv2.solvePnP(X, x, K, dist, flags=cv2.SOLVEPNP_SQPNP)
        if ok and refine == "opencv":
            rvec, tvec = cv2.solvePnPRefineLM(X, x, K, dist, rvec, tvec)
            proj, _ = cv2.projectPoints(X, rvec, tvec, K, dist)
            rms = float(np.sqrt(np.mean(np.sum((proj[:, 0] - x) ** 2, axis=-1))))
        if not ok or (refine == "opencv" and rms > 5.0):
            raise ValueError(f"image {m}: PnP failed (reprojection RMS {rms if ok else float('nan'):.3g} px); "
                             "check the intrinsics, the marker order and that pixels are in px")
        out[m] = cv2.Rodrigues(rvec)[0]
        trans[m] = tvec[:, 0]
    if refine == "batched":
        out, trans = _gauss_newton_pnp(uv, X, K, dist, out, trans, iterations=4)
    return out, trans


def static_sensor_orientations(acc, mag) -> np.ndarray:
    """Sensor attitudes ``I = sensor_from_world`` from accelerometer + magnetometer (static).

    Uses ``ahrs.common.orientation.ecompass`` (ENU): the world's z axis is the measured
    specific force (up), x the horizontal part of the field.

    Parameters
    ----------
    acc, mag : array_like, shape (M, 3)
        Mean accelerometer (m/s^2) and magnetometer (any unit) vectors, sensor frame.

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
        ``I_t`` (body-from-world).
    """
    from ahrs.common.orientation import ecompass

    acc, mag = np.asarray(acc, dtype=float), np.asarray(mag, dtype=float)
    # ecompass returns the world_from_sensor matrix; I_t is its transpose
    Q = np.array([ecompass(a, m, frame="ENU", representation="rotmat") for a, m in zip(acc, mag)])
    return np.swapaxes(Q, -1, -2)


def dynamic_sensor_orientations(imu: pd.DataFrame, rate_hz: float, *, madgwick: str = "ahrs") -> OrientationStream:
    """The moving node's orientation from a Madgwick MARG filter, as a ``world_from_body`` stream.

    ``ahrs.filters.Madgwick`` (S. Madgwick, "An efficient orientation filter for
    inertial and inertial/magnetic sensor arrays", 2010) with its default MARG gain
    0.041, started by ``ecompass`` on the first sample. Its quaternions ``(w, x, y, z)`` rotate
    sensor vectors into its world: they are the stream's ``world_from_body`` as they come
    (``I_t`` of eq. (1) is their transpose).

    Parameters
    ----------
    imu : DataFrame
        ``t`` and the IMU columns.
    rate_hz : float
    madgwick : {"ahrs", "transcribed"}
        ``ahrs``' filter, or :func:`~replication.study.lab.fastchain.madgwick_marg` (the same
        filter, faster: the seed studies).

    Returns
    -------
    OrientationStream
        At the IMU times ``imu["t"]``.
    """
    gyr, acc, mag = (imu[c].to_numpy() for c in (GYR_COLUMNS, ACC_COLUMNS, MAG_COLUMNS))
    if madgwick == "ahrs":
        from ahrs.filters import Madgwick

        q = Madgwick(gyr=gyr, acc=acc, mag=mag, frequency=rate_hz).Q
    elif madgwick == "transcribed":
        q = madgwick_marg(gyr, acc, mag, rate_hz)
    else:
        raise ValueError(f"madgwick must be 'ahrs' or 'transcribed', got {madgwick!r}")
    return OrientationStream(imu["t"].to_numpy(), matrix_from_quaternion(q), "Madgwick")


def _chordal_mean(R):
    return nearest_rotation(np.sum(R, axis=-3))


def static_motions(recording: LabRecording, *, sample: str = "mean") -> dict:
    """Camera and sensor relative rotations of each static data set (the paper's protocol).

    At each static orientation the *mean* of the measurements is used (Sec. III-B, "to increase the
    signal-to-noise ratio"): the mean marker pixels give one PnP attitude ``C_t``, the mean
    accelerometer and magnetometer vectors one ``I_t``. Consecutive orientations give the motions
    ``Delta R_c = C_{t+1} C_t^T`` and ``Delta R_i = I_{t+1} I_t^T`` (eqs. (3)-(4)).

    Parameters
    ----------
    recording : LabRecording
    sample : {"mean", "single", "all"}
        ``"mean"``: the paper's protocol; ``"single"``: the first sample of each orientation
        instead; ``"all"``: every measurement, the alternative the paper names ("instead of using
        all the measurements"): each IMU sample gives its own ``I``
        (:func:`~replication.study.lab.fastchain.ecompass_attitudes`) and is paired with the camera
        frame at or before its time (its own ``C``,
        :func:`~replication.study.lab.fastchain.refine_camera_orientations` from the PnP pose of the
        mean pixels); the ``j``-th pair of an orientation and the ``j``-th of the next give one
        motion, so each pair of consecutive orientations gives as many motions as it has samples
        (the fewer of the two), weighted alike.

    Returns
    -------
    dict
        set id -> ``(A, B)``, each of shape (motions, 3, 3): ``poses - 1`` motions, or with
        ``"all"`` the sum over consecutive orientations of their samples.
    """
    if sample not in ("mean", "single", "all"):
        raise ValueError(f"sample must be 'mean', 'single' or 'all', got {sample!r}")
    n = len(recording.rig["wand_points"])
    if sample == "all":
        return _all_sample_motions(recording, n)
    reduce = (lambda g: g.mean()) if sample == "mean" else (lambda g: g.first())
    C = camera_orientations(marker_pixels(reduce(recording.static_markers.groupby(["set", "pose"])), n), recording.rig)
    im = reduce(recording.static_imu.groupby(["set", "pose"])[IMU_COLUMNS])
    I = static_sensor_orientations(im[ACC_COLUMNS].to_numpy(), im[MAG_COLUMNS].to_numpy())
    sets = im.index.get_level_values("set").to_numpy()
    out = {}
    for k in np.unique(sets):
        sel = sets == k
        out[int(k)] = (relative_rotations(C[sel]), relative_rotations(I[sel]))
    return out


def _all_sample_motions(recording: LabRecording, n_markers: int) -> dict:
    """``static_motions(recording, sample="all")``."""
    markers, imu = recording.static_markers, recording.static_imu
    mean_uv = marker_pixels(markers.groupby(["set", "pose"]).mean(), n_markers)
    C0, t0 = camera_poses(mean_uv, recording.rig)
    pose_keys = markers.groupby(["set", "pose"]).ngroup().to_numpy()    # same order as the groupby's mean
    C = refine_camera_orientations(marker_pixels(markers, n_markers), recording.rig, C0[pose_keys], t0[pose_keys])
    I = ecompass_attitudes(imu[ACC_COLUMNS].to_numpy(), imu[MAG_COLUMNS].to_numpy())
    cam_key = markers[["set", "pose"]].to_numpy()
    imu_key = imu[["set", "pose"]].to_numpy()
    cam_t, imu_t = markers["t"].to_numpy(), imu["t"].to_numpy()
    out = {}
    for k in np.unique(imu_key[:, 0]):
        frames, samples = [], []
        for p in np.unique(imu_key[imu_key[:, 0] == k, 1]):
            ci = np.flatnonzero((cam_key[:, 0] == k) & (cam_key[:, 1] == p))
            ii = np.flatnonzero((imu_key[:, 0] == k) & (imu_key[:, 1] == p))
            at = np.searchsorted(cam_t[ci], imu_t[ii], side="right") - 1  # the frame at or before each sample
            keep = at >= 0
            frames.append(C[ci[at[keep]]])
            samples.append(I[ii[keep]])
        A, B = [], []
        for p in range(len(frames) - 1):
            j = min(len(frames[p]), len(frames[p + 1]))
            A.append(frames[p + 1][:j] @ np.swapaxes(frames[p][:j], -1, -2))
            B.append(samples[p + 1][:j] @ np.swapaxes(samples[p][:j], -1, -2))
        out[int(k)] = (np.concatenate(A), np.concatenate(B))
    return out


@dataclass
class LabResult:
    """The experiment's results (see :func:`run_lab`).

    Attributes
    ----------
    estimates : dict
        Table II column -> (n_sets, 3, 3) estimates of ``R0`` (camera_from_sensor).
    r0 : dict
        Table II column -> the chordal mean of its estimates (used for the dynamic trial).
    per_set : pandas.DataFrame
        One row per set and column: ``set``, ``method``, ``roll_deg``, ``pitch_deg``,
        ``yaw_deg`` of the estimate; ``dev_x_deg``, ``dev_y_deg``, ``dev_z_deg``: the
        rotation vector of ``R_est R_ref^T`` (degrees, camera axes), ``R_ref`` the true
        ``R0`` if known, else the method's mean; ``from_mean_deg`` (angle to the
        method's mean) and, if the truth is known, ``true_error_deg``.
    traces : pandas.DataFrame
        ``t`` and roll/pitch/yaw of ``camera``, ``sensor_frame`` and each projection.
    table2 : pandas.DataFrame
        Rows (angle, method), columns of :func:`attitude_statistics`.
    truth : numpy.ndarray or None
        The true ``R0`` if the recording carries one (simulation).
    dynamic : dict
        The dynamic trial at the camera times: ``t`` (s), ``camera_from_world`` (``C_t``, by PnP)
        and ``world_from_sensor`` (the Madgwick stream slerped to the camera times; ``I_t`` is its
        transpose), for re-projecting it with another ``R0`` or another reference frame
        (:mod:`replication.study.table2`).
    """

    estimates: dict
    r0: dict
    per_set: pd.DataFrame
    traces: pd.DataFrame
    table2: pd.DataFrame
    truth: np.ndarray | None = None
    dynamic: dict = field(default_factory=dict)


def run_lab(recording: LabRecording, solvers: dict = TABLE2_SOLVERS, *, fast: bool = False,
            dynamic_camera=None) -> LabResult:
    """The experiment of Sec. III-B from recordings: calibrate per data set, then the dynamic trial.

    Parameters
    ----------
    recording : LabRecording
        Simulated (:func:`simulate_lab`) or loaded
        (:func:`replication.study.lab.recording.load_lab`).
    solvers : dict
        Column name -> (registered solver, options); default Table II's three methods
        (:data:`TABLE2_SOLVERS`).
    fast : bool
        The dynamic trial through the faster equivalents of the seed studies: the camera by
        ``camera_orientations(..., refine="batched")``, the sensor by
        ``dynamic_sensor_orientations(..., madgwick="transcribed")`` (each equal to the default to
        about 1e-6 deg and to rounding, ``tests/study/test_lab_claims.py``).
    dynamic_camera : array_like (M, 3, 3), optional
        The dynamic trial's camera attitudes (``LabResult.dynamic["camera_from_world"]``) of a run
        on a recording with the same marker pixels (e.g. the same seed with IMU errors switched
        off), reused instead of PnP on every frame again.

    Returns
    -------
    LabResult

    Notes
    -----
    The paper does not say which of its 10 estimates it projected with in Fig. 7 and
    Table II; we use each method's chordal mean over the data sets.
    The dynamic trial compares relative attitudes to the first camera frame:
    ``Delta R_c = C_k C_0^T`` against ``R0 Delta R_i R0^T`` with
    ``Delta R_i = I_k I_0^T``, the sensor sampled at the camera times by slerp.
    """
    motions = static_motions(recording)
    sets = sorted(motions)
    estimates, warned = {}, {}
    for name, (method, options) in solvers.items():
        out = []
        for k in sets:
            with warnings.catch_warnings(record=True) as caught:  # recorded per data set (a finding), not shown
                warnings.simplefilter("always", ReplicationWarning)
                out.append(solve(method, *motions[k], **options))
            warned[name, k] = ", ".join(sorted({w.category.__name__ for w in caught
                                                 if issubclass(w.category, ReplicationWarning)}))
        estimates[name] = np.stack(out)
    r0 = {name: _chordal_mean(R) for name, R in estimates.items()}
    truth = recording.truth.get("camera_from_sensor")
    rows = []
    for name, R in estimates.items():
        rpy = yaw_pitch_roll_deg_from_matrix(R)[..., ::-1]
        ref = truth if truth is not None else r0[name]
        dev = np.degrees(rotation_vector_from_matrix(R @ ref.T))                           # deviation, camera axes
        for i, k in enumerate(sets):
            row = {"set": k, "method": name, "roll_deg": rpy[i, 0], "pitch_deg": rpy[i, 1], "yaw_deg": rpy[i, 2],
                   "dev_x_deg": dev[i, 0], "dev_y_deg": dev[i, 1], "dev_z_deg": dev[i, 2],
                   "from_mean_deg": float(angle_between_deg(R[i], r0[name])), "warnings": warned[name, k]}
            if truth is not None:
                row["true_error_deg"] = float(angle_between_deg(R[i], truth))
            rows.append(row)
    per_set = pd.DataFrame(rows)

    # dynamic trial
    dm = recording.dynamic_markers
    if dynamic_camera is None:
        C = camera_orientations(marker_pixels(dm, len(recording.rig["wand_points"])), recording.rig,
                                refine="batched" if fast else "opencv")
    else:
        C = np.asarray(dynamic_camera, dtype=float)
        if C.shape != (len(dm), 3, 3):
            raise ValueError(f"dynamic_camera must have shape ({len(dm)}, 3, 3) (one per camera frame), got {C.shape}")
    sensor = dynamic_sensor_orientations(recording.dynamic_imu, recording.rig["imu_rate_hz"],
                                         madgwick="transcribed" if fast else "ahrs")
    t_cam, t_imu = dm["t"].to_numpy(), sensor.t
    if t_cam[0] < t_imu[0] or t_cam[-1] > t_imu[-1]:
        raise ValueError(f"dynamic trial: camera times {t_cam[0]:.3f}..{t_cam[-1]:.3f} s are not inside "
                         f"the IMU's {t_imu[0]:.3f}..{t_imu[-1]:.3f} s")
    world_from_sensor = sensor.at(t_cam)
    dC = relative_rotations(C, reference=0)
    dI = relative_rotations(world_from_sensor, reference=0, convention="world_from_body")
    traces = {"camera": yaw_pitch_roll_deg_from_matrix(dC)[..., ::-1],
              "sensor_frame": yaw_pitch_roll_deg_from_matrix(dI)[..., ::-1]}
    for name, R in r0.items():
        # the paper's R0 Delta R_i R0^T (roll first)
        traces[name] = yaw_pitch_roll_deg_from_matrix(R @ dI @ R.T)[..., ::-1]
    tables = {name: attitude_statistics(tr, traces["camera"]) for name, tr in traces.items() if name != "camera"}
    order = list(solvers) + ["sensor_frame"]
    rows = pd.MultiIndex.from_product([["roll", "pitch", "yaw"], order], names=["angle", "method"])
    table2 = pd.concat(tables, names=["method"]).swaplevel().reindex(rows)
    frame = {"t": t_cam[1:]}
    for name, tr in traces.items():
        for i, a in enumerate(("roll", "pitch", "yaw")):
            frame[f"{name}_{a}"] = tr[:, i]
    return LabResult(estimates, r0, per_set, pd.DataFrame(frame), table2, truth,
                     {"t": t_cam, "camera_from_world": C, "world_from_sensor": world_from_sensor})
