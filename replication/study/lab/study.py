"""Studies of the simulated lab: summaries, error-source ablation, sensitivity, the experiment over many seeds.

Support of ``notebooks/05_table2_experiment.ipynb``: a statement about the lab is about the
distribution of its seeds and about interventions (an error source switched off, the true
``R0`` turned, another reference frame), not about one draw.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd

from ...core.so3 import angle_between_deg, exp_map
from ...core.solvers import ReplicationWarning, solve, sqp
from ..table2 import projection_statistics
from .chain import LabResult, run_lab, static_motions
from .settings import SOURCES, TABLE2_SOLVERS, LabSettings
from .simulate import simulate_lab

__all__ = ["summarize", "ablation", "sensitivity", "seed_study", "seed_spread"]


def summarize(result: LabResult, *, failure_deg: float = 10.0) -> dict:
    """One line of numbers per experiment: per method the mean true ``R0`` error (``true_``; and
    ``true_clean_`` over the data sets on which the solver issued no warning), the
    number of data sets whose estimate is more than ``failure_deg`` from the truth, the
    number of data sets on which the solver warned, the
    mean spread around the method's mean estimate (Fig. 6) and the Table II RMS averaged
    over roll, pitch and yaw."""
    per = result.per_set.groupby("method", sort=False)
    rms = result.table2["rms_deg"].groupby(level="method", sort=False).mean()
    row = {}
    for name in result.estimates:
        err = per.get_group(name)["true_error_deg"]
        clean = per.get_group(name)["warnings"] == ""
        row[f"true_{name}"] = err.mean()
        row[f"true_clean_{name}"] = err[clean].mean() if clean.any() else np.nan
        row[f"failed_{name}"] = int((err > failure_deg).sum())
        row[f"warned_{name}"] = int((per.get_group(name)["warnings"] != "").sum())
        row[f"spread_{name}"] = per.get_group(name)["from_mean_deg"].mean()
    for name in rms.index:
        row[f"rms_{name}"] = rms[name]
    return row


def ablation(settings: LabSettings = LabSettings(), sources=None, solvers: dict = TABLE2_SOLVERS) -> pd.DataFrame:
    """Rerun the whole simulated experiment with error sources switched off.

    Cases: ``all sources``; ``without <source>`` (one switched off at a time);
    ``only <source>`` (all others off); ``no sources``. Every other random draw stays
    the same (see :func:`simulate_lab`).

    Returns
    -------
    pandas.DataFrame
        Index ``case``; columns ``noise_free_dynamic_attitude`` (see
        :attr:`LabSettings.noise_free_dynamic_attitude`: Table II's statistics of that case are
        set by rounding at the 1e-3 deg level) and those of :func:`summarize`.
    """
    sources = list(SOURCES) if sources is None else list(sources)
    cases = [("all sources", settings)]
    cases += [(f"without {s}", settings.without(s)) for s in sources]
    cases += [(f"only {s}", settings.without(*[o for o in sources if o != s])) for s in sources]
    cases.append(("no sources", settings.without(*sources)))
    rows = [{"case": label, "noise_free_dynamic_attitude": st.noise_free_dynamic_attitude,
             **summarize(run_lab(simulate_lab(st), solvers))} for label, st in cases]
    return pd.DataFrame(rows).set_index("case")


def sensitivity(name: str, values, settings: LabSettings = LabSettings(), solvers: dict = TABLE2_SOLVERS):
    """Rerun the experiment for each value of one :class:`LabSettings` field.

    Returns
    -------
    pandas.DataFrame
        Index the values (named ``name``); columns of :func:`summarize`.
    """
    if name not in {f.name for f in dataclasses.fields(LabSettings)}:
        raise ValueError(f"{name!r} is not a LabSettings field")
    rows = [{name: v, **summarize(run_lab(simulate_lab(dataclasses.replace(settings, **{name: v})), solvers))}
            for v in values]
    return pd.DataFrame(rows).set_index(name)


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
        ``{name: options of replication.core.solvers.sqp}``: also run SQP from the identity so configured on every
        data set: ``failed_sqp_<name>`` (data sets more than ``failure_deg`` off) and ``limit_sqp_<name>`` (of
        those, stopped by the iteration limit, ``max_iterations``, default 100).
    turned_deg : iterable of float
        Also project with the true ``R0`` turned by these angles (about the camera's x, y and z axis in turn):
        ``rms_turned_<angle>`` is Table II's RMS averaged over the three angles and the three axes, i.e. the
        RMS a calibration that far off would show.
    single_sample : bool
        Also calibrate with the first sample of each static orientation instead of the mean
        (:func:`replication.study.lab.static_motions`): ``true_single_ours_right``.
    """
    rows = []
    for seed in seeds:
        recording = simulate_lab(dataclasses.replace(settings, seed=int(seed)))
        result = run_lab(recording)
        row = {"seed": int(seed)}
        summary = summarize(result, failure_deg=failure_deg)
        for name in result.estimates:
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


def seed_spread(values: pd.Series, digits: int = 2) -> str:
    """``"<mean> (SD <sd>; <min>-<max>)"``: a quantity over the seeds (a column of :func:`seed_study`).

    Notebook 05, "The lab over 20 seeds" (its seed table) and its claims (:func:`replication.study.lab.lab_claims`);
    ``digits`` decimals, the SD with ``ddof=1``.
    """
    return (f"{values.mean():.{digits}f} (SD {values.std(ddof=1):.{digits}f}; "
            f"{values.min():.{digits}f}-{values.max():.{digits}f})")
