"""What keeps the online estimator's ``ready`` right between its decisions: the recent pairs
tested against the estimate and its radius (:func:`misfit_test`, :class:`MisfitGuard`), and the
sentences of ``not_ready`` (:func:`not_ready_reasons`). A frame that drifts is told from a re-mount
in :mod:`replication.rig.online_drift`. Theory and measured numbers: ``docs/judging.md``, section
``replication.rig.online_guard``."""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..core.stats import chi2_quantile

_EYE = np.eye(3)

__all__ = ["GUARD_LEVEL", "GUARD_CLEAR_LEVEL", "GUARD_MIN_PAIRS", "GUARD_K", "GUARD_WINDOW", "GUARD_EVERY",
           "GUARD_LONG_WINDOWS", "MisfitGuard", "misfit_test", "detector_reasons", "not_ready_reasons"]

#: Level of the region the recent pairs' own rotation must leave to withdraw ``ready`` (checked
#: after every pair of a suspected change, so stricter than the detector's
#: :data:`replication.rig.online_events.CONFIRM_LEVEL`).
GUARD_LEVEL = 0.9999
#: Fewest pairs since the CUSUM last stood at 0 that are tested (3 unknowns; fewer pairs say little
#: about a rotation).
GUARD_MIN_PAIRS = 3
#: The last this many pairs are tested together every :data:`GUARD_EVERY` pairs (a shift too small
#: to show in any one pair's residual: 1 deg at 0.5 deg of noise needs about 8 pairs at
#: :data:`GUARD_LEVEL`).
GUARD_WINDOW = 20
#: Pairs between two tests of the last :data:`GUARD_WINDOW` (each costs about 100 us: 5 us per
#: pair).
GUARD_EVERY = 20
#: Longer windows: the last 80, 160 and 320 pairs. A re-mount smaller than the pair noise (0.55-0.9
#: deg at 1 deg of noise) shows in no 20 pairs: the statistic grows with the window (about ``N
#: angle^2 / s^2``); 0.55 deg at 1 deg of noise passes :data:`GUARD_LEVEL` in about 120 pairs.
GUARD_LONG_WINDOWS = (80, 160, 320)
#: The long windows are tested together every this many pairs, on block sums of this many pairs
#: (about 50 us a test, 100 us after a refinement: 3-5 us a pair).
GUARD_LONG_EVERY = 20
#: A window that withdrew ``ready`` keeps it withdrawn until a later window's statistic is below
#: this quantile of ``chi^2_3`` (a window that fits as usual): between the two levels the shift is
#: neither shown nor ruled out (a 1 deg re-mount at 0.2 deg of camera noise, absorbed by the
#: estimate without an alarm, was ready again 21 s later).
GUARD_CLEAR_LEVEL = 0.95
#: Allowance of the guard's own sum ``max(0, S + z - k)``, ``z = d^2 / (2 s^2)`` (about ``chi^2_3 /
#: 3``, mean 1, while the estimate holds): its window is the pairs since that sum last stood at 0.
#: Lower than the detector's allowance (2) so that a change whose residuals are only 1.5-2 times the
#: noise (1 deg at 0.5 deg of noise) keeps the window open.
GUARD_K = 1.5


def _misfit_vectors(R, A, B) -> np.ndarray:
    """Each pair's misfit of ``R`` as the axial vector of ``E = R^T A R B^T`` (times ``2 sin`` of
    its angle), (J, 3)."""
    E = np.swapaxes(R, -1, -2) @ A @ R @ np.swapaxes(B, -1, -2)
    return np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=-1)


def misfit_test(R, cov, s2, A, B) -> tuple[float, float]:
    """The pairs ``(A, B)`` solved on their own by one Gauss-Newton step from ``R`` (as
    :func:`replication.rig.online_events.drift_test`): ``(statistic, angle_deg)``, the statistic
    ``w^T (C_w + cov)^{-1} w`` (``C_w = (s^2 / 3) G_w^{-1}``, ``s^2`` the estimate's mean square
    residual ``s2``, ``cov`` its covariance or None), ``angle_deg = |w|`` in degrees; ``(0, nan)``
    where the pairs do not determine a rotation (``G_w`` singular)."""
    r = _misfit_vectors(R, A, B)
    SB = B.sum(axis=0)
    H = 2.0 * len(A) * _EYE - SB - SB.T
    g = 0.5 * (r.sum(axis=0) - np.einsum("jba,jb->a", B, r))
    return _statistic(g.tolist(), H.ravel().tolist(), s2, cov)


