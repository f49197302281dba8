"""What the online estimator decides about pairs that do not fit its running picture: a pair that
repeats an earlier one (:class:`RepeatFilter`), and an alarm of its change detector
(:class:`OnlineEvent`, with the window solves behind it: the pairs after an alarm solved on their
own and compared with the estimate). Theory and measured numbers: ``docs/judging.md``, section
``replication.rig.online_events``."""
from __future__ import annotations

import math
import warnings
from collections import deque
from dataclasses import dataclass

import numpy as np

from ..core.so3 import angle_between_deg
from ..core.stats import chi2_quantile, radius_deg
from .online_guard import MisfitGuard

__all__ = ["OnlineEvent", "EVENT_KINDS", "RepeatFilter", "DUPLICATE_DEG", "SMALL_MOTION_DEG", "DUPLICATE_MEMORY",
           "REPEAT_NOISE_SHARE", "REPEAT_MAX_FACTOR",
           "ChangeDetector", "CONFIRM_LEVEL", "NOISE_Z", "TRIM_FACTOR", "solve_window", "pair_d2", "classify",
           "drift_test", "combined_threshold", "describe", "residual_angle_deg"]

#: Kinds of :class:`OnlineEvent`: the four :func:`classify` tells apart, in the order it tests them,
#: ``drift`` (a re-mount that continues the last one:
#: :func:`replication.rig.online_drift.recognise_drift`) and ``drift_end`` (a drift followed that
#: stopped: :func:`replication.rig.online_drift.track_drift`), and ``clock_jump`` (a
#: ``noise_change`` or ``outliers`` after which the live rig measured another clock offset:
#: :mod:`replication.rig.online_clock`).
EVENT_KINDS = ("remount", "noise_change", "outliers", "new_information", "drift", "drift_end", "clock_jump")
#: Level of the combined error radius a window's estimate must leave to be a re-mount.
CONFIRM_LEVEL = 0.999
#: Level of the test that the window's pairs do not fit the old estimate at the old level (a
#: re-mount needs both).
FIT_LEVEL = 0.9
#: In-control ``d^2 / m`` is about ``chi^2_3 / 3`` (median 0.79). A window whose median at its own
#: best fit is above this (RMS residual about 1.6 times the old level) has a new noise level.
NOISE_Z = 2.0
#: A window's pairs whose ``d^2`` exceeds this many times the window's median are trimmed before its
#: estimate is re-solved (outlier pairs inside the window).
TRIM_FACTOR = 9.0


#: Two pairs whose camera motions and sensor motions agree within this (deg, elementwise on the
#: matrices, i.e. about an angle) are one pair repeated: independent measurements of real motion
#: never agree that closely in all six degrees of freedom (the sensors' noise over a pairing
#: interval is 0.005-0.5 deg).
DUPLICATE_DEG = 0.01
#: Once the pairs' noise ``s`` (RMS residual) is known, a pair within this share of ``s`` of an
#: earlier one is a repeat too (a copy jittered far below the noise has the same noise), at most
#: :data:`REPEAT_MAX_FACTOR` x ``duplicate_deg``: independent measurements of one motion differ by
#: about ``0.6 s`` per axis (all six within ``0.1 s``: odds < 1e-5).
REPEAT_NOISE_SHARE = 0.1
REPEAT_MAX_FACTOR = 5.0
#: Pairs whose camera and sensor motions are both below this (deg) are never called repeats (a rig
#: at rest).
SMALL_MOTION_DEG = 0.5
#: Pairs between the onset of a suspected change and its alarm that are kept (the CUSUM rises for at
#: most ``h / (cap - k)`` pairs after a jump; more are only kept after a slow drift).
SINCE_ONSET = 64
#: Width of the repeat test's grid cells, in tolerances (wide: a pair is rarely near a cell edge, so
#: one look-up).
CELL_TOLERANCES = 16.0
#: Most distinct pairs remembered for the repeat test (about 0.3 kB each, 15 MB in all): 14 h at one
#: pair per second.
DUPLICATE_MEMORY = 50_000


