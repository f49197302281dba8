"""Studies of the simulated lab: summaries, error-source ablation, sensitivity, the experiment over
many seeds.

Support of ``notebooks/05_table2_experiment.ipynb``: a statement about the lab is about the
distribution of its seeds and about interventions (an error source switched off, the true
``R0`` turned, another reference frame), not about one draw.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd

from ...core.so3 import angle_between_deg, matrix_from_rotation_vector
from ...core.solvers import ReplicationWarning, solve, sqp
from ...core.stats import ROUNDING_RUNS, declared_bound, mean_se, wilson_interval
from ..table2 import projection_statistics
from .chain import LabResult, run_lab, static_motions
from .settings import PARTS, SOURCES, TABLE2_SOLVERS, LabSettings
from .simulate import simulate_lab

__all__ = ["summarize", "ablation", "sensitivity", "seed_study", "seed_spread", "seed_findings", "count_text",
           "sqp_shares", "check_sqp_shares", "seed_range", "pitch_bias_intervention", "intervention_finding",
           "RESOLVE_DEG"]


#: The declared bound (deg) of the change of the two-step error with every sample instead of each
#: orientation's mean, and its margin: the change is -0.0019 on both sets of seeds here and moves by
#: up to 0.0005 deg between machines.
ALL_MINUS_MEAN_BOUND = (-0.005, 0.0)
ALL_MINUS_MEAN_MARGIN = 0.0008


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


def ablation(settings: LabSettings = LabSettings(), sources=None, solvers: dict = TABLE2_SOLVERS, *,
             fast: bool = False) -> pd.DataFrame:
    """Rerun the whole simulated experiment with error sources switched off.

    Cases: ``all sources``; ``without <source>`` (one switched off at a time); ``only <source>``
    (all others off); ``no sources``. Every other random draw stays the same (see
    :func:`simulate_lab`). ``fast``: :func:`run_lab`'s faster equivalents for the dynamic trial (the
    same numbers to about 1e-6 deg; where the filter's chatter sets them, see below, to rounding
    either way).

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
             **summarize(run_lab(simulate_lab(st), solvers, fast=fast))} for label, st in cases]
    return pd.DataFrame(rows).set_index("case")


def sensitivity(name: str, values, settings: LabSettings = LabSettings(), solvers: dict = TABLE2_SOLVERS, *,
                fast: bool = False):
    """Rerun the experiment for each value of one :class:`LabSettings` field (``fast``: as in
    :func:`ablation`).

    Returns
    -------
    pandas.DataFrame
        Index the values (named ``name``); columns of :func:`summarize`.
    """
    if name not in {f.name for f in dataclasses.fields(LabSettings)}:
        raise ValueError(f"{name!r} is not a LabSettings field")
    rows = [{name: v, **summarize(run_lab(simulate_lab(dataclasses.replace(settings, **{name: v})), solvers,
                                          fast=fast))} for v in values]
    return pd.DataFrame(rows).set_index(name)


