"""The common end of :func:`replication.rig.calibration.calibrate` (streams) and
:func:`replication.rig.poses.calibrate_poses` (static pose sets): solve the pairs, their residuals,
a bootstrap radius, the verdict. Theory and measured numbers: ``docs/judging.md``, section
``replication.rig.solve_and_judge``."""
from __future__ import annotations

import dataclasses
import math
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..core import so3
from ..core.checks import check_number, check_rotation_matrices
from ..core.handeye import pair_residual_deg
from ..core.motions import prepare_motions
from ..core.solvers import ReplicationWarning, SolverAnswerError, checked_core, solve, solver_info
from .quality import Evidence, Reason, Verdict, judge
from .report import RADIUS_COVERS, CalibrationResult

__all__ = ["check_common", "first_reference", "reference_reading", "check_options", "solve_pairs", "Resampling",
           "Provenance", "with_reasons",
           "bootstrap_replicates", "unfit_replicates", "block_indices", "station_indices", "per_station_median",
           "REPLICATE_FIT_FACTOR", "REPLICATE_FIT_FLOOR_DEG", "FROZEN_DEG"]

#: A bootstrap replicate is no solution of its resample when the root-mean-square residual of its
#: pairs (cost (8) as an angle) exceeds this factor times that of the answer on all pairs, on the
#: same pairs, ... Measured (the ratio of the two, every registered solver, 200 replicates, seed 0):
#: TUM-VI, EuRoC MH01 and Tabb DS1 0.92-1.06, except sqp on EuRoC, one replicate at 26.6 (a local
#: minimum: 2.9 deg against 0.11); the synthetic rig of tests/ test_calibration.py (50 replicates)
#: with 0.2 deg noise 1.00-1.02, OpenCV's wrappers up to 1.75; noise-free up to 3.0 (1e-9 deg
#: residuals, under the floor); a pose set with 1-3 outlying stations of 30-120 deg (3 seeds, both
#: pairings) up to 1.00 (chordal_optimal), 1.01 (robust), 1.78 (two_step_left). A random rotation:
#: tens to hundreds.
REPLICATE_FIT_FACTOR = 4.0
#: ... plus this (deg): residuals of noise-free data are rounding (1e-9 deg measured), whose ratios
#: mean nothing.
REPLICATE_FIT_FLOOR_DEG = 1e-6
#: Replicates all within this angle (deg) of the answer on all the pairs, where the pairs leave more
#: than :data:`REPLICATE_FIT_FLOOR_DEG`, are the answer returned unchanged (a solver that ignores
#: its input): a radius of zero. Measured (chordal_optimal, 200 replicates, seed 0): the replicate
#: nearest the answer is 0.0019 deg from it on TUM-VI, 0.0041 on EuRoC MH01, 0.011 on Tabb DS1;
#: noise-free pairs leave 1e-9 deg, under the floor.
FROZEN_DEG = 1e-9


def check_common(method, n_bootstrap, seed, reference):
    """Check the parameters every calibration takes (before any work); returns the reference as a
    rotation or None."""
    solver_info(method)  # an unknown name fails before any work, listing the available ones
    check_number("n_bootstrap", n_bootstrap, minimum=0, integer=True, strict=False)
    check_number("seed", seed, minimum=0, integer=True, strict=False)
    if reference is None:
        return None
    ref = np.asarray(reference, dtype=float)
    if ref.shape == (4, 4):
        raise ValueError("reference is a 4x4 transform; pass its rotation block "
                         "(the upper-left 3x3 camera_from_sensor)")
    if ref.shape not in ((3, 3), (2, 3, 3)):
        raise ValueError(f"reference must be a 3x3 rotation (camera_from_sensor), got shape {ref.shape} (two "
                         f"references, e.g. two published calibrations: shape (2, 3, 3))")
    return check_rotation_matrices(ref, "reference", atol=1e-5)