_STAY, _DOWN, _UP = (0,), (0, -1), (0, 1)
_KEY = 1 << 40  # a cell's three integer coordinates as one integer key (|coordinate| < 2**39 for rotations)


class RepeatFilter:
    """Remembers the pairs seen and tells whether a new one repeats one of them (within ``tol_deg``
    elementwise on both rotation matrices; ``tol_deg = 0``: exact repeats only). Pairs whose camera
    and sensor motions are both below :data:`SMALL_MOTION_DEG` are never repeats.

    O(1) per pair: a grid on the sensor motion's antisymmetric part, cells of
    :data:`CELL_TOLERANCES` ``tol`` per axis; a pair within ``tol`` lies in this pair's cell or,
    where this pair is within ``tol`` of the cell's edge on an axis, in the neighbour across it
    (mostly one look-up, at most 8). The first :data:`DUPLICATE_MEMORY` distinct pairs are
    remembered (18 floats each in one array, about 0.3 kB per pair with the grid); later ones are
    compared, not remembered.
    """

    def __init__(self, tol_deg: float = DUPLICATE_DEG):
        self._tol = self._tol0 = math.radians(tol_deg)
        self._inv = 1.0 / (CELL_TOLERANCES * REPEAT_MAX_FACTOR * self._tol) if self._tol else 0.0  # the widest
        self._small_trace = 1.0 + 2.0 * math.cos(math.radians(SMALL_MOTION_DEG))
        self._cells: dict = {}              # cell key -> row index, or list of row indices
        self._rows = np.empty((64, 18))      # the remembered pairs (flat A, flat B), grown by doubling
        self.remembered = 0

    def _remember(self, key, values) -> None:
        if self.remembered >= DUPLICATE_MEMORY:
            return
        if self.remembered == len(self._rows):
            self._rows = np.concatenate([self._rows, np.empty_like(self._rows)])[:DUPLICATE_MEMORY]
        self._rows[self.remembered] = values
        held = self._cells.get(key)
        self._cells[key] = self.remembered if held is None else (
            [held, self.remembered] if isinstance(held, int) else held + [self.remembered])
        self.remembered += 1

    def set_noise(self, rms_deg: float) -> None:
        """The pairs' RMS residual (deg): the tolerance becomes :data:`REPEAT_NOISE_SHARE` of it,
        never below the one given nor above :data:`REPEAT_MAX_FACTOR` times it (exact repeats only
        stay exact)."""
        if self._tol0:
            self._tol = min(max(self._tol0, REPEAT_NOISE_SHARE * math.radians(rms_deg)), REPEAT_MAX_FACTOR * self._tol0)

    tolerance_deg = property(lambda self: math.degrees(self._tol), doc="The tolerance in use (deg).")

    def seen(self, fa, fb) -> bool:
        """Whether the pair (row-major flat ``A`` and ``B``, lists of 9 floats) repeats an earlier
        one; remembers it if not."""
        small = self._small_trace
        if fa[0] + fa[4] + fa[8] > small and fb[0] + fb[4] + fb[8] > small:
            return False  # a rig at rest repeats the identity with independent noise: not a repeat
        tol, cells = self._tol, self._cells
        if tol == 0.0:
            key = tuple(fa + fb)
            if key in cells:
                return True
            self._remember(key, fa + fb)
            return False
        inv, edge = self._inv, tol * self._inv  # a cell spans CELL_TOLERANCES times the widest tolerance
        x, y, z = 0.5 * (fb[7] - fb[5]) * inv, 0.5 * (fb[2] - fb[6]) * inv, 0.5 * (fb[3] - fb[1]) * inv
        bx, by, bz = math.floor(x), math.floor(y), math.floor(z)
        x, y, z = x - bx, y - by, z - bz
        for dx in (_DOWN if x < edge else _UP if x >= 1.0 - edge else _STAY):  # a repeat edge away is a neighbour
            for dy in (_DOWN if y < edge else _UP if y >= 1.0 - edge else _STAY):
                for dz in (_DOWN if z < edge else _UP if z >= 1.0 - edge else _STAY):
                    held = cells.get(((bx + dx) * _KEY + by + dy) * _KEY + bz + dz)
                    if held is not None:
                        rows = self._rows[held if isinstance(held, list) else [held]]
                        if np.any(np.abs(rows - np.array(fa + fb)).max(axis=1) <= tol):
                            return True
        self._remember((bx * _KEY + by) * _KEY + bz, fa + fb)
        return False