def seed_study(seeds, settings: LabSettings = LabSettings(), *, failure_deg: float = 10.0, sqp_runs=None,
               turned_deg=(), single_sample: bool = False, all_samples: bool = False, without=(),
               fast: bool = True) -> pd.DataFrame:
    """The simulated experiment once per seed: one row of numbers per seed.

    Columns: per method (``ours_right``, ``ours_left``, ``optimization``) ``shared_bias_<m>`` (angle
    of the chordal mean of its 10 estimates to the true ``R0``: what every data set shares),
    ``true_<m>`` (mean angle of the 10 estimates to the true ``R0``), ``spread_<m>`` (mean angle of
    the estimates to their mean: Fig. 6's consistency), ``failed_<m>`` (data sets more than
    ``failure_deg`` off), ``rms_<m>`` (Table II's RMS averaged over roll, pitch, yaw), ``corr_<m>``
    (smallest correlation over the three angles; ``corr_<angle>_ours_right`` per angle);
    ``pitch_bias_true_R0`` / ``rms_true_R0``: Table II's pitch mean and average RMS when the true
    ``R0`` is used for the projection; ``rms_reversed_ours_right``: the same with the two-step
    (``R^r``) chordal mean's error reversed (``E^T R0`` for the estimate ``E R0``: an error of the
    same size and axis, opposite sign).

    Parameters
    ----------
    seeds : iterable of int
    settings : LabSettings
        Every seed uses these settings with its own ``seed``.
    failure_deg : float
        A data set whose estimate is farther than this from the true ``R0`` has failed.
    sqp_runs : dict, optional
        ``{name: options of replication.core.solvers.sqp}``: also run SQP from the identity so
        configured on every data set: ``failed_sqp_<name>`` (data sets more than ``failure_deg``
        off) and ``limit_sqp_<name>`` (of those, stopped by the iteration limit, ``max_iterations``,
        default 100).
    turned_deg : iterable of float
        Also project with the true ``R0`` turned by these angles (about the camera's x, y and z axis
        in turn): ``rms_turned_<angle>`` is Table II's RMS averaged over the three angles and the
        three axes, i.e. the RMS a calibration that far off would show.
    single_sample : bool
        Also calibrate with the first sample of each static orientation instead of the mean
        (:func:`replication.study.lab.static_motions`): ``true_single_ours_right``.
    all_samples : bool
        Also calibrate with every sample of each static orientation (``static_motions(...,
        sample="all")``, the alternative the paper names): ``true_all_ours_right``.
    without : iterable of str
        Error sources or parts (:data:`SOURCES`, :data:`PARTS`) to switch off one at a time, on the
        same seed (every other draw unchanged): the two-step (``R^r``) calibration and the dynamic
        trial rerun, with the camera's dynamic attitudes reused (the marker pixels are checked to be
        the same). Columns ``<column>_without_<source>`` (spaces as ``_``) for
        ``shared_bias_ours_right``, ``true_ours_right``, ``rms_ours_right``, ``pitch_bias_true_R0``
        and ``rms_true_R0``.
    fast : bool
        :func:`replication.study.lab.run_lab`'s faster equivalents for the dynamic trial (its
        ``fast``): the same numbers to about 1e-6 deg, in half the time.
    """
    without = list(without)
    right = {"ours_right": TABLE2_SOLVERS["ours_right"]}
    rows = []
    for seed in seeds:
        seeded = dataclasses.replace(settings, seed=int(seed))
        recording = simulate_lab(seeded)
        result = run_lab(recording, fast=fast)
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
            turned = [result.truth @ matrix_from_rotation_vector(np.radians(float(angle)) * axis) for axis in np.eye(3)]
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
            row[f"limit_sqp_{name}"] = int(sum(o and int(r.iterations) >= cap for o, r in zip(off, runs)))
        for sample, wanted in (("single", single_sample), ("all", all_samples)):
            if wanted:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", ReplicationWarning)
                    est = [solve("two_step_right", A, B) for A, B in static_motions(recording, sample=sample).values()]
                row[f"true_{sample}_ours_right"] = float(np.mean(angle_between_deg(np.stack(est), result.truth)))
        for source in without:
            off_recording = simulate_lab(seeded.without(source))
            if not off_recording.dynamic_markers.equals(recording.dynamic_markers):
                raise ValueError(f"switching {source!r} off changed the marker pixels: the camera cannot be reused")
            off = run_lab(off_recording, right, fast=fast, dynamic_camera=result.dynamic["camera_from_world"])
            off_true = projection_statistics(off, off.truth)
            tag = "_without_" + source.replace(" ", "_")
            row["shared_bias_ours_right" + tag] = float(angle_between_deg(off.r0["ours_right"], off.truth))
            row["true_ours_right" + tag] = float(off.per_set["true_error_deg"].mean())
            row["rms_ours_right" + tag] = float(off.table2.xs("ours_right", level="method")["rms_deg"].mean())
            row["pitch_bias_true_R0" + tag] = float(off_true.loc["pitch", "mean_deg"])
            row["rms_true_R0" + tag] = float(off_true["rms_deg"].mean())
        rows.append(row)
    return pd.DataFrame(rows).set_index("seed")


#: The share (deg of |pitch bias|) the magnetometer intervention must resolve: its 95 % interval on
#: each set of seeds must be narrower than this on either side of its mean, or no verdict is drawn
#: from it.
RESOLVE_DEG = 0.1


