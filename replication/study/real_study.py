"""Studies on the real recordings (support of ``notebooks/07_real_data.ipynb``).

Each function runs one study of the notebook over named data sets and returns a table; the
notebook shows the tables, states what they decide and records its verdicts. Data sets are
given as ``{name: (camera, sensor, reference name)}`` with ``camera`` an
:class:`~replication.rig.streams.OrientationStream` and ``sensor`` an orientation or gyro stream
(for :func:`replication.rig.calibration.calibrate`), or ``camera`` and ``sensor`` as arrays of
absolute attitudes of a static pose set (for :func:`replication.rig.poses.calibrate_poses`).
Warnings are recorded, never shown: :class:`~replication.core.solvers.ObservabilityWarning` (a
property of the data set) apart from the others (a property of the solver's answer).
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ..core.so3 import rotation_angle_deg
from ..core.solvers import ConvergenceWarning, ObservabilityWarning, ReplicationWarning, two_step
from ..rig.association import stream_pairs
from ..rig.calibration import calibrate
from ..rig.poses import calibrate_poses, pose_pairs
from .baselines import compare

__all__ = ["station_bootstrap", "recording_warnings", "calibration_table", "solver_tables", "protocol_table",
           "sensitivity_table", "calibrations", "usual_mistakes", "verdict_table", "reference_floor_table"]


def recording_warnings(fn, *args, **kwargs):
    """Call ``fn`` recording our warnings.

    Returns
    -------
    (result, observability_warned, others) : (object, bool, str)
        ``fn``'s result, whether it issued an
        :class:`~replication.core.solvers.ObservabilityWarning`, and the sorted names of the other
        :class:`~replication.core.solvers.ReplicationWarning` classes it issued.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ReplicationWarning)
        r = fn(*args, **kwargs)
    kinds = {w.category for w in caught if issubclass(w.category, ReplicationWarning)}
    return r, ObservabilityWarning in kinds, ", ".join(sorted(k.__name__ for k in kinds - {ObservabilityWarning}))


def calibration_table(results: dict) -> pd.DataFrame:
    """The headline table of :func:`calibrations`' results, one row per ``(data, method)``.

    Returns
    -------
    pandas.DataFrame
        Index ``(data, method)``; columns ``error_deg`` (angle to the reference), ``pairs``,
        ``bootstrap95_deg``, ``offset_ms``, its 95 % interval ``offset_low_ms`` / ``offset_high_ms``
        and ``offset_corr`` (the clock offset and its correlation; NaN for pose sets),
        ``change_deg`` (the angle between R0 before and after the change test's split, where it
        ran), ``change_significant``, ``axis_spread_deg`` (camera), ``observability_warning``,
        ``other warnings`` (from the result's warnings) and ``verdict`` (the level of the result's
        verdict, :mod:`replication.rig.quality`).
    """
    rows = []
    for (name, method), r in results.items():
        kinds = {w.split(":", 1)[0] for w in r.warnings}
        static = np.isnan(r.time_offset_correlation)  # a static pose set has no clock
        rows.append({"data": name, "method": method, "error_deg": r.reference_error_deg, "pairs": r.n_pairs,
                     "bootstrap95_deg": r.bootstrap_ci95_deg, "offset_ms": np.nan if static else 1e3 * r.time_offset_s,
                     "offset_low_ms": 1e3 * r.time_offset_ci95_s[0], "offset_high_ms": 1e3 * r.time_offset_ci95_s[1],
                     "offset_corr": r.time_offset_correlation,
                     "change_deg": (r.change_test or {}).get("angle_deg", np.nan),
                     "change_significant": (r.change_test or {}).get("significant", False),
                     "axis_spread_deg": float(r.observability.camera_axis_spread_deg),
                     "observability_warning": "ObservabilityWarning" in kinds,
                     "other warnings": ", ".join(sorted(kinds - {"ObservabilityWarning"})), "verdict": r.verdict.level})
    return pd.DataFrame(rows).set_index(["data", "method"])


def solver_tables(streams: dict, pose_sets: dict, references: dict, *, interval: float = 1.0) -> pd.DataFrame:
    """Every registered solver on the same pairs of each data set
    (:func:`replication.study.baselines.compare`).

    Streams are paired at ``interval`` seconds (:func:`~replication.rig.association.stream_pairs`),
    pose sets over all pairs (:func:`~replication.rig.poses.pose_pairs`). The ``opencv_*`` solvers
    rebuild a pose chain from the pairs and form all its pairs, so they get non-overlapping pairs:
    every ``interval / dt``-th pair of a stream, the consecutive pairs of a pose set.

    Returns
    -------
    pandas.DataFrame
        Index ``(data, method)``; columns ``error_deg`` (angle to the reference), ``n_pairs``,
        ``warnings`` (other than :class:`~replication.core.solvers.ObservabilityWarning`),
        ``seconds``.
    """
    tables = {}
    for name, (cam, sensor, ref) in streams.items():
        A, B, _, _ = stream_pairs(cam, sensor, interval=interval)
        step = int(round(interval / np.median(np.diff(cam.t))))
        tables[name] = _one_problem(A, B, references[ref], (A[::step], B[::step]))
    for name, (cam, sensor, ref) in pose_sets.items():
        tables[name] = _one_problem(*pose_pairs(cam, sensor), references[ref],
                                    pose_pairs(cam, sensor, pairs="consecutive"))
    return pd.concat(tables, names=["data", "method"])