@dataclass(frozen=True)
class OnlineEvent:
    """A change-detector alarm, confirmed on the pairs after it and classified (see the module
    notes)."""

    kind: str                   # one of EVENT_KINDS
    pair: int                   # pair index (over the calibrator's life) where it was decided
    alarm_pair: int             # where the alarm was raised
    source: str                 # what raised it: "cusum" (the residuals jumped) or "drift" (the drift test)
    onset_pair: int             # the first pair after the CUSUM last stood at 0 (where the change likely began)
    window_pairs: int           # pairs in the confirmation window
    angle_deg: float            # angle between the estimate before and the window's own estimate
    threshold_deg: float        # the combined radius (CONFIRM_LEVEL) the angle was tested against
    median_z_before: float      # median d^2 / m of the window at the estimate before
    median_z_after: float       # ... at the window's own estimate
    pairs_dropped: int          # pairs kept out of the estimate (outliers)
    R_before: np.ndarray
    R_after: np.ndarray
    message: str
    rate_deg_per_pair: float | None = None   # drift: how fast the frame moves (deg per pair)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "pair": self.pair, "alarm_pair": self.alarm_pair, "source": self.source,
                "onset_pair": self.onset_pair, "window_pairs": self.window_pairs, "angle_deg": self.angle_deg,
                "threshold_deg": self.threshold_deg, "median_z_before": self.median_z_before,
                "median_z_after": self.median_z_after, "pairs_dropped": self.pairs_dropped,
                "R_before": self.R_before.tolist(), "R_after": self.R_after.tolist(), "message": self.message,
                "rate_deg_per_pair": self.rate_deg_per_pair}


def pair_d2(R, A, B) -> np.ndarray:
    """``||A_j R - R B_j||_F^2`` of every pair (``8 sin^2(theta_j / 2)``, ``theta_j`` the residual
    angle)."""
    return 6.0 - 2.0 * np.einsum("jab,jab->j", A @ R, R @ B)


def residual_angle_deg(d2: float) -> float:
    """The residual rotation angle (deg) of a pair from its ``d^2 = 8 sin^2(theta / 2)``."""
    return math.degrees(2.0 * math.asin(min(1.0, math.sqrt(max(d2, 0.0) / 8.0))))


def _excitation_deg(B) -> float:
    n = len(B)
    G = 2.0 * n * np.eye(3) - B.sum(axis=0) - np.swapaxes(B, -1, -2).sum(axis=0)
    return math.degrees(math.sqrt(max(float(np.linalg.eigvalsh(G)[0]), 0.0) / n)), G


def solve_window(A, B, *, min_excitation_deg: float, s2_floor: float, d2_floor: float):
    """A window of pairs solved on its own: ``(R, keep, cov)``.

    A consensus first (``robust``: MSAC over two-pair samples, then Cauchy IRLS), so that outlier
    pairs inside the window do not move it; then the minimiser of eq. (8) over the pairs within
    :data:`TRIM_FACTOR` times the median ``d^2`` of that consensus (the certified
    ``chordal_optimal``; ``keep`` marks them). ``cov`` is the estimate's covariance ``(s^2 / 3)
    G^{-1}`` over the kept pairs, ``s^2`` their mean square residual, never below ``s2_floor`` (the
    estimate's own noise level: from a handful of pairs ``s^2`` is too uncertain to lower the
    threshold a re-mount must pass); None where the window does not determine ``R0`` (excitation
    below ``min_excitation_deg``, fewer than 5 pairs or half the window kept, a degenerate solve):
    then no re-mount can be confirmed from it.
    """
    from ..core.solvers import solve

    keep = np.ones(len(A), bool)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            R = solve("robust", A, B)
            d2 = pair_d2(R, A, B)
            keep = d2 <= TRIM_FACTOR * max(float(np.median(d2)), d2_floor)
            if keep.sum() < max(5, len(A) / 2):
                return R, keep, None
            R = solve("chordal_optimal", A[keep], B[keep])
    except ValueError:  # the window alone is degenerate (e.g. single-axis)
        return np.eye(3), keep, None
    n = int(keep.sum())
    excitation, G = _excitation_deg(B[keep])
    if excitation < min_excitation_deg:
        return R, keep, None
    s2 = max(float(np.mean(pair_d2(R, A[keep], B[keep]))) / 2.0 * n / (n - 3.0), s2_floor)
    return R, keep, (s2 / 3.0) * np.linalg.inv(G)


