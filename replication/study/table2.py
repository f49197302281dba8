"""Table II: its statistics, what they measure, and the comparison with the paper's (beside Table
I's :mod:`replication.study.table1`).

Table II compares the camera's relative attitude ``Delta R_c = C_k C_ref^T`` with the sensor's,
projected into the camera frame with an estimate of ``R0``: ``R0 Delta R_i R0^T``, ``Delta R_i = I_k
I_ref^T``. Its numbers mix two errors: that of the ``R0`` used, and that of the sensor's own
attitude (the AHRS filter's) at the reference frame and at each time. :func:`projection_statistics`
re-projects a lab run's dynamic trial with any ``R0`` (the true one included) and any reference
frame, which separates the two by intervention: project with the true ``R0`` (no calibration error
left), move the reference frame, switch error sources off. Roll, pitch and yaw are the intrinsic
``z-y'-x''`` angles of a relative rotation, ``Delta R = Rz(yaw) Ry(pitch) Rx(roll)``
(:func:`replication.core.so3.yaw_pitch_roll_deg_from_matrix`), listed roll first as in Table II. The
lab over many seeds is :func:`replication.study.lab.seed_study`.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..core.checks import check_rotation_matrices
from ..core.handeye import relative_rotations
from ..core.so3 import rotation_angle_deg, yaw_pitch_roll_deg_from_matrix
from .paper import TABLE2_ANGLES, TABLE2_METHODS, load_table2

if TYPE_CHECKING:  # the lab's chain computes Table II with this module; no import cycle at run time
    from .lab import LabResult

__all__ = ["attitude_statistics", "projection_statistics", "reference_frame_dependence",
           "table2_versus_paper"]


def attitude_statistics(estimate_deg, reference_deg) -> pd.DataFrame:
    """Table II's statistics of an attitude trace against the camera's.

    Parameters
    ----------
    estimate_deg, reference_deg : array_like, shape (M, 3)
        Roll, pitch, yaw traces (degrees).

    Returns
    -------
    pandas.DataFrame
        Index roll, pitch, yaw; columns ``rms_deg``, ``mean_deg``, ``sd_deg`` of the
        difference ``estimate - reference`` (wrapped to (-180, 180]; population SD, so
        ``rms^2 = mean^2 + sd^2``) and ``correlation`` (Pearson) of the two traces.
    """
    est, ref = np.asarray(estimate_deg, dtype=float), np.asarray(reference_deg, dtype=float)
    d = (est - ref + 180.0) % 360.0 - 180.0
    corr = [np.corrcoef(est[:, i], ref[:, i])[0, 1] for i in range(3)]
    return pd.DataFrame(
        {"rms_deg": np.sqrt(np.mean(d**2, axis=0)), "mean_deg": d.mean(axis=0), "sd_deg": d.std(axis=0),
         "correlation": corr},
        index=pd.Index(["roll", "pitch", "yaw"], name="angle"),
    )


def projection_statistics(result: LabResult, R0, *, reference_time: float = 0.0) -> pd.DataFrame:
    """Table II's statistics (:func:`attitude_statistics`) of the dynamic trial projected with
    ``R0``.

    Parameters
    ----------
    result : LabResult
        A run of :func:`replication.study.lab.run_lab` (its ``dynamic`` field).
    R0 : array_like (3, 3)
        ``camera_from_sensor`` to project with.
    reference_time : float
        Seconds after the trial's start of the reference frame of the relative attitudes (the
        paper's, and :func:`replication.study.lab.run_lab`'s, is the first frame).
    """
    R0 = check_rotation_matrices(R0, "R0", atol=1e-6)
    t, C, Q = result.dynamic["t"], result.dynamic["camera_from_world"], result.dynamic["world_from_sensor"]
    if not 0.0 <= reference_time <= t[-1] - t[0]:
        raise ValueError(f"reference_time must be within the trial (0 to {t[-1] - t[0]:.1f} s), got {reference_time}")
    ref = int(np.argmin(np.abs(t - t[0] - reference_time)))
    dC = relative_rotations(C, reference=ref)
    dI = relative_rotations(Q, reference=ref, convention="world_from_body")
    return attitude_statistics(yaw_pitch_roll_deg_from_matrix(R0 @ dI @ R0.T)[..., ::-1],
                               yaw_pitch_roll_deg_from_matrix(dC)[..., ::-1])


def reference_frame_dependence(result: LabResult, estimates: dict, times) -> pd.DataFrame:
    """Mean difference (the bias, deg) and RMS of roll, pitch, yaw for each ``R0`` of ``estimates``
    and reference time.

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


def table2_versus_paper(result: LabResult) -> pd.DataFrame:
    """Table II of the simulated lab beside the paper's, with each method's true ``R0`` error.

    Returns
    -------
    pandas.DataFrame
        Index (angle, method); columns ``paper_*`` and ``ours_*`` for RMS, mean, SD
        (deg) and correlation, and ``true_r0_error_deg``: the mean angle of the method's
        per-set estimates to the true ``R0`` (for ``sensor_frame``: the angle of the true
        ``R0`` itself, the error of assuming aligned frames). NaN if the truth is unknown.
    """
    paper = load_table2()  # indexed by (angle, method)
    ours = result.table2.reindex(paper.index)
    out = pd.concat([paper.add_prefix("paper_"), ours.add_prefix("ours_")], axis=1)
    cols = ["rms_deg", "mean_deg", "sd_deg", "correlation"]
    out = out[[f"{w}_{c}" for c in cols for w in ("paper", "ours")]]
    true = {}
    if result.truth is not None:
        true = result.per_set.groupby("method")["true_error_deg"].mean().to_dict()
        true["sensor_frame"] = float(rotation_angle_deg(result.truth))  # ignoring R0 altogether
    out["true_r0_error_deg"] = [true.get(m, np.nan) for m in out.index.get_level_values("method")]
    return out.reindex(pd.MultiIndex.from_product([TABLE2_ANGLES, TABLE2_METHODS], names=["angle", "method"]))