def first_reference(reference):
    """The reference a single-reference check uses: the one given, or the first of two."""
    if reference is None or np.ndim(reference) == 2:
        return reference
    return np.asarray(reference)[0]


def reference_reading(errors_deg, disagreement_deg: float, radius_deg: float = float("nan")) -> str:
    """Which reading two references' errors allow: an error below the references' own disagreement
    (the reference floor) is agreement with them, not a measure of accuracy. With R0's 95 % radius
    (``radius_deg``, finite), errors that differ by no more than the radius cannot tell the
    references apart, and errors both within it are agreement with both; a difference beyond it
    names the closer reference whatever the floor (references 10 deg apart, R0 on one of them:
    closer to that one, not "agreement")."""
    e1, e2 = errors_deg
    r = radius_deg if np.isfinite(radius_deg) and radius_deg >= 0 else None
    floor = f"the references' own disagreement {disagreement_deg:.3f} deg (the reference floor)"
    if r is not None and max(e1, e2) <= r:
        return (f"agreement within R0's radius: both errors ({e1:.3f}, {e2:.3f} deg) are within its 95 % radius "
                f"{r:.3f} deg, and {floor}: R0 agrees with both references")
    if min(e1, e2) > max(disagreement_deg, r or 0.0):
        return (f"a difference beyond the floor: both errors ({e1:.3f}, {e2:.3f} deg) exceed {floor}"
                + (f" and R0's 95 % radius {r:.3f} deg" if r is not None else "")
                + ", so R0 differs from both by more than they differ from each other (R0's own error, or one the "
                  "references share)")
    resolved = abs(e1 - e2) > r if r is not None else max(e1, e2) > disagreement_deg
    if resolved:
        closer = 1 if e1 <= e2 else 2
        why = (f"is the smaller, by more than R0's 95 % radius {r:.3f} deg ({floor})" if r is not None
               else f"is within {floor} and the other's ({max(e1, e2):.3f} deg) is not")
        return (f"closer to reference {closer}: its error ({min(e1, e2):.3f} deg) {why}; an error within the floor "
                f"is agreement, not accuracy")
    if max(e1, e2) <= disagreement_deg:
        return (f"agreement, not accuracy: both errors ({e1:.3f}, {e2:.3f} deg) are within {floor}, so the data "
                f"cannot say which reference is closer to the truth, nor how close R0 is")
    return (f"not resolved: the errors ({e1:.3f}, {e2:.3f} deg) differ by no more than R0's 95 % radius {r:.3f} deg, "
            f"so the data cannot say which reference is closer; {floor}")