def combined_threshold(cov_a, cov_b) -> float:
    """The :data:`CONFIRM_LEVEL` radius (deg) of the difference of two independent estimates
    (``inf`` if either covariance is unknown)."""
    if cov_a is None or cov_b is None:
        return math.inf
    return radius_deg(cov_a + cov_b, CONFIRM_LEVEL)


def classify(R_old, cov_old, s2_old, m, A, B, *, cap, min_excitation_deg, d2_floor):
    """Classify a confirmation window ``(A, B)`` against the estimate ``R_old`` (covariance
    ``cov_old``, mean square residual ``s2_old``) and the reference level ``m`` (see the module
    notes).

    Returns
    -------
    dict
        ``kind`` (one of :data:`EVENT_KINDS`), ``undecided`` (the angle lies between half the
        threshold and the threshold: more pairs may show a small re-mount), ``R_new``, ``keep``,
        ``angle_deg``, ``threshold_deg``, ``z_old``, ``z_new`` (``d^2 / m`` of each window pair at
        each estimate), ``median_z_before``, ``median_z_after`` and ``level_new`` (the window's mean
        ``d^2`` at its own estimate, kept pairs).
    """
    R_new, keep, cov_new = solve_window(A, B, min_excitation_deg=min_excitation_deg, s2_floor=s2_old,
                                        d2_floor=d2_floor)
    if cov_new is None:
        R_new = R_old
    d2_old, d2_new = pair_d2(R_old, A, B), pair_d2(R_new, A, B)
    angle = float(angle_between_deg(R_old, R_new))
    threshold = combined_threshold(cov_old, cov_new)
    z_old, z_new = d2_old / m, d2_new / m
    med_old, med_new = float(np.median(z_old)), float(np.median(z_new))
    gross = z_old > cap
    # the pairs the window's own estimate keeps must not fit the old estimate at its noise level
    # s2_old (the mean square residual angle over every pair in it; the detector's reference level m
    # follows slow changes): their sum of 3 d^2 / (2 s2_old), about chi^2_{3n} in control, above its
    # FIT_LEVEL quantile
    n = int(keep.sum())
    misfit = 1.5 * float(np.sum(d2_old[keep])) / s2_old > chi2_quantile(FIT_LEVEL, 3 * n)
    if angle > threshold and med_new <= cap and misfit:
        kind = "remount"
    elif gross.any() and (gross.all() or float(np.median(z_old[~gross])) <= NOISE_Z):
        kind = "outliers"  # the window's pairs either fit the estimate at the old level or are gross outliers
    elif med_new > NOISE_Z:
        kind = "noise_change"
    elif med_old <= NOISE_Z:
        kind = "outliers"
    else:
        kind = "new_information"
    # close to a re-mount (more than half the threshold away, or beyond it but fitting the old
    # estimate): more pairs may decide
    return {"kind": kind, "undecided": kind != "remount" and angle > 0.5 * threshold, "R_new": R_new, "keep": keep,
            "angle_deg": angle, "threshold_deg": threshold, "z_old": z_old, "z_new": z_new,
            "median_z_before": med_old, "median_z_after": med_new,
            "level_new": max(float(np.mean(d2_new[keep])), d2_floor)}