def _one_problem(A, B, reference, opencv_pairs) -> pd.DataFrame:
    table = compare(A, B, reference, pairs_for={"opencv_": opencv_pairs}, ignore_warnings=(ObservabilityWarning,))
    return table.rename(columns={"mean_deg": "error_deg"})[["error_deg", "n_pairs", "warnings", "seconds"]]


def protocol_table(streams: dict, references: dict, intervals) -> pd.DataFrame:
    """The paper's protocol (50 two-step iterations) against the default (run to the limit) on the
    same pairs.

    Returns
    -------
    pandas.DataFrame
        Index ``(data, interval (s))``; columns ``sigma2/sigma1 of K`` (rounded to 5 digits), the
        error of ``R^l`` after 50 iterations and at the default's answer (deg), the default's
        iterations (or ``"closed form"``) and whether the 50-iteration run warned
        (:class:`~replication.core.solvers.ConvergenceWarning`).
    """
    rows = {}
    for name, (cam, sensor, ref) in streams.items():
        for interval in intervals:
            A, B, _, _ = stream_pairs(cam, sensor, interval=interval)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", ReplicationWarning)
                fifty = two_step(A, B, iterations=50)
                limit = two_step(A, B)
            rows[(name, interval)] = {
                "sigma2/sigma1 of K": round(float(limit.observability.spectral_ratio), 5),
                "50 iterations: error (deg)": float(rotation_angle_deg(fifty.history.R_left.T @ references[ref])),
                "default: error (deg)": float(rotation_angle_deg(limit.history.R_left.T @ references[ref])),
                "default: iterations": "closed form" if limit.history.closed_form else int(limit.iterations),
                "50 iterations warned": any(issubclass(w.category, ConvergenceWarning) for w in caught),
            }
    out = pd.DataFrame(rows).T
    out.index.names = ["data", "interval (s)"]
    return out


def sensitivity_table(camera, gyro, reference, *, intervals, shares, methods, n_bootstrap: int,
                      seed: int) -> pd.DataFrame:
    """:func:`~replication.rig.calibration.calibrate` over pairing intervals and over leading shares
    of the recording.

    Returns
    -------
    pandas.DataFrame
        Index ``(study, value, method)``; columns ``error_deg``, ``bootstrap95_deg``, ``pairs``.
    """
    def row(study, value, method, r):
        return {"study": study, "value": value, "method": method, "error_deg": r.reference_error_deg,
                "bootstrap95_deg": r.bootstrap_ci95_deg, "pairs": r.n_pairs}

    rows = []
    for interval in intervals:
        for method in methods:
            r = recording_warnings(calibrate, camera, gyro, method=method, interval=interval, reference=reference,
                                   n_bootstrap=n_bootstrap, seed=seed)[0]
            rows.append(row("interval (s)", interval, method, r))
    t0, t1 = camera.t[0], camera.t[-1]
    for share in shares:
        part = camera.between(t0, t0 + share * (t1 - t0))
        for method in methods:
            r = recording_warnings(calibrate, part, gyro, method=method, reference=reference,
                                   n_bootstrap=n_bootstrap, seed=seed)[0]
            rows.append(row("length (share of the recording)", share, method, r))
    return pd.DataFrame(rows).set_index(["study", "value", "method"])


def calibrations(streams: dict, pose_sets: dict, references: dict, methods=("chordal_optimal",), *, seed: int,
                 **options) -> dict:
    """:func:`~replication.rig.calibration.calibrate` on every stream pair (``calibrate_poses`` on
    every pose set), with each method, warnings recorded in the results, not shown: ``{(data,
    method): result}``."""
    out = {}
    for name, (cam, sensor, ref) in {**streams, **pose_sets}.items():
        fn = calibrate_poses if name in pose_sets else calibrate
        for method in methods:
            out[name, method] = recording_warnings(fn, cam, sensor, method=method, reference=references[ref],
                                                   seed=seed, **options)[0]
    return out


