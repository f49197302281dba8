"""What Table II measures, and the simulated lab over many seeds (support of ``notebooks/05_table2_experiment.ipynb``).

Table II compares the camera's relative attitude ``Delta R_c = C_k C_ref^T`` with the sensor's, projected into
the camera frame with an estimate of ``R0``: ``R0 Delta R_i R0^T``, ``Delta R_i = I_k I_ref^T``. Its numbers
mix two errors: that of the ``R0`` used, and that of the sensor's own attitude (the AHRS filter's) at the
reference frame and at each time. :func:`projection_statistics` re-projects a lab run's dynamic trial with any
``R0`` (the true one included) and any reference frame, which separates the two by intervention:
project with the true ``R0`` (no calibration error left), move the reference frame, switch error sources off.
:func:`seed_study` repeats the whole simulated experiment over many seeds, so that a statement about the lab
is about its distribution, not about one draw.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd

from .handeye import relative_rotations
from .lab import (LabResult, LabSettings, attitude_statistics, euler_rpy_deg, run_lab, simulate_lab, static_motions,
                  summarize)
from .so3 import angle_between_deg, check_rotation_matrices, exp_map
from .solvers import ReplicationWarning, solve, sqp

__all__ = ["projection_statistics", "reference_frame_dependence", "seed_study"]


def projection_statistics(result: LabResult, R0, *, reference_time: float = 0.0) -> pd.DataFrame:
    """Table II's statistics (:func:`replication.lab.attitude_statistics`) of the dynamic trial projected with ``R0``.

    Parameters
    ----------
    result : LabResult
        A run of :func:`replication.lab.run_lab` (its ``dynamic`` field).
    R0 : array_like (3, 3)
        ``camera_from_sensor`` to project with.
    reference_time : float
        Seconds after the trial's start of the reference frame of the relative attitudes (the paper's, and
        :func:`replication.lab.run_lab`'s, is the first frame).
    """
    R0 = check_rotation_matrices(R0, "R0", atol=1e-6)
    t, C, I = result.dynamic["t"], result.dynamic["camera"], result.dynamic["sensor"]
    if not 0.0 <= reference_time <= t[-1] - t[0]:
        raise ValueError(f"reference_time must be within the trial (0 to {t[-1] - t[0]:.1f} s), got {reference_time}")
    ref = int(np.argmin(np.abs(t - t[0] - reference_time)))
    dC = relative_rotations(C, reference=ref)
    dI = relative_rotations(I, reference=ref)
    return attitude_statistics(euler_rpy_deg(R0 @ dI @ R0.T), euler_rpy_deg(dC))


def reference_frame_dependence(result: LabResult, estimates: dict, times) -> pd.DataFrame:
    """Mean difference (the bias, deg) and RMS of roll, pitch, yaw for each ``R0`` of ``estimates`` and reference time.

    Returns
    -------
    pandas.DataFrame
        Index ``(R0, reference time (s))``; columns ``<angle> mean`` and ``<angle> rms`` (deg).
    """
    rows = {}
    for name, R in estimates.items():
        for tr in times:
            st = projection_statistics(result, R, reference_time=float(tr))
            rows[(name, float(tr))] = {**{f"{a} mean": st.loc[a, "mean_deg"] for a in st.index},
                                       **{f"{a} rms": st.loc[a, "rms_deg"] for a in st.index}}
    out = pd.DataFrame(rows).T
    out.index.names = ["R0", "reference time (s)"]
    return out


def seed_study(seeds, settings: LabSettings = LabSettings(), *, failure_deg: float = 10.0, sqp_runs=None,
               turned_deg=(), single_sample: bool = False) -> pd.DataFrame:
    """The simulated experiment once per seed: one row of numbers per seed.

    Columns: per method (``ours_right``, ``ours_left``, ``optimization``) ``shared_bias_<m>`` (angle of the
    chordal mean of its 10 estimates to the true ``R0``: what every data set shares), ``true_<m>`` (mean angle of
    the 10 estimates to the true ``R0``), ``spread_<m>`` (mean angle of the estimates to their mean: Fig. 6's
    consistency), ``failed_<m>`` (data sets more than ``failure_deg`` off), ``rms_<m>`` (Table II's RMS averaged
    over roll, pitch, yaw), ``corr_<m>`` (smallest correlation over the three angles; ``corr_<angle>_ours_right``
    per angle); ``pitch_bias_true_R0`` / ``rms_true_R0``: Table II's pitch mean and average RMS when the true
    ``R0`` is used for the projection; ``rms_reversed_ours_right``: the same with the two-step (``R^r``) chordal
    mean's error reversed (``E^T R0`` for the estimate ``E R0``: an error of the same size and axis, opposite sign).

    Parameters
    ----------
    seeds : iterable of int
    settings : LabSettings
        Every seed uses these settings with its own ``seed``.
    failure_deg : float
        A data set whose estimate is farther than this from the true ``R0`` has failed.
    sqp_runs : dict, optional
        ``{name: options of replication.solvers.sqp}``: also run SQP from the identity so configured on every
        data set: ``failed_sqp_<name>`` (data sets more than ``failure_deg`` off) and ``limit_sqp_<name>`` (of
        those, stopped by the iteration limit, ``max_iterations``, default 100).
    turned_deg : iterable of float
        Also project with the true ``R0`` turned by these angles (about the camera's x, y and z axis in turn):
        ``rms_turned_<angle>`` is Table II's RMS averaged over the three angles and the three axes, i.e. the
        RMS a calibration that far off would show.
    single_sample : bool
        Also calibrate with the first sample of each static orientation instead of the mean
        (:func:`replication.lab.static_motions`): ``true_single_ours_right``.
    """
    rows = []
    for seed in seeds:
        recording = simulate_lab(dataclasses.replace(settings, seed=int(seed)))
        result = run_lab(recording)
        row = {"seed": int(seed)}
        summary = summarize(result, failure_deg=failure_deg)
        for name, R in result.estimates.items():
            row[f"shared_bias_{name}"] = float(angle_between_deg(result.r0[name], result.truth))
            row[f"true_{name}"] = summary[f"true_{name}"]
            row[f"spread_{name}"] = summary[f"spread_{name}"]
            row[f"failed_{name}"] = summary[f"failed_{name}"]
            row[f"rms_{name}"] = summary[f"rms_{name}"]
            row[f"corr_{name}"] = float(result.table2.xs(name, level="method")["correlation"].min())
        for angle in ("roll", "pitch", "yaw"):
            row[f"corr_{angle}_ours_right"] = float(result.table2.loc[(angle, "ours_right"), "correlation"])
        row["rms_sensor_frame"] = summary["rms_sensor_frame"]
        true = projection_statistics(result, result.truth)
        row["pitch_bias_true_R0"] = float(true.loc["pitch", "mean_deg"])
        row["pitch_bias_ours_right"] = float(result.table2.loc[("pitch", "ours_right"), "mean_deg"])
        row["rms_true_R0"] = float(true["rms_deg"].mean())
        error = result.r0["ours_right"] @ result.truth.T
        row["rms_reversed_ours_right"] = float(projection_statistics(result, error.T @ result.truth)["rms_deg"].mean())
        for angle in turned_deg:
            turned = [result.truth @ exp_map(np.radians(float(angle)) * axis) for axis in np.eye(3)]
            row[f"rms_turned_{angle:g}"] = float(np.mean([projection_statistics(result, R)["rms_deg"].mean()
                                                          for R in turned]))
        motions = static_motions(recording) if sqp_runs else {}
        for name, options in (sqp_runs or {}).items():
            cap = int(options.get("max_iterations", 100))
            with warnings.catch_warnings():  # the failures are what is counted
                warnings.simplefilter("ignore", ReplicationWarning)
                runs = [sqp(A, B, **options) for A, B in motions.values()]
            off = [angle_between_deg(r.R, result.truth) > failure_deg for r in runs]
            row[f"failed_sqp_{name}"] = int(sum(off))
            row[f"limit_sqp_{name}"] = int(sum(o and int(r.n_iterations) >= cap for o, r in zip(off, runs)))
        if single_sample:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ReplicationWarning)
                single = [solve("two_step_right", A, B) for A, B in static_motions(recording, sample="single").values()]
            row["true_single_ours_right"] = float(np.mean(angle_between_deg(np.stack(single), result.truth)))
        rows.append(row)
    return pd.DataFrame(rows).set_index("seed")