def drift_test(R, cov, s2_old, A, B, *, min_excitation_deg) -> tuple[bool, float, float]:
    """Whether the last pairs ``(A, B)`` (already in the estimate) agree on another rotation than
    the estimate ``R`` (covariance ``cov``). Returns ``(alarm, angle_deg, threshold_deg)``.

    One Gauss-Newton step from ``R`` on the window's own pairs, in closed form: at ``R exp([w]x)``
    pair ``j``'s residual rotation vector is about ``r_j - (I - B_j) w`` (``r_j`` the vee of the
    antisymmetric part of ``R^T A_j R B_j^T``), so the window's estimate is ``w = G^{-1} sum_j (I -
    B_j^T) r_j`` with covariance ``(s^2 / 3) G^{-1}`` (``s^2`` the window's mean square residual
    after the step, ``n / (n - 3)`` corrected, never below the estimate's own ``s2_old``). An alarm
    when ``|w|`` exceeds the :data:`CONFIRM_LEVEL` combined radius; cheap (no solver, no per-pair
    Python), and it is confirmed on the pairs after it.
    """
    if cov is None:
        return False, math.nan, math.inf
    n = len(A)
    E = np.swapaxes(R, -1, -2) @ A @ R @ np.swapaxes(B, -1, -2)
    r = 0.5 * np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=-1)
    SB = B.sum(axis=0)
    G = 2.0 * n * np.eye(3) - SB - SB.T
    lam = np.linalg.eigvalsh(G)
    if math.degrees(math.sqrt(max(float(lam[0]), 0.0) / n)) < min_excitation_deg:
        return False, math.nan, math.inf
    w = np.linalg.solve(G, r.sum(axis=0) - np.einsum("jba,jb->a", B, r))
    e = r - (w - np.einsum("jab,b->ja", B, w))
    s2 = max(float(np.einsum("ja,ja->", e, e)) / (n - 3.0), s2_old)
    angle = math.degrees(float(np.linalg.norm(w)))
    threshold = combined_threshold(cov, (s2 / 3.0) * np.linalg.inv(G))
    return angle > threshold, angle, threshold


def describe(kind: str, info: dict, n_window: int, dropped: int) -> str:
    """One sentence for an event, with its numbers."""
    a, t = info["angle_deg"], info["threshold_deg"]
    return {
        "remount": f"the {n_window} pairs after the alarm agree on a new R0 {a:.3g} deg from the estimate (> {t:.3g} "
                   f"deg, the {100 * CONFIRM_LEVEL:g} % combined radius): re-mounted; started over",
        "noise_change": f"no new R0 ({a:.3g} deg <= {t:.3g} deg), but the {n_window} pairs fit no rotation at the old "
                        f"noise level (median d^2/m {info['median_z_after']:.3g} > {NOISE_Z:g}): the noise level "
                        f"changed",
        "outliers": f"no new R0 ({a:.3g} deg <= {t:.3g} deg) and most of the {n_window} pairs still fit the estimate "
                    f"(median d^2/m {info['median_z_before']:.3g} <= {NOISE_Z:g}): outlier pairs, {dropped} kept out",
        "new_information": f"{'at least half of ' if dropped else ''}the {n_window} pairs fit a rotation {a:.3g} deg "
                           f"away, within the combined radius {t:.3g} deg, better than the estimate (median d^2/m "
                           f"{info['median_z_after']:.3g} vs {info['median_z_before']:.3g}): new information "
                           f"(typically better-excited motion), added"
                           + (f"; {dropped} pairs that do not fit it kept out" if dropped else ""),
    }[kind]