def _inv3(m):
    """Inverse of a 3x3 matrix given as 9 floats, row-major (plain Python: cheaper than numpy at
    this size); None if singular."""
    a, b, c, d, e, f, g, h, i = m
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * A + b * B + c * C
    if not det or not math.isfinite(det):
        return None
    k = 1.0 / det
    return [A * k, (c * h - b * i) * k, (b * f - c * e) * k, B * k, (a * i - c * g) * k, (c * d - a * f) * k,
            C * k, (b * g - a * h) * k, (a * e - b * d) * k]


def _mul3(m, v):
    return [m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
            m[6] * v[0] + m[7] * v[1] + m[8] * v[2]]


def _share(R, A, B):
    """A pair's share ``(g_j, H_j)`` of the Gauss-Newton step from ``R``: ``g_j = (I - B_j^T) r_j``
    (``r_j`` its residual rotation vector ``vee`` of the antisymmetric part of ``R^T A_j R B_j^T``)
    and ``H_j = 2I - B_j - B_j^T``, as plain floats (3 and 9, row-major)."""
    e = (R.T @ A @ R @ B.T).ravel().tolist()
    r = (0.5 * (e[7] - e[5]), 0.5 * (e[2] - e[6]), 0.5 * (e[3] - e[1]))
    b = B.ravel().tolist()
    g = [r[0] - b[0] * r[0] - b[3] * r[1] - b[6] * r[2], r[1] - b[1] * r[0] - b[4] * r[1] - b[7] * r[2],
         r[2] - b[2] * r[0] - b[5] * r[1] - b[8] * r[2]]
    H = [2.0 - 2.0 * b[0], -b[1] - b[3], -b[2] - b[6], -b[1] - b[3], 2.0 - 2.0 * b[4], -b[5] - b[7],
         -b[2] - b[6], -b[5] - b[7], 2.0 - 2.0 * b[8]]
    return g, H


def _statistic(g, H, s2, cov) -> tuple[float, float]:
    """``(w^T (C_w + cov)^{-1} w, |w| in deg)`` for ``w = H^{-1} g`` and ``C_w = (s2 / 3) H^{-1}``
    (9-float ``H``, 3-float ``g``, ``cov`` a 3x3 array or None); ``(0, nan)`` where ``H`` is
    singular."""
    Hi = _inv3(H)
    if Hi is None:
        return 0.0, math.nan
    w = _mul3(Hi, g)
    c = [0.0] * 9 if cov is None else cov.ravel().tolist()
    Ci = _inv3([s2 / 3.0 * x + y for x, y in zip(Hi, c)])
    if Ci is None:
        return 0.0, math.nan
    stat = sum(a * b for a, b in zip(w, _mul3(Ci, w)))
    if not math.isfinite(stat):
        return 0.0, math.nan
    return stat, math.degrees(math.sqrt(w[0] ** 2 + w[1] ** 2 + w[2] ** 2))