def pitch_bias_intervention(seeds, part: str, settings: LabSettings = LabSettings()) -> pd.DataFrame:
    """Table II's pitch bias with the true ``R0`` per seed, as it is and with one error source or
    part switched off.

    The same numbers as :func:`seed_study`'s ``pitch_bias_true_R0`` and
    ``pitch_bias_true_R0_without_<part>`` (``tests/study/test_lab_claims.py``), without the
    calibrations: the projection uses the true ``R0``, so only the dynamic trial is run (the
    camera's attitudes once, the AHRS filter on both recordings), about a third of the time, for the
    many seeds that resolving a small share needs.

    Returns
    -------
    pandas.DataFrame
        Index ``seed``; columns ``pitch_bias`` and ``pitch_bias_without`` (deg).
    """
    known = {**SOURCES, **PARTS}
    if part not in known:
        raise ValueError(f"unknown error source or part {part!r}; known: {', '.join(known)}")
    rows = []
    for seed in seeds:
        seeded = dataclasses.replace(settings, seed=int(seed))
        recording = simulate_lab(seeded)
        result = run_lab(recording, {}, fast=True)
        off_recording = simulate_lab(seeded.without(part))
        if not off_recording.dynamic_markers.equals(recording.dynamic_markers):
            raise ValueError(f"switching {part!r} off changed the marker pixels: the camera cannot be reused")
        off = run_lab(off_recording, {}, fast=True, dynamic_camera=result.dynamic["camera_from_world"])
        rows.append({"seed": int(seed),
                     "pitch_bias": float(projection_statistics(result, result.truth).loc["pitch", "mean_deg"]),
                     "pitch_bias_without": float(projection_statistics(off, off.truth).loc["pitch", "mean_deg"])})
    return pd.DataFrame(rows).set_index("seed")


def intervention_finding(frame: pd.DataFrame, *, resolve: float = RESOLVE_DEG) -> dict:
    """The change of ``|pitch bias|`` with the part switched off (:func:`pitch_bias_intervention`),
    paired per seed.

    Returns ``dict`` with ``value`` (mean change, deg), ``se``, ``low`` / ``high`` (its 95 %
    interval, mean ± 1.96 SE), ``n``, ``abs_pitch_bias`` (mean ``|pitch bias|`` as it is),
    ``resolved`` (the interval excludes 0), ``fine`` (the interval's half-width below ``resolve``: a
    share of that size would be resolved) and ``text`` (``"mean ± SE [low, high]"``).
    """
    change = frame["pitch_bias_without"].abs() - frame["pitch_bias"].abs()
    m, se = mean_se(change.to_numpy(dtype=float))
    low, high = m - 1.96 * se, m + 1.96 * se
    return {"value": float(m), "se": float(se), "low": float(low), "high": float(high), "n": len(frame),
            "abs_pitch_bias": float(frame["pitch_bias"].abs().mean()), "resolved": bool(low > 0 or high < 0),
            "fine": bool(1.96 * se < resolve), "text": f"{m:.3f} ± {se:.3f} [{low:.3f}, {high:.3f}]"}


def seed_spread(values: pd.Series, digits: int = 2) -> str:
    """``"<mean> (SD <sd>; <min>-<max>)"``: a quantity over the seeds (a column of
    :func:`seed_study`).

    Notebook 05, "The lab over 20 seeds" (its seed table) and its claims
    (:mod:`replication.study.lab.claims`); ``digits`` decimals, the SD with ``ddof=1``.
    """
    return (f"{values.mean():.{digits}f} (SD {values.std(ddof=1):.{digits}f}; "
            f"{values.min():.{digits}f}-{values.max():.{digits}f})")


def seed_range(study: pd.DataFrame) -> str:
    """``"seeds 1-20"``: the seeds of a :func:`seed_study` frame (its index), which must be
    consecutive."""
    seeds = list(study.index)
    if not seeds or seeds != list(range(seeds[0], seeds[0] + len(seeds))):
        raise ValueError(f"the seeds must be consecutive integers, got {seeds}")
    return f"seeds {seeds[0]}-{seeds[-1]}"


def count_text(k, n) -> str:
    """``"15 of 20 (53-89 %)"``: a count of seeds with its Wilson 95 % interval
    (:func:`replication.core.stats.wilson_interval`)."""
    low, high = wilson_interval(k, n)
    return f"{int(k)} of {int(n)} ({100 * low:.0f}-{100 * high:.0f} %)"


def _parts(study):
    tag = "shared_bias_ours_right_without_"
    return [c[len(tag):] for c in study.columns if c.startswith(tag)]