class ChangeDetector:
    """The online estimator's change detector (see :mod:`replication.rig.online`'s notes): a CUSUM
    on the pair residuals against a reference level, the drift test, the confirmation window after
    an alarm, and its decision (:func:`classify`). It holds no estimate:
    :class:`replication.rig.online.OnlineCalibrator` passes its estimate and covariance in, adds the
    pairs it is told to add, and acts on the decisions.

    Attributes
    ----------
    armed : bool
        Running (once the motion determines ``R0``).
    level : float
        The reference level ``m`` of ``d^2``.
    checking : bool
        An alarm is being confirmed (the pairs go to the window, not the estimate).
    """

    def __init__(self, *, k: float, h: float, cap: float, reference_rate: float, confirm_pairs: int,
                 max_confirm_pairs: int, drift_pairs: int, min_excitation_deg: float, noise_floor_deg: float,
                 d2_floor: float):
        self.k, self.h, self.cap, self.rate = k, h, cap, reference_rate
        self.confirm_pairs, self.max_confirm_pairs, self.drift_pairs = confirm_pairs, max_confirm_pairs, drift_pairs
        self.min_excitation_deg, self.noise_floor_deg, self.d2_floor = min_excitation_deg, noise_floor_deg, d2_floor
        self.reset()

    def reset(self) -> None:
        """Forget everything (a start, or a re-mount)."""
        self.armed, self.level, self.cusum = False, math.nan, 0.0
        self.checking, self.window, self.target = False, [], self.confirm_pairs
        self.alarm_pair, self.source, self.onset = None, None, 0
        self.since_onset = deque(maxlen=SINCE_ONSET)   # (A, B, held out) since the sum last stood at 0
        self.guard = MisfitGuard(SINCE_ONSET)           # those not held out, tested against the estimate
        self.recent = deque(maxlen=self.drift_pairs)    # the drift test's window: the last pairs added
        self.since_drift = 0

    @property
    def misfits(self) -> int:
        """Pairs held out as gross misfits (``d^2`` above ``cap`` times the level) since the CUSUM
        last stood at 0: the start of a change or of an outlier burst that the CUSUM has not decided
        yet."""
        return sum(held for *_, held in self.since_onset) if self.cusum > 0.0 else 0

    def undecided(self, misfits: int):
        """A warning :class:`replication.rig.quality.Reason` when a stream stops while this detector
        is undecided (an alarm being confirmed, or at least ``misfits`` gross misfits since the
        CUSUM last stood at 0), else None: a change of ``R0`` in the last pairs can be neither
        confirmed nor ruled out."""
        from .quality import Reason

        if self.checking:
            return Reason("end_undecided", "warning", float(len(self.window)), float(self.target),
                          f"the stream ended while an alarm (pair {self.alarm_pair}) was being confirmed, "
                          f"{len(self.window)} of {self.target} pairs: a change of R0 at the end is neither confirmed "
                          f"nor ruled out; the estimate is the one before the alarm (record longer)")
        if self.misfits >= misfits:
            return Reason("end_undecided", "warning", float(self.misfits), float(misfits),
                          f"the last {len(self.since_onset)} pairs include {self.misfits} that do not fit the estimate "
                          f"(d^2 above {self.cap:g} x its level; CUSUM {self.cusum:.3g} of {self.h:g}) when the stream "
                          f"ended: a change of R0 at the end is neither confirmed nor ruled out (record longer)")
        return None

    def arm(self, level: float, index: int) -> None:
        """Start (or restart) at reference level ``level``; ``index`` is the next pair's."""
        self.armed, self.level, self.cusum = True, max(level, self.d2_floor), 0.0
        self.since_onset.clear()
        self.guard.clear()
        self.onset = index

    def observe(self, A, B, d2: float, index: int, R, cov, s2) -> tuple[bool, bool]:
        """One pair (``index``) with residual ``d2`` at the estimate ``R`` (covariance ``cov``, mean
        square residual ``s2``). Returns ``(add, decide)``: whether the calibrator adds it to its
        sums, and whether the confirmation window is complete (call :meth:`decide`)."""
        if self.checking:
            self.window.append((A, B))
            return False, len(self.window) >= self.target
        mean = max(self.level, self.d2_floor)
        z = d2 / mean
        self.cusum = max(0.0, self.cusum + min(z, self.cap) - self.k)
        if self.cusum <= self.h / 3:  # no change building up: the reference follows the residual level
            self.level += self.rate * (min(d2, self.cap * mean) - self.level)
        held = z > self.cap  # a gross outlier stays out of the sums
        self.since_onset.append((A, B, held))
        if not held:
            self.recent.append((A, B))
            self.since_drift += 1
        if not held and s2 is not None:  # the guard tests the pair against the estimate (s2: its noise)
            self.guard.add(A, B, d2, R, cov, s2, self.recent)
        if self.cusum == 0.0:
            self.since_onset.clear()
            self.onset = index + 1
        elif self.cusum > self.h:
            self._alarm(index, "cusum")
        elif self.since_drift >= self.drift_pairs // 2 and len(self.recent) == self.drift_pairs:
            self.since_drift = 0
            A_w = np.array([a for a, _ in self.recent])
            B_w = np.array([b for _, b in self.recent])
            if drift_test(R, cov, s2, A_w, B_w, min_excitation_deg=self.min_excitation_deg)[0]:
                self._alarm(index, "drift")
        return not held, False

    def _alarm(self, index: int, source: str) -> None:
        # a jump (CUSUM) shows in a few pairs; a drift was seen in drift_pairs pairs and needs more
        # than a few
        self.checking, self.alarm_pair, self.source = True, index, source
        self.window = []
        self.target = self.confirm_pairs if source == "cusum" else min(self.drift_pairs // 2, self.max_confirm_pairs)

    def decide(self, R_old, cov_old, s2_old, index: int):
        """The confirmation window's decision (:func:`classify`), or None while it waits for more
        pairs. Returns a dict: ``event`` (:class:`OnlineEvent`), ``restart`` (a re-mount: start over
        from ``R_new``), ``kept`` (the pairs to add: the window's and the held-out ones that fit),
        ``held_before`` (pairs held out before the alarm, already counted as dropped)."""
        A = np.array([a for a, _ in self.window])
        B = np.array([b for _, b in self.window])
        m = max(self.level, self.d2_floor)
        info = classify(R_old, cov_old, s2_old, m, A, B, cap=self.cap, min_excitation_deg=self.min_excitation_deg,
                        d2_floor=self.d2_floor)
        if info["undecided"] and len(A) < self.max_confirm_pairs:
            self.target = min(len(A) + self.confirm_pairs, self.max_confirm_pairs)
            return None
        kind, R_new = info["kind"], info["R_new"]
        since = list(self.since_onset)
        held = [(a, b) for a, b, h in since if h]
        if kind == "remount":
            level = info["level_new"]
            candidates = [(a, b) for a, b, _ in since] + list(zip(A, B))
            fits = lambda a, b: pair_d2(R_new, a[None], b[None])[0] <= self.cap * level  # noqa: E731
        else:
            level = info["level_new"] if kind == "noise_change" else m
            candidates = held + list(zip(A, B))
            # new information: the pairs that fit the window's own estimate (a gross pair fits none)
            R_fit = R_new if kind == "new_information" else R_old
            fits = lambda a, b: pair_d2(R_fit, a[None], b[None])[0] <= self.cap * level  # noqa: E731
        kept = [(a, b) for a, b in candidates if fits(a, b)]
        dropped = len(candidates) - len(kept)
        event = OnlineEvent(kind, index, self.alarm_pair, self.source, self.onset, len(A), info["angle_deg"],
                            info["threshold_deg"], info["median_z_before"], info["median_z_after"], dropped,
                            np.array(R_old), np.array(R_new), describe(kind, info, len(A), dropped))
        if kind == "remount":
            self.reset()
        else:
            self.checking, self.window, self.cusum, self.level = False, [], 0.0, level
            self.since_onset.clear()
            self.guard.clear()
            self.onset, self.since_drift = index + 1, 0
        for pair in kept:
            self.recent.append(pair)
        return {"event": event, "restart": kind == "remount", "R_new": R_new, "kept": kept,
                "held_before": len(held), "rearm": kind == "new_information"}