class MisfitGuard:
    """Tests the recent pairs against the estimate (see the module notes): the pairs since its own
    sum last stood at 0 after each pair (a run of residuals above the noise), and the last
    :data:`GUARD_WINDOW` pairs every :data:`GUARD_EVERY` pairs (a shift too small for any one pair's
    residual to show, seen in its direction).

    The change detector calls :meth:`add` for each pair it adds to the estimate (not the gross
    misfits it holds out) and :meth:`clear` when it decides or starts over. :attr:`misfit` is None
    while the pairs fit, else ``(pairs, angle_deg, statistic, threshold)`` of the test that withdrew
    ``ready``: the run's until its sum returns to 0, the window's until a later window fits as usual
    (:data:`GUARD_CLEAR_LEVEL`).
    """

    def __init__(self, maxlen: int, level: float = GUARD_LEVEL):
        self.level, self.threshold = level, chi2_quantile(level, 3)
        self.clear_threshold = chi2_quantile(GUARD_CLEAR_LEVEL, 3)
        self.pairs = deque(maxlen=maxlen)   # the run's pairs: [A, B, bound_j, (g_j, H_j) once computed]
        self._ring = np.empty((max(GUARD_LONG_WINDOWS), 2, 3, 3))  # the last pairs, for the long windows
        blocks = len(self._ring) // GUARD_LONG_EVERY  # the ring in blocks: their sums of B_j and of the shares g_j
        self._block_B, self._block_g = np.zeros((blocks, 3, 3)), np.zeros((blocks, 3))
        self._block_version, self._version, self._shares_R = np.full(blocks, -1), 0, None  # g_j at _shares_R
        self.forget()

    @property
    def misfit(self):
        return self.run_misfit or self.window_misfit or self.long_misfit

    @property
    def long_misfit(self):
        """The long window whose test withdrew ``ready`` (of several, the highest statistic), or
        None."""
        return self._long_worst

    def widen(self, radius: float) -> float:
        """The radius to publish: while the recent pairs agree on a rotation the radius does not
        allow, the estimate may be that far off (their angle added); else ``radius``."""
        m = self.misfit
        return radius if m is None or not math.isfinite(m[1]) else radius + m[1]

    def describe(self) -> str:
        """The sentence for ``not_ready`` while :attr:`misfit` is set."""
        n, angle, stat, threshold = self.misfit
        return (f"the last {n} pairs agree on a rotation {angle:.3g} deg from the estimate, beyond what its radius "
                f"allows (statistic {stat:.3g} > {threshold:.3g}, the {100 * self.level:g} % region of both): a "
                f"change, not decided yet")

    def clear(self) -> None:
        """Forget the run and the short window (a decision, a start); the long windows keep their
        pairs (still in the estimate) until :meth:`forget` (a re-mount: a new guard)."""
        self._clear_run()
        self.window_misfit, self._since_window = None, 0

    def forget(self) -> None:
        """Forget the long windows' pairs too."""
        self.clear()
        self._long = dict.fromkeys(GUARD_LONG_WINDOWS)     # per long window: its misfit or None
        self._long_worst = None
        self._count = 0      # pairs in the ring (since the last clear)

    def _clear_run(self) -> None:
        self.pairs.clear()
        self._g, self._H = [0.0] * 3, [0.0] * 9   # the run's sums of g_j = (I - B_j^T) r_j and H_j = 2I - B_j - B_j^T
        self._chi2 = 0.0     # its sum of 1.5 d^2 / s^2 (a bound on its statistic)
        self.sum = 0.0
        self.run_misfit = None

    def _scan(self, R, cov, s2, recent) -> None:
        self._since_window = 0
        window = np.array(list(recent)[-GUARD_WINDOW:])  # (n, 2, 3, 3): A and B
        stat, angle = misfit_test(R, cov, s2, window[:, 0], window[:, 1])
        if stat > self.threshold:
            self.window_misfit = (GUARD_WINDOW, angle, stat, self.threshold)
        elif stat <= self.clear_threshold:  # withdrawn until a window fits at a usual level (hysteresis)
            self.window_misfit = None

    def _scan_long(self, R, cov, s2) -> None:
        """The long windows (:data:`GUARD_LONG_WINDOWS`) the ring holds, tested together on block
        sums of :data:`GUARD_LONG_EVERY` pairs: each block's ``sum B_j`` once, its share of the
        Gauss-Newton step (:func:`misfit_test`) once per estimate (recomputed only after a
        refinement); a window sums its blocks."""
        every, count = GUARD_LONG_EVERY, self._count
        blocks = len(self._block_g)
        newest = (count // every - 1) % blocks
        pairs = np.arange(count - every, count) % len(self._ring)
        self._block_B[newest] = self._ring[pairs, 1].sum(axis=0)
        self._block_version[newest] = -1
        m = min(count, len(self._ring)) // every
        if m < GUARD_LONG_WINDOWS[0] // every:
            return
        if R is not self._shares_R:  # a new estimate: every block's share is stale
            self._shares_R, self._version = R, self._version + 1
        ids = (count // every - 1 - np.arange(m)) % blocks            # newest first
        stale = ids[self._block_version[ids] != self._version]
        if len(stale):
            at = ((stale * every)[:, None] + np.arange(every)).ravel()  # ring slots of those blocks' pairs
            A, B = self._ring[at, 0], self._ring[at, 1]
            r = _misfit_vectors(R, A, B)
            shares = 0.5 * (r - np.einsum("jba,jb->ja", B, r))
            self._block_g[stale] = shares.reshape(len(stale), every, 3).sum(axis=1)
            self._block_version[stale] = self._version
        g, SB = np.cumsum(self._block_g[ids], axis=0), np.cumsum(self._block_B[ids], axis=0)
        for n in GUARD_LONG_WINDOWS:
            k = n // every
            if k > m:
                break
            H = 2.0 * n * _EYE - SB[k - 1] - SB[k - 1].T
            stat, angle = _statistic(g[k - 1].tolist(), H.ravel().tolist(), s2, cov)
            if stat > self.threshold:
                self._long[n] = (n, angle, stat, self.threshold)
            elif stat <= self.clear_threshold:
                self._long[n] = None
        held = [m for m in self._long.values() if m is not None]
        self._long_worst = max(held, key=lambda m: m[2]) if held else None

    def add(self, A, B, d2: float, R, cov, s2: float, recent=()) -> None:
        """One pair added to the estimate (residual ``d2`` at ``R``; ``cov``, ``s2``: the estimate's
        covariance and mean square residual); ``recent``: the last pairs added, this one included (a
        sequence of ``(A, B)``)."""
        z = 0.5 * d2 / s2
        self._since_window += 1
        if self._since_window >= GUARD_EVERY and len(recent) >= GUARD_WINDOW:
            self._scan(R, cov, s2, recent)
        k = self._count % len(self._ring)
        self._ring[k, 0], self._ring[k, 1] = A, B
        self._count += 1
        if self._count % GUARD_LONG_EVERY == 0:
            self._scan_long(R, cov, s2)
        total = self.sum + z - GUARD_K
        if total <= 0.0:
            if self.sum:
                self._clear_run()
            return
        self.sum = total
        pairs = self.pairs
        if len(pairs) == pairs.maxlen:
            _, _, bound0, part = pairs[0]
            self._chi2 -= bound0
            if part is not None:
                self._g = [x - y for x, y in zip(self._g, part[0])]
                self._H = [x - y for x, y in zip(self._H, part[1])]
        bound = 3.0 * z
        pairs.append([A, B, bound, None])
        self._chi2 += bound
        if self.run_misfit is not None or len(pairs) < GUARD_MIN_PAIRS or self._chi2 <= self.threshold:
            return  # withdrawn until the sum returns to 0; or the run cannot pass the threshold
        for pair in pairs:  # the pairs' shares of the Gauss-Newton step, computed once a test is due
            if pair[3] is None:
                pair[3] = g, H = _share(R, pair[0], pair[1])
                self._g = [x + y for x, y in zip(self._g, g)]
                self._H = [x + y for x, y in zip(self._H, H)]
        stat, angle = _statistic(self._g, self._H, s2, cov)
        if stat > self.threshold:
            self.run_misfit = (len(pairs), angle, stat, self.threshold)


def detector_reasons(detector, misfits_withdraw: int) -> list[str]:
    """The sentences of ``not_ready`` the change detector
    (:class:`replication.rig.online_events.ChangeDetector`) and its guard give: a change being
    confirmed, ``misfits_withdraw`` gross misfits or more, the recent pairs' misfit."""
    why = []
    if detector.checking:
        why.append(f"a change is being confirmed ({len(detector.window)} of {detector.target} pairs)")
    elif detector.misfits >= misfits_withdraw:
        why.append(f"{detector.misfits} recent pairs do not fit the estimate (d^2 above {detector.cap:g} x its "
                   f"level): a change or outliers, not decided yet")
    if detector.guard.misfit is not None:
        why.append(detector.guard.describe())
    return why


def not_ready_reasons(cal, misfits_withdraw: int) -> list[str]:
    """The sentences of ``not_ready`` (:meth:`replication.rig.online.OnlineCalibrator.status`): one
    per unmet condition of ``ready`` of the calibrator ``cal``, with its number."""
    why = []
    if cal._n_eff < cal.min_pairs:
        why.append(f"{cal._n_eff:.1f} effective distinct pairs < {cal.min_pairs}"
                   + (f" ({cal.duplicates} repeated pairs refused)" if cal.duplicates else ""))
    if cal._excitation < cal.min_excitation_deg:
        axis = None if cal._weak_axis is None else cal._weak_axis.tolist()
        why.append(f"the motion does not determine R0: RMS rotation about axes perpendicular to "
                   f"{np.round(axis, 3).tolist() if axis else 'any axis'} (sensor frame) is "
                   f"{cal._excitation:.3g} deg < {cal.min_excitation_deg:g} deg; rotate about other axes")
    why += detector_reasons(cal._detector, misfits_withdraw)
    if not cal._radius < cal.target_deg:
        why.append(f"{100 * cal.level:g} % radius {cal._radius:.3g} deg >= target {cal.target_deg:g} deg")
        if cal._creep.found is not None:
            why.append(cal._creep.describe(cal.target_deg))
    if cal._verdict is not None and cal._verdict.level == "fail":
        why += [r.message for r in cal._verdict.reasons if r.level == "fail"]
    return why