def seed_findings(study: pd.DataFrame) -> pd.DataFrame:
    """The seed study's findings on one set of seeds: counts of seeds with their Wilson 95 %
    interval, paired differences and means with their standard errors.

    Notebook 05, "The lab over fresh seeds": each finding on the seeds it was found on beside the
    fresh ones (:mod:`replication.study.lab.claims` builds the records from them). Which findings
    there are follows the columns of ``study`` (:func:`seed_study`): the turned ``R0``
    (``rms_turned_<a>``), the parts switched off (``..._without_<part>``), the single and all-sample
    calibrations.

    Returns
    -------
    pandas.DataFrame
        Index ``finding`` (an id); columns ``what`` (its text), ``kind`` (``"count"``: ``value``
        seeds of ``n``, ``low``-``high`` its Wilson interval; ``"mean"``: ``value`` ± ``se`` over
        the ``n`` seeds; ``"median"``), and ``text`` (``"k of n (low-high %)"``, ``"mean ± se"`` or
        the median), deg where a quantity has a unit.
    """
    n = len(study)
    rows = {}

    def count(key, what, mask):
        k = int(np.asarray(mask, dtype=bool).sum())
        low, high = wilson_interval(k, n)
        rows[key] = dict(what=what, kind="count", value=float(k), n=n, low=low, high=high, se=np.nan,
                         text=count_text(k, n))

    def mean(key, what, values, digits=3):
        m, se = mean_se(np.asarray(values, dtype=float))
        rows[key] = dict(what=what, kind="mean", value=float(m), n=n, low=np.nan, high=np.nan, se=float(se),
                         text=f"{m:.{digits}f} ± {se:.{digits}f}")

    rms_true = study["rms_true_R0"]
    count("estimate_beats_truth", "seeds where the two-step estimate gives a smaller Table II RMS than the true R0",
          study["rms_ours_right"] < rms_true)
    count("reversed_loses", "seeds where the estimate's error reversed gives a larger RMS than the true R0",
          study["rms_reversed_ours_right"] > rms_true)
    turned = [c[len("rms_turned_"):] for c in study.columns if c.startswith("rms_turned_")]
    for a in turned:
        count(f"turned_{a}_loses", f"seeds where R0 turned by {a} deg gives a larger RMS than the true R0",
              study[f"rms_turned_{a}"] > rms_true)
    mean("rms_true", "Table II RMS with the true R0 (deg)", rms_true)
    mean("rms_estimate_minus_truth", "RMS with the estimate minus with the true R0 (deg)",
         study["rms_ours_right"] - rms_true)
    mean("rms_reversed_minus_truth", "RMS with the reversed error minus with the true R0 (deg)",
         study["rms_reversed_ours_right"] - rms_true)
    for a in turned:
        mean(f"rms_turned_{a}_minus_truth", f"RMS with R0 turned by {a} deg minus with the true R0 (deg)",
             study[f"rms_turned_{a}"] - rms_true)
    mean("shared_bias", "error of the mean of the 10 estimates (deg)", study["shared_bias_ours_right"], 2)
    ratio = study["shared_bias_ours_right"] / (study["spread_ours_right"] / np.sqrt(10))
    count("shared_exceeds_independent", "seeds where that error exceeds the spread / sqrt(10) independent per-set "
          "errors would leave", ratio > 1)
    rows["shared_ratio_median"] = dict(what="that error / (spread / sqrt(10)), median over the seeds", kind="median",
                                       value=float(ratio.median()), n=n, low=np.nan, high=np.nan, se=np.nan,
                                       text=f"{ratio.median():.1f}")
    pitch = study["pitch_bias_true_R0"].abs()
    mean("abs_pitch_bias", "|pitch bias| with the true R0 (deg)", pitch, 2)
    for part in _parts(study):
        name = part.replace("_", " ")
        tag = "_without_" + part
        shared_off = study["shared_bias_ours_right" + tag]
        pitch_off = study["pitch_bias_true_R0" + tag].abs()
        mean("shared_bias" + tag, f"error of the mean of the 10 estimates without {name} (deg)", shared_off, 2)
        mean("shared_bias_change" + tag, f"its change with {name} switched off (deg)",
             shared_off - study["shared_bias_ours_right"], 3)
        mean("abs_pitch_bias" + tag, f"|pitch bias| with the true R0 without {name} (deg)", pitch_off, 2)
        mean("abs_pitch_bias_change" + tag, f"its change with {name} switched off (deg)", pitch_off - pitch, 3)
        count("estimate_beats_truth" + tag, f"seeds where the estimate gives a smaller RMS than the true R0, without "
              f"{name}", study["rms_ours_right" + tag] < study["rms_true_R0" + tag])
    mean("true_mean", "two-step error to the true R0, the mean of each orientation (deg)", study["true_ours_right"], 2)
    if "true_single_ours_right" in study:
        mean("single_minus_mean", "its change with the first sample of each orientation instead (deg)",
             study["true_single_ours_right"] - study["true_ours_right"], 2)
    if "true_all_ours_right" in study:
        mean("all_minus_mean", "its change with every sample of each orientation instead (deg)",
             study["true_all_ours_right"] - study["true_ours_right"], 4)
        # a change of thousandths of a degree whose last digit moves between machines (by up to
        # 0.0005 deg over the variants of scripts/spread.py, as large as its SE): shown as a bound
        # declared in advance
        rows["all_minus_mean"]["text"] = declared_bound(
            rows["all_minus_mean"]["value"], *ALL_MINUS_MEAN_BOUND, margin=ALL_MINUS_MEAN_MARGIN,
            what="the change with every sample of each orientation (deg)")
    for angle in ("roll", "pitch", "yaw"):
        count(f"corr_{angle}_at_paper", f"seeds where the {angle} correlation after calibration is at least 0.999",
              study[f"corr_{angle}_ours_right"] >= 0.999)
    count("calibration_reduces", "seeds where the calibrated RMS is below the sensor frame's",
          study["rms_ours_right"] < study["rms_sensor_frame"])
    out = pd.DataFrame.from_dict(rows, orient="index")
    out.index.name = "finding"
    return out