def usual_mistakes(camera, gyro, reference, *, seed: int, n_bootstrap: int = 50) -> dict:
    """The issue's usual input mistakes made on purpose on one good recording (an intervention):
    ``{case: result}``.

    Cases: as recorded; the camera quaternions read in the wrong component order (``(w, x, y, z)``
    read as ``(x, y, z, w)``); the camera poses inverted (``camera_from_world``); the gyro in deg/s
    read as rad/s; the sensor clock 10 s off (beyond the default offset search of 0.2 s).
    """
    from ..core.so3 import matrix_from_quaternion, quaternion_from_matrix
    from ..rig.streams import GyroStream, OrientationStream

    q = quaternion_from_matrix(camera.world_from_body)
    cases = {
        "as recorded": (camera, gyro),
        "camera quaternions (w, x, y, z) read as (x, y, z, w)":
            (OrientationStream(camera.t, matrix_from_quaternion(q[:, [3, 0, 1, 2]]), camera.source), gyro),
        "camera poses inverted (camera_from_world)":
            (OrientationStream(camera.t, np.swapaxes(camera.world_from_body, -1, -2), camera.source), gyro),
        "gyro in deg/s read as rad/s": (camera, GyroStream(gyro.t, np.degrees(gyro.omega), gyro.source)),
        "sensor clock 10 s off": (camera, GyroStream(gyro.t + 10.0, gyro.omega, gyro.source)),
    }
    return {name: recording_warnings(calibrate, cam, sen, reference=reference, seed=seed,
                                     n_bootstrap=n_bootstrap)[0] for name, (cam, sen) in cases.items()}


def verdict_table(results: dict) -> pd.DataFrame:
    """One row per result: its verdict, the checks behind it (names, worst first), an input mistake
    it named, and its angle to the reference (deg).

    The reasons' full messages (with their measured numbers and thresholds) are in each result's
    ``verdict.reasons`` and on its diagnostic figure.
    """
    rows = []
    for name, r in results.items():
        reasons = sorted(r.verdict.reasons, key=lambda x: x.level != "fail")
        mistake = next((x.message.split(";")[0].removeprefix("likely input mistake: ") for x in reasons
                        if x.check == "input_mistake"), "")
        rows.append({"data": name, "verdict": r.verdict.level,
                     "checks": ", ".join(f"{x.check} ({x.level})" for x in reasons if x.check != "input_mistake"),
                     "input mistake named": mistake, "error_deg": r.reference_error_deg})
    return pd.DataFrame(rows).set_index("data")


def station_bootstrap(C, S, *, n_bootstrap: int = 200, seed: int = 0) -> dict:
    """A static pose set's 95 % bootstrap radius resampling its stations (what
    :func:`calibrate_poses` does) and resampling its pairs one by one (what it did before, treating
    the ``N (N - 1) / 2`` pairs as independent)."""
    from ..core.motions import prepare_motions
    from ..core.so3 import angle_between_deg
    from ..rig.poses import calibrate_poses, pose_pairs
    from ..rig.solve_and_judge import block_indices, bootstrap_replicates

    r = calibrate_poses(C, S, n_bootstrap=n_bootstrap, seed=seed)
    motions = prepare_motions(*pose_pairs(C, S))
    boot = bootstrap_replicates(motions, "chordal_optimal", {},
                                block_indices(np.random.default_rng(seed), motions.J, 1, n_bootstrap))
    return {"stations": int(len(C)), "pairs": int(motions.J), "radius by stations (deg)": r.bootstrap_ci95_deg,
            "radius by pairs one by one (deg)": float(np.percentile(angle_between_deg(boot, r.R), 95))}


def reference_floor_table(results: dict, rig_of: dict, references: dict) -> pd.DataFrame:
    """Every estimate against every published calibration of its rig, and the references' own
    disagreement.

    Parameters
    ----------
    results : dict
        ``{(data, method): CalibrationResult}`` (:func:`calibrations`).
    rig_of : dict
        ``{data: rig}``: the rig each data set was recorded on.
    references : dict
        ``{rig: {reference name: camera_from_sensor}}``: the published calibrations of each rig.

    Returns
    -------
    pandas.DataFrame
        Index ``(data, method)``; one column ``to <reference> (deg)`` per reference name (NaN where
        the rig has no such reference), ``references apart (deg)`` (the largest angle between two
        references of the rig: the *reference floor*; NaN with one reference) and ``reading``:
        ``within the floor`` when the estimate is no farther from any reference than they are from
        each other (it agrees with each as far as they agree; that says nothing on which is nearer
        the truth), ``beyond the floor`` when it is farther from one of them than they are from each
        other, ``one reference`` when there is no floor to compare with.
    """
    names = list(dict.fromkeys(n for refs in references.values() for n in refs))
    rows = []
    for (data, method), r in results.items():
        refs = references[rig_of[data]]
        angles = {n: float(rotation_angle_deg(r.R.T @ R)) for n, R in refs.items()}
        apart = [float(rotation_angle_deg(a.T @ b)) for i, a in enumerate(refs.values())
                 for b in list(refs.values())[i + 1:]]
        floor = max(apart) if apart else np.nan
        reading = ("one reference" if not apart else
                   "within the floor" if max(angles.values()) <= floor else "beyond the floor")
        rows.append({"data": data, "method": method,
                     **{f"to {n} (deg)": angles.get(n, np.nan) for n in names},
                     "references apart (deg)": floor, "reading": reading})
    return pd.DataFrame(rows).set_index(["data", "method"])