def check_options(method, options):
    """Refuse solver options the solver does not take (or values it refuses), before any work: the
    solver is called once with them on a tiny exact problem."""
    if not options:
        return
    A = so3.matrix_from_rotation_vector(np.array([[0.5, 0.0, 0.0], [0.0, 0.6, 0.0], [0.0, 0.0, 0.7], [0.3, 0.4, 0.0]]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            solver_info(method).core(prepare_motions(A, A), **options)
        except TypeError as err:
            raise ValueError(f"solver {method!r} does not take the option(s) {sorted(options)}: {err}") from None
        except ValueError as err:
            raise ValueError(f"solver {method!r} refuses the option(s) {sorted(options)}: {err}") from None


def block_indices(rng, J: int, block: int, n_bootstrap: int) -> np.ndarray:
    """Moving-block bootstrap: ``(n_bootstrap, J)`` pair indices, blocks of ``block`` consecutive
    pairs."""
    block = int(min(J, block))
    starts = rng.integers(0, J - block + 1, size=(n_bootstrap, -(-J // block)))
    return (starts[..., None] + np.arange(block)).reshape(n_bootstrap, -1)[:, :J]


def station_indices(rng, stations, n_bootstrap: int) -> list:
    """Station bootstrap (see the module notes): for each replicate, the pair indices, pair ``k`` of
    stations ``(i_k, j_k)`` repeated ``m_i m_j`` times (``m`` the stations' multiplicities in a draw
    of ``N`` with replacement). ``stations = (i, j, N)``, or ``(i, j, N, labels)``: stations that
    share a label (repeats of one station) are drawn together, as one, ``D`` distinct stations drawn
    ``D`` times."""
    i, j, N = stations[:3]
    labels = stations[3] if len(stations) > 3 else np.arange(N)
    distinct, group = np.unique(labels, return_inverse=True)
    out = []
    for _ in range(n_bootstrap):
        m = np.bincount(rng.integers(0, len(distinct), len(distinct)), minlength=len(distinct))[group]
        out.append(np.repeat(np.arange(len(i)), m[i] * m[j]))
    return out


def _repeats(stations):
    """The report's ``station_repeats`` (stations given, distinct, the groups of repeats), or None
    without repeats."""
    if stations is None or len(stations) < 4 or len(np.unique(stations[3])) == stations[2]:
        return None
    labels = np.asarray(stations[3])
    groups = [np.flatnonzero(labels == g).tolist() for g in np.unique(labels)]
    return {"stations": int(stations[2]), "distinct": len(groups), "groups": [g for g in groups if len(g) > 1]}


def _repeats_reason(repeats):
    if repeats is None:
        return None
    named = "; ".join(" = ".join(str(k) for k in g) for g in repeats["groups"][:5]) + (
        f"; and {len(repeats['groups']) - 5} more groups" if len(repeats["groups"]) > 5 else "")
    extra = repeats["stations"] - repeats["distinct"]
    return Reason("repeated_stations", "warning", float(extra), 0.0,
                  f"{extra} of the {repeats['stations']} stations repeat others (0-based, the same attitude on both "
                  f"sides within the motion a pair needs): {named}; each group is counted once in the bootstrap "
                  f"({repeats['distinct']} distinct stations), since repeats do not add independent poses")


def per_station_median(res, stations) -> np.ndarray:
    """Median residual (deg) of the pairs that use each station (NaN for a station in no pair)."""
    i, j, N = stations[:3]
    return np.array([np.median(res[(i == s) | (j == s)]) if np.any((i == s) | (j == s)) else np.nan
                     for s in range(N)])


def _progress(items, **options):
    """``items`` behind a tqdm progress bar on standard error; without tqdm (an optional package:
    the extra ``study``) ``items`` as they are, the bar being all that is lost."""
    try:
        from tqdm import tqdm
    except ImportError:
        return items
    return tqdm(items, file=sys.stderr, **options)


def bootstrap_replicates(motions, method, options, index_sets, *, progress=False, masks=False, fit_to=None):
    """The solver on each resample (``index_sets``: an ``(n, J)`` array of pair indices, or a list
    of index arrays of any lengths), through the registry's one door for re-solves
    (:func:`replication.core.solvers.checked_core`): validated pairs, so no re-validation; the
    replicates' own warnings would repeat the main solve's and are not issued; every answer is
    checked as :func:`solve` checks it.

    Every replicate is also checked for being a solution of its resample against ``fit_to``, the
    answer on all the pairs (:func:`unfit_replicates`; without ``fit_to`` the solver is run once on
    all the pairs for it).

    Returns the replicates' answers ``R_boot``; with ``masks`` ``(R_boot, failed, reflection,
    unfit)``, with the masks of the solver's declared failures (NaN blocks), reflections and answers
    that are no solutions, which never enter a radius (without ``masks`` any of them raises); with
    ``masks="reason"`` ``(R_boot, reason)``, the ``fail`` reason naming the solver, or None. Raises
    :class:`~replication.core.solvers.SolverAnswerError` (a ``ValueError`` naming the solver) where
    an answer is neither a rotation nor a NaN block (e.g. ``2 R``)."""
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ReplicationWarning)
        if isinstance(index_sets, np.ndarray):  # equal lengths: batched, in chunks for a progress bar
            chunks = np.array_split(np.arange(len(index_sets)), min(len(index_sets), 10)) if progress else [
                np.arange(len(index_sets))]
            if progress:
                chunks = _progress(chunks, desc=f"bootstrap ({method})", unit="chunk")
            for chunk in chunks:
                out.append(checked_core(method, motions.subset(index_sets[chunk]),
                                        where=f" on bootstrap replicates {chunk[0]}..{chunk[-1]}", **options))
        else:
            sets = index_sets
            if progress:
                sets = _progress(sets, desc=f"station bootstrap ({method})", unit="replicate")
            for k, idx in enumerate(sets):
                R, failed, reflection = checked_core(method, motions.subset(idx), where=f" on bootstrap replicate {k}",
                                                     **options)
                out.append((R[None], failed[None], reflection[None]))
    R_boot, failed, reflection = (np.concatenate(part) for part in zip(*out))
    if fit_to is None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ReplicationWarning)
            full, full_failed, full_reflection = checked_core(method, motions, where=" on all the pairs", **options)
        fit_to = None if full_failed or full_reflection else full
    unfit, fit = (np.zeros(len(R_boot), dtype=bool), None) if fit_to is None else unfit_replicates(
        motions, R_boot, index_sets, fit_to, skip=failed | reflection)
    bad = _bad_replicates(method, failed, reflection, unfit, fit,
                          frozen=fit is not None and _frozen(R_boot, fit_to, failed | reflection, fit))
    if masks == "reason":  # solve_pairs: the masks and the reason, the replicates' fit measured once
        return R_boot, bad
    if masks:
        return R_boot, failed, reflection, unfit
    if bad is not None:
        raise SolverAnswerError(bad.message)
    return R_boot


def _rms_deg(residual_deg) -> float:
    """The pairs' cost (8) as an angle: the residual angle whose chordal distance is the root mean
    square of theirs (``||A R - R B||_F = 2 sqrt(2) sin(angle / 2)``)."""
    return math.degrees(2.0 * math.asin(min(1.0, math.sqrt(float(np.mean(np.sin(np.radians(residual_deg) / 2) ** 2))))))


def unfit_replicates(motions, R_boot, index_sets, R, *, skip=None):
    """Which bootstrap replicates are no solution of their resample: ``(unfit, (replicate, full))``,
    ``unfit`` the mask of replicates whose pairs' root-mean-square residual (cost (8) as an angle)
    exceeds :data:`REPLICATE_FIT_FACTOR` times that of ``R`` (the answer on all pairs) on the same
    pairs plus :data:`REPLICATE_FIT_FLOOR_DEG`, and the two per replicate (deg; NaN where ``skip``,
    e.g. the replicates that are no rotations)."""
    n = len(R_boot)
    skip = np.zeros(n, dtype=bool) if skip is None else np.asarray(skip, dtype=bool)
    own, full = np.full(n, np.nan), np.full(n, np.nan)
    residual = pair_residual_deg(R, motions.A, motions.B)
    for b, idx in enumerate(index_sets):
        if not skip[b]:
            idx = np.asarray(idx)
            own[b] = _rms_deg(pair_residual_deg(R_boot[b], motions.A[idx], motions.B[idx]))
            full[b] = _rms_deg(residual[idx])
    with np.errstate(invalid="ignore"):
        unfit = ~skip & ~(own <= REPLICATE_FIT_FACTOR * full + REPLICATE_FIT_FLOOR_DEG)
    return unfit, (own, full)


def _frozen(R_boot, R, skip, fit) -> bool:
    """Whether every usable replicate is ``R`` itself (within :data:`FROZEN_DEG`) although the pairs
    leave more than :data:`REPLICATE_FIT_FLOOR_DEG` (see :data:`FROZEN_DEG`)."""
    usable = ~np.asarray(skip, dtype=bool)
    if usable.sum() < 2 or not np.nanmax(fit[1][usable]) > REPLICATE_FIT_FLOOR_DEG:
        return False
    return bool(np.all(so3.angle_between_deg(R_boot[usable], R) <= FROZEN_DEG))


def _bad_replicates(method, failed, reflection, unfit=None, fit=None, frozen=False):
    """A ``fail`` reason naming the solver where some bootstrap replicates are no rotations or no
    solutions of their resamples (no radius then), or None."""
    unfit = np.zeros_like(failed) if unfit is None else unfit
    if frozen:
        n = int((~(failed | reflection)).sum())
        return Reason("bootstrap_answers", "fail", float(n), 0.0,
                      f"solver {method!r} returned the answer on all the pairs, unchanged within {FROZEN_DEG:g} deg, "
                      f"on every one of the {n} bootstrap replicates although their pairs differ and leave up to "
                      f"{np.nanmax(fit[1]):.3g} deg: it ignores its input, so no radius is given (it would be zero) "
                      f"and its answer here is not to be trusted; use chordal_optimal")
    if not (failed.any() or reflection.any() or unfit.any()):
        return None
    parts = [f"declared a failure (NaN) on {int(failed.sum())}" if failed.any() else "",
             f"returned a reflection (det -1) on {int(reflection.sum())}" if reflection.any() else "",
             f"returned an answer that is no solution of its resample on {int(unfit.sum())}" if unfit.any() else ""]
    bad = int((failed | reflection | unfit).sum())
    why = "not a rotation" if not unfit.any() else "not a rotation, or not a solution," if (
        failed.any() or reflection.any()) else "not a solution"
    detail = ""
    if unfit.any():
        own, full = fit
        k = int(np.nanargmax(np.where(unfit, own / np.maximum(full, 1e-300), np.nan)))
        detail = (f" (worst: root-mean-square pair residual {own[k]:.3g} deg on its resample, where the answer on all "
                  f"the pairs leaves {full[k]:.3g} deg; a solution leaves at most {REPLICATE_FIT_FACTOR:g} times that "
                  f"+ {REPLICATE_FIT_FLOOR_DEG:g} deg)")
    return Reason("bootstrap_answers", "fail", float(bad), 0.0,
                  f"solver {method!r} " + " and ".join(p for p in parts if p) + f" of {failed.size} bootstrap "
                  f"replicates{detail}: its answer is {why} on resamples of these pairs, so no radius is given and "
                  f"its answer here is not to be trusted; use chordal_optimal")


@dataclass(frozen=True)
class Resampling:
    """How :func:`solve_pairs` measures the radius: ``n_bootstrap`` replicates from ``seed``,
    resampling moving blocks of ``block`` pairs (streams), or, with ``stations = (i, j, N[,
    labels])`` (pair ``k`` between static stations ``i_k`` and ``j_k``), resampling stations, whose
    median residual (or, with ``station_residual(R)``, whose own residual at the estimate ``R``) is
    also reported and judged; ``progress`` shows a progress bar."""

    n_bootstrap: int
    seed: int | None
    block: int = 1
    stations: tuple | None = None
    station_residual: Callable | None = None
    progress: bool = False


@dataclass(frozen=True)
class Provenance:
    """What :func:`solve_pairs` carries into the report unjudged: the pairing ``interval`` (s, NaN
    for poses), the clock (``time_offset = (offset, correlation, applied)``, its 95 % interval and
    peak margin), the change test's report, the call's ``parameters`` and ``inputs``, each pair's
    start time and further diagnostics."""

    interval: float = math.nan
    time_offset: tuple = (math.nan, math.nan, False)
    time_offset_ci95_s: tuple = (math.nan, math.nan)
    time_offset_peak_margin: float = math.nan
    change_test: dict | None = None
    parameters: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    pair_times: np.ndarray | None = None
    extra_diagnostics: dict | None = None


def solve_pairs(A, B, *, method: str, options: dict, reference, evidence: dict, resampling: Resampling,
                provenance: Provenance):
    """Solve, residuals, bootstrap, verdict: a :class:`~replication.rig.report.CalibrationResult`.

    ``method(**options)`` solves the pairs, ``reference`` (one rotation, two stacked, or None) and
    ``evidence`` (the caller's measurements, :class:`~replication.rig.quality.Evidence`'s fields)
    join the verdict; the radius is measured as ``resampling`` says (:class:`Resampling`);
    ``provenance`` goes into the report (:class:`Provenance`).
    """
    n_bootstrap, seed, block, stations, station_residual, progress = (
        resampling.n_bootstrap, resampling.seed, resampling.block, resampling.stations, resampling.station_residual,
        resampling.progress)
    interval, time_offset, time_offset_ci95_s, time_offset_peak_margin, change_test = (
        provenance.interval, provenance.time_offset, provenance.time_offset_ci95_s,
        provenance.time_offset_peak_margin, provenance.change_test)
    parameters, inputs, pair_times, extra_diagnostics = (
        provenance.parameters, provenance.inputs, provenance.pair_times, provenance.extra_diagnostics)
    motions = prepare_motions(A, B)  # validated once: the solve and every bootstrap replicate use it
    references = None if reference is None or np.ndim(reference) == 2 else np.asarray(reference)
    if references is not None:  # two references: the old fields and the first check use the first
        reference = references[0]
        inputs = {**inputs, "second_reference_camera_from_sensor": references[1]}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ReplicationWarning)
        sol = solve(method, motions, full_output=True, **options)
    ours = [w for w in caught if issubclass(w.category, ReplicationWarning)]
    for w in caught:  # still said to the caller, as solve() says it
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    R = sol.R
    if not np.isfinite(R).all() or not np.linalg.det(R) > 0:  # solve() warned; a calibration needs a rotation
        what = "declared a failure (returned NaN)" if not np.isfinite(R).all() else "returned a reflection (det -1)"
        raise SolverAnswerError(f"solver {method!r} {what} on these {len(A)} pairs: no rotation to calibrate with "
                                f"(its warning: {ours[-1].message if ours else 'none'}); use chordal_optimal")
    res = pair_residual_deg(R, A, B)
    J = len(A)
    rng = np.random.default_rng(seed)
    repeats = _repeats(stations)
    if stations is not None and (parameters.get("pairs", "all") == "all" or repeats is not None):
        distinct = len(np.unique(stations[3])) if len(stations) > 3 else stations[2]
        units, resamples = float(distinct), "stations" if repeats is None else "distinct stations (repeats as one)"
        index_sets = (lambda: station_indices(rng, stations, n_bootstrap))
    else:
        block = 2 if stations is not None else block
        units = J / int(min(J, block))
        resamples = f"pairs in moving blocks of {int(min(J, block))}"
        index_sets = (lambda: block_indices(rng, J, block, n_bootstrap))
    ci, boot = float("nan"), np.empty((0, 3))
    boot_failed, bad_replicates = None, None
    if n_bootstrap and units >= 3:
        try:
            sets = index_sets()
            R_boot, bad_replicates = bootstrap_replicates(motions, method, options, sets, progress=progress,
                                                          masks="reason", fit_to=R)
        except SolverAnswerError:  # the solver broke its contract: the registry's error, naming it
            raise
        except ValueError as err:  # a resample of few pairs can be degenerate: no radius, and say why
            boot_failed = str(err).split(":")[0]
        else:
            if bad_replicates is None:  # never a radius from non-rotations
                ci = float(np.percentile(so3.angle_between_deg(R_boot, R), 95))
                boot = np.degrees(so3.rotation_vector_from_matrix(R_boot @ R.T))
    motion = float(np.median(so3.rotation_angle_deg(A)))
    station_medians = None if stations is None else (per_station_median(res, stations) if station_residual is None
                                                     else station_residual(R))
    verdict = judge(Evidence(n_pairs=J, residual_median_deg=float(np.median(res)), motion_median_deg=motion,
                             bootstrap_deg=ci if math.isfinite(ci) else None,
                             axis_spread_deg=float(sol.observability.camera_axis_spread_deg),
                             warnings=tuple(w.category.__name__ for w in ours),
                             spectral_ratio=float(sol.observability.spectral_ratio), method=method,
                             blocks=units if n_bootstrap else None, bootstrap_failed=boot_failed,
                             reference_error_deg=(None if reference is None
                                                  else float(so3.angle_between_deg(R, reference))),
                             pose_residual_medians_deg=None if station_medians is None else tuple(station_medians),
                             pose_residual_kind=("its own residual" if station_residual else
                                                 "median residual of its pairs"),
                             **evidence),
                    extra=[r for r in (bad_replicates, _repeats_reason(repeats), _second_reason(R, references))
                           if r is not None])
    offset, corr, applied = time_offset
    diagnostics = {"pair_times": pair_times, "residuals_deg": res, "bootstrap_rotvec_deg": boot,
                   "motion_median_deg": motion}
    if station_medians is not None:
        diagnostics.update(pose_residual_median_deg=station_medians, station_pairs=(stations[0], stations[1]))
    diagnostics.update(extra_diagnostics or {})
    return CalibrationResult(
        R=R,
        quaternion_wxyz=so3.quaternion_from_matrix(R),
        euler_zyx_deg=so3.yaw_pitch_roll_deg_from_matrix(R),
        method=method,
        interval_s=interval,
        n_pairs=int(J),
        time_offset_s=offset,
        time_offset_correlation=corr,
        time_offset_applied=applied,
        time_offset_ci95_s=tuple(float(v) for v in time_offset_ci95_s),
        time_offset_peak_margin=float(time_offset_peak_margin),
        change_test=change_test,
        residual_deg={"mean": float(res.mean()), "median": float(np.median(res)),
                      "rms": float(np.sqrt(np.mean(res ** 2))), "p95": float(np.percentile(res, 95)),
                      "max": float(res.max())},
        bootstrap_ci95_deg=ci,
        observability=sol.observability,
        reference_error_deg=None if reference is None else float(so3.angle_between_deg(R, reference)),
        **_two_references(R, references, ci),
        verdict=verdict,
        warnings=tuple(f"{w.category.__name__}: {w.message}" for w in ours),
        parameters=parameters,
        inputs=inputs,
        bootstrap_resamples=resamples if n_bootstrap else "none",
        bootstrap_covers=RADIUS_COVERS,
        pose_residual_median_deg=None if station_medians is None else station_medians.tolist(),
        station_repeats=repeats,
        diagnostics=diagnostics,
    )


def _two_references(R, references, radius_deg: float = float("nan")) -> dict:
    """The result's fields for two references: each error, their disagreement and the reading it
    allows (with R0's 95 % radius, :func:`reference_reading`)."""
    if references is None:
        return {}
    errors = tuple(float(so3.angle_between_deg(R, ref)) for ref in references)
    disagreement = float(so3.angle_between_deg(references[0], references[1]))
    return {"reference_errors_deg": errors, "reference_disagreement_deg": disagreement,
            "reference_reading": reference_reading(errors, disagreement, radius_deg)}


def _second_reason(R, references):
    """The reference check of the second reference (the first is judged as a single one)."""
    if references is None:
        return None
    found = judge(Evidence(n_pairs=10 ** 6, residual_median_deg=None, motion_median_deg=None, bootstrap_deg=None,
                           reference_error_deg=float(so3.angle_between_deg(R, references[1])))).reasons
    return next((dataclasses.replace(r, check="second_reference_error_deg",
                                     message=r.message.replace("the given reference", "the second reference"))
                 for r in found if r.check == "reference_error_deg"), None)


def with_reasons(result: CalibrationResult, reasons) -> CalibrationResult:
    """``result`` with further verdict reasons (the verdict's level follows)."""
    return dataclasses.replace(result, verdict=Verdict.of((*result.verdict.reasons, *reasons)))