def sqp_shares(study: pd.DataFrame, runs) -> dict:
    """SQP's failures over a :func:`seed_study` frame run with ``sqp_runs`` named ``runs``:
    ``"failed, <name>"`` (share of the data sets more than 10 deg off), ``"at limit"`` (share of the
    100-iteration failures stopped by the iteration limit; the run named ``"100 iterations"``) and
    ``"seeds"`` (share of seeds with a failed set)."""
    n_sets = 10 * len(study)
    out = {f"failed, {name}": study[f"failed_sqp_{name}"].sum() / n_sets for name in runs}
    failed = study["failed_sqp_100 iterations"]
    out["at limit"] = study["limit_sqp_100 iterations"].sum() / max(int(failed.sum()), 1)
    out["seeds"] = float((failed > 0).mean())
    out["counts"] = {"data sets": n_sets, "failed": int(failed.sum()), "seeds": len(study)}
    return out


def check_sqp_shares(shares: dict, bounds: dict, label: str) -> bool:
    """SQP's failure shares (:func:`sqp_shares`) against the bounds notebook 05 declares, each kept
    with a margin of :data:`~replication.core.stats.ROUNDING_RUNS` data sets (seeds, failed sets):
    which data sets SLSQP finishes within its cap changes with the machine's rounding, so a share is
    shown only as a declared bound (:func:`~replication.core.stats.declared_bound`; ``ValueError``
    naming it if one does not hold). Returns True."""
    n = shares["counts"]
    margin = {key: ROUNDING_RUNS / max(count, 1) for key, count in n.items()}
    what = f"table2_methods_agree, {label}: SQP's share of"
    declared_bound(shares["failed, 100 iterations"], bounds["failed"], margin=margin["data sets"],
                   what=f"{what} failed data sets (100 iterations)")
    declared_bound(shares["at limit"], bounds["at limit"], margin=margin["failed"],
                   what=f"{what} failed sets stopped at the limit")
    declared_bound(shares["seeds"], bounds["seeds"], margin=margin["seeds"], what=f"{what} seeds with a failed set")
    declared_bound(shares["failed, 1000 iterations"], high=bounds["failed, 1000"], margin=margin["data sets"],
                   what=f"{what} failed data sets (1000 iterations)")
    declared_bound(shares["failed, cost (8) / 2J"], high=bounds["failed, per pair"], margin=margin["data sets"],
                   what=f"{what} failed data sets (cost (8) / 2J)")
    return True
