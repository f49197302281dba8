"""Does ``R0`` hold over the whole recording? ``R0`` per segment of time and the segments that
disagree. Theory and measured numbers: ``docs/judging.md``, section ``replication.rig.segments``."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats as _st

from ..core.so3 import angle_between_deg, matrix_from_rotation_vector, rotation_vector_from_matrix
from ..core.stats import radius_deg
from .changepoint import S2_FLOOR, _fit, _long_run

__all__ = ["Segment", "SegmentTest", "segment_test", "SEGMENT_S", "ANALYSIS_INTERVAL_S", "MIN_SEGMENTS",
           "MAX_LEFT_OUT_SHARE", "run", "report", "reasons", "consistent_mask", "parts_angle_deg"]

#: Target length of a segment (s): long enough for each segment's R0 to be determined by its own
#: motion (10 s of 1 s pairs at 20 Hz: 180 pairs), short enough that a stretch of bad tracking fills
#: segments of its own.
SEGMENT_S = 10.0
#: The pairs the segment and change tests run on, whatever ``calibrate``'s ``interval`` (module
#: notes).
ANALYSIS_INTERVAL_S = 1.0
#: Fewest segments the test runs with (two are the change test's job).
MIN_SEGMENTS = 3
#: ``use="consistent"`` keeps the majority: left out beyond this share it may be the wrong part (a
#: ``fail``).
MAX_LEFT_OUT_SHARE = 1 / 3


@dataclass(frozen=True)
class Segment:
    """One segment: its time span (s, since the first camera sample in ``calibrate``'s report),
    pairs, ``R0``, its 95 % noise radius, its angle to the other segments' mean, that difference's
    statistic, p-value and whether it disagrees (significant after Bonferroni over the segments)."""

    start_s: float
    end_s: float
    n_pairs: int
    R: np.ndarray = field(repr=False)
    radius_deg: float
    angle_deg: float
    statistic: float
    p_value: float
    disagrees: bool

    def to_dict(self) -> dict:
        return {"start_s": self.start_s, "end_s": self.end_s, "n_pairs": self.n_pairs, "R0": self.R.tolist(),
                "radius_deg": self.radius_deg, "angle_to_rest_deg": self.angle_deg, "statistic": self.statistic,
                "p_value": self.p_value, "disagrees": self.disagrees}


@dataclass(frozen=True)
class SegmentTest:
    """What :func:`segment_test` found (times as given in ``t``; ``calibrate`` reports them since
    the first camera sample).

    Attributes
    ----------
    segments : tuple of Segment
    significant : bool
        The segments disagree beyond their noise (``statistic > threshold``, false-alarm probability
        ``level``).
    statistic, threshold, p_value, level, dof : float
        ``Q / (3 (S - 1))``, the F quantile it is compared with, its p-value, the level, and ``3 (S
        - 1)``.
    inflation, effective_blocks : float
        ``phi`` and ``n_eff`` (module notes).
    R_mean : ndarray (3, 3)
        The segments' weighted mean.
    pairs_radius_deg, between_radius_deg : float
        95 % radius of ``R_mean`` from the pairs' noise, and from the segments' scatter (module
        notes).
    consistent : tuple of int
        The segments of the consistent part (every one where none disagrees; empty where no half of
        them agrees).
    max_angle_deg : float
        The largest angle of a disagreeing segment to the others' mean (0 where none disagrees).
    interval_s : float or None
        The pairs' interval, where known.
    """

    segments: tuple
    significant: bool
    statistic: float
    threshold: float
    p_value: float
    level: float
    dof: int
    inflation: float
    effective_blocks: float
    R_mean: np.ndarray = field(repr=False)
    pairs_radius_deg: float
    between_radius_deg: float
    consistent: tuple
    max_angle_deg: float
    interval_s: float | None = None

    @property
    def disagreeing(self) -> tuple:
        """Indices of the segments that disagree with the others."""
        return tuple(i for i, s in enumerate(self.segments) if s.disagrees)

    def used_spans(self, left_out: bool = False) -> list:
        """The consistent part (``left_out``: the rest) as ``[start_s, end_s]`` spans (neighbouring
        segments merged)."""
        spans = []
        for i in (sorted(set(range(len(self.segments))) - set(self.consistent)) if left_out else self.consistent):
            s = self.segments[i]
            if spans and math.isclose(spans[-1][1], s.start_s, abs_tol=1e-9):
                spans[-1][1] = s.end_s
            else:
                spans.append([s.start_s, s.end_s])
        return spans

    def summary(self) -> str:
        """One line: the verdict of the test with its numbers."""
        bad = self.disagreeing
        named = ", ".join(f"{self.segments[i].start_s:.1f}-{self.segments[i].end_s:.1f} s "
                          f"({self.segments[i].angle_deg:.2f} deg)" for i in bad)
        head = (f"{len(self.segments)} segments " + ("disagree" if self.significant else "agree within their noise"
                                                     + (" as a whole" if bad else ""))
                + f" (statistic {self.statistic:.2f}, threshold {self.threshold:.2f}, p = {self.p_value:.2g})")
        return head + (f"; disagreeing by their own tests: {named}" if bad else "") + (
            f"; radius from the pairs {self.pairs_radius_deg:.3f} deg, between segments "
            f"{self.between_radius_deg:.3f} deg")

    def to_dict(self, t0: float = 0.0) -> dict:
        """For the JSON report (times less ``t0``)."""
        segs = [{**s.to_dict(), "start_s": s.start_s - t0, "end_s": s.end_s - t0} for s in self.segments]
        return {"run": True, "note": None, "significant": self.significant, "statistic": self.statistic,
                "threshold": self.threshold, "p_value": self.p_value, "level": self.level, "dof": self.dof,
                "inflation": self.inflation, "interval_s": self.interval_s, "segments": segs,
                "disagreeing": list(self.disagreeing), "max_angle_deg": self.max_angle_deg,
                "pairs_radius_deg": self.pairs_radius_deg, "between_radius_deg": self.between_radius_deg,
                "consistent_segments": list(self.consistent),
                "consistent_spans_s": [[a - t0, b - t0] for a, b in self.used_spans()]}


def _mean(R, W, start, iterations: int = 20):
    """Weighted mean rotation: Gauss-Newton on ``sum_i d_i^T W_i d_i``, ``d_i = log(R_bar^T
    R_i)``."""
    Rb = start
    H = W.sum(axis=0)
    for _ in range(iterations):
        d = rotation_vector_from_matrix(Rb.T @ R)
        step = np.linalg.solve(H, np.einsum("iab,ib->a", W, d))
        Rb = Rb @ matrix_from_rotation_vector(step)
        if np.linalg.norm(step) < 1e-12:
            break
    return Rb, np.linalg.inv(H)


def _against(Ri, Ci, Rr, Cr) -> tuple[float, float]:
    """A segment against the others' mean ``Rr``, covariance ``Cr``: ``d^T (C_i + C_r)^{-1} d / 3``
    and the angle."""
    di = rotation_vector_from_matrix(Rr.T @ Ri)
    return float(di @ np.linalg.solve(Ci + Cr, di)) / 3.0, float(angle_between_deg(Ri, Rr))


def _homogeneity(R, C, nu):
    """Over the segments ``R``, ``C``: the mean, ``Q / dof``, each segment's leave-one-out statistic
    and angle."""
    S = len(R)
    W = np.linalg.inv(C)
    Rb, Cb = _mean(R, W, R[int(np.argmin(np.trace(C, axis1=1, axis2=2)))])
    d = rotation_vector_from_matrix(Rb.T @ R)
    dof = 3 * (S - 1)
    F = float(np.einsum("ia,iab,ib->", d, W, d)) / dof
    z, ang = np.empty(S), np.empty(S)
    for i, rest in enumerate(np.arange(S) != np.arange(S)[:, None]):
        z[i], ang[i] = _against(R[i], C[i], *_mean(R[rest], W[rest], Rb, iterations=5))
    p_i = _st.f.sf(z, 3, nu)
    return Rb, Cb, d, F, dof, z, p_i, ang


def segment_test(A, B, t, *, block: int = 1, segment_s: float = SEGMENT_S, level: float = 0.01,
                 interval: float | None = None) -> SegmentTest:
    """``R0`` per segment of about ``segment_s`` seconds, and whether the segments agree (module
    notes).

    Parameters
    ----------
    A, B : array_like, shape (J, 3, 3)
        Camera and sensor relative rotations of the pairs, in time order (eqs. (3)-(4)).
    t : array_like, shape (J,)
        The pairs' start times (s), non-decreasing.
    block : int
        Pairs per interval (as :func:`replication.rig.changepoint.two_segment_test`).
    segment_s : float
        Target segment length (s); the recording is cut into ``floor(span / segment_s)`` equal
        segments.
    level : float
        False-alarm probability, in (0, 0.5).
    interval : float or None
        The pairs' interval (s), reported.

    Raises
    ------
    ValueError
        Bad parameters (named), too short a recording for :data:`MIN_SEGMENTS` segments, or a
        segment whose motions are about one axis only (its R0 is not determined).
    """
    from .changepoint import _check

    A, B, t = _check(A, B, t, block, 0.1, level)
    if not (isinstance(segment_s, (int, float)) and math.isfinite(segment_s) and segment_s > 0):
        raise ValueError(f"segment_s must be a positive number of seconds, got {segment_s!r}")
    J, m = len(A), int(block)
    span = float(t[-1] - t[0])
    S = int(span // segment_s)
    if S < MIN_SEGMENTS:
        raise ValueError(f"too short for a segment test: {span:.1f} s of pair start times make {S} segments of "
                         f"{segment_s:g} s, fewer than {MIN_SEGMENTS}")
    edges = t[0] + span * np.arange(S + 1) / S
    seg = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, S - 1)
    first = np.searchsorted(seg, np.arange(S))
    last = np.append(first[1:], J)
    stop = np.where(np.arange(S) < S - 1, last - m, last)  # the pairs reaching into the next segment: left out
    n = (stop - first).astype(float)
    if np.any(n < max(10, 3 * m)):
        raise ValueError(f"too few pairs in a segment for a segment test: {int(n.min())} (segments of "
                         f"{span / S:.1f} s, {m} pairs per interval)")
    kron = np.einsum("jab,jcd->jacbd", B, A).reshape(J, 9, 9)
    PK = np.concatenate([np.zeros((1, 9, 9)), np.cumsum(kron, axis=0)])
    PB = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(B, axis=0)])
    R, cost, _, G = _fit(PK[stop] - PK[first], PB[stop] - PB[first], n)
    # the inflation about the estimate of all the segments' pairs together (module notes)
    R1, _, s21, G1 = _fit((PK[stop] - PK[first]).sum(axis=0)[None], (PB[stop] - PB[first]).sum(axis=0)[None],
                              np.array([n.sum()]))
    omega = sum(_long_run(A[a:b], B[a:b], R1[0], m) for a, b in zip(first, stop))
    Gi = np.linalg.inv(G1[0])
    phi = max(1.0, float(np.trace(Gi @ omega @ Gi) / np.trace(Gi @ ((s21[0] / 3.0) * G1[0]) @ Gi)))
    # the noise scale from each segment's residuals about its own estimate, pooled (a segment that
    # disagrees does not inflate it); the inflation, a ratio, from the fit of all the pairs
    s2 = np.full(S, max(float(cost.sum() / (2.0 * (n - 3.0)).sum()), S2_FLOOR))
    C = phi * (s2 / 3.0)[:, None, None] * np.linalg.inv(G)
    nu = max((J - m) / (2 * m + 1), 1.0)
    Rb, Cb, d, F, dof, z, p_i, ang = _homogeneity(R, C, nu)
    thr = float(_st.f.isf(level, dof, nu))
    disagree = p_i < level / S
    # the consistent part: leave out the worst disagreeing segment until none disagrees
    keep = np.ones(S, bool)
    flagged = disagree.copy()
    while flagged.any():
        worst = np.flatnonzero(keep)[int(np.argmax(np.where(flagged, z, -np.inf)[keep]))]
        keep[worst] = False
        if keep.sum() < max(2, math.ceil(S / 2)):
            keep[:] = False
            break
        k = np.flatnonzero(keep)
        *_, zk, pk, _ = _homogeneity(R[k], C[k], nu)
        flagged = np.zeros(S, bool)
        flagged[k] = pk < level / len(k)
    if keep.any() and not keep.all():  # masking: a bad segment pulls the others' mean; judge against the kept part
        W_all = np.linalg.inv(C)
        Rk, Ck = _mean(R[keep], W_all[keep], R[np.flatnonzero(keep)[0]])
        for i in np.flatnonzero(~keep):
            z[i], ang[i] = _against(R[i], C[i], Rk, Ck)
        p_i = _st.f.sf(z, 3, nu)
        disagree = ~keep
    between = radius_deg(max(1.0, F) * Cb, 0.95)  # the pairs' radius scaled by the segments' excess scatter
    segments = tuple(Segment(start_s=float(edges[i]), end_s=float(edges[i + 1]), n_pairs=int(n[i]), R=R[i],
                             radius_deg=radius_deg(C[i], 0.95), angle_deg=float(ang[i]), statistic=float(z[i]),
                             p_value=float(p_i[i]), disagrees=bool(disagree[i])) for i in range(S))
    return SegmentTest(segments=segments, significant=bool(F > thr), statistic=F, threshold=thr,
                       p_value=float(_st.f.sf(F, dof, nu)), level=float(level), dof=dof, inflation=phi,
                       effective_blocks=float(nu), R_mean=Rb, pairs_radius_deg=radius_deg(Cb, 0.95),
                       between_radius_deg=between, consistent=tuple(int(i) for i in np.flatnonzero(keep)),
                       max_angle_deg=float(ang[disagree].max()) if disagree.any() else 0.0,
                       interval_s=None if interval is None else float(interval))


def run(A, B, t, block: int, interval: float = ANALYSIS_INTERVAL_S):
    """:func:`segment_test` for ``calibrate``: ``(test, None)``, or ``(None, why)`` where it cannot
    run (too short a recording, a segment whose motions are about one axis)."""
    try:
        return segment_test(A, B, t, block=block, interval=interval), None
    except ValueError as err:
        return None, f"not run: {err}"


def parts_angle_deg(test) -> float:
    """The angle (deg) between the ``R0`` of the consistent part and that of the rest, each the
    pair-weighted chordal mean of its segments' (0 where nothing is left out): how far ``R0`` moves
    if the rest is right."""
    keep = np.zeros(len(test.segments), bool)
    keep[list(test.consistent)] = True
    if keep.all() or not keep.any():
        return 0.0

    def mean(k):
        u, _, vt = np.linalg.svd(sum(s.n_pairs * s.R for s, k_i in zip(test.segments, k) if k_i))
        return u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    return float(angle_between_deg(mean(keep), mean(~keep)))


def report(test, note, t0: float, used=None) -> dict:
    """The segment test for the JSON report (times since ``t0``); ``used``: what
    ``use="consistent"`` kept, with the spans kept and left out and :func:`parts_angle_deg` where it
    kept a part."""
    if test is None:
        return {"run": False, "note": note, "use": used}
    if used is not None and used.get("kept_s") is not None:
        used = {**used, "kept_spans_s": [[a - t0, b - t0] for a, b in test.used_spans()],
                "left_out_spans_s": [[a - t0, b - t0] for a, b in test.used_spans(left_out=True)],
                "R0_moves_deg_if_left_out_part_is_right": parts_angle_deg(test)}
    return {**test.to_dict(t0), "use": used}


def consistent_mask(test, t_start, interval: float) -> np.ndarray:
    """The pairs (start times ``t_start``, ``interval`` long) that lie inside the consistent part of
    ``test``."""
    keep = np.zeros(len(t_start), bool)
    last = test.segments[-1].end_s
    for a, b in test.used_spans():  # the last segment's pairs reach one analysis interval past its last start
        keep |= (t_start >= a) & (t_start + interval <= b + (ANALYSIS_INTERVAL_S if b == last else 0.0))
    return keep


def reasons(test, t0: float, used=None, note=None) -> list:
    """Verdict reasons: segments that disagree with the rest beyond their noise, named with their
    times (a ``warning``; a ``fail`` beyond ``remount_deg``'s fail bound,
    :data:`replication.rig.quality.THRESHOLDS`); what ``use="consistent"`` dropped."""
    from .quality import THRESHOLDS, Reason

    out = []
    if test is None:
        if used is not None:
            out.append(Reason("segments_consistent_part", "warning", None, None,
                              f"use='consistent': the segment test did not run ({note}), so every pair was used"))
        return out
    fail = THRESHOLDS["remount_deg"][1]
    bad = list(test.disagreeing)  # ok only where every segment agrees with the rest within its noise
    spans = ", ".join(f"{a - t0:.1f}-{b - t0:.1f} s" for a, b in test.used_spans())
    if used is not None:
        if used["kept_s"] is None:
            out.append(Reason("segments_consistent_part", "fail", None, None,
                              "use='consistent': no half of the recording's segments agrees on R0 (the segments "
                              "disagree throughout); R0 is from all the pairs and not to be trusted"))
        elif used["dropped_s"]:
            share = used["dropped_s"] / (used["dropped_s"] + used["kept_s"])
            worst = max((test.segments[i].angle_deg for i in bad), default=0.0)
            level = "fail" if share > MAX_LEFT_OUT_SHARE and worst > fail else "warning"
            out_spans = ", ".join(f"{a - t0:.1f}-{b - t0:.1f} s" for a, b in test.used_spans(left_out=True))
            out.append(Reason("segments_consistent_part", level, float(share), MAX_LEFT_OUT_SHARE,
                              f"use='consistent': R0 is from the consistent part only (kept: {spans}, "
                              f"{used['kept_s']:.1f} s); left out: {out_spans} ({used['dropped_s']:.1f} s, "
                              f"{100 * share:.0f} % of the recording), where segments disagreed with the rest by up "
                              f"to {worst:.2f} deg. The part kept is the majority, not known to be the right one: "
                              f"without a reference the pairs cannot tell which part is right; if the part left out "
                              f"is the well-tracked one, R0 moves by {parts_angle_deg(test):.2f} deg (the two "
                              f"parts' R0 apart)"
                              + ("; with this much left out, check the tracking of both parts or calibrate each on "
                                 "its own" if level == "fail" else "")))
        return out
    if not bad:
        return out
    worst = max(test.segments[i].angle_deg for i in bad)
    level, bound = ("fail", fail) if worst > fail else ("warning", 0.0)
    named = "; ".join(f"{test.segments[i].start_s - t0:.1f}-{test.segments[i].end_s - t0:.1f} s by "
                      f"{test.segments[i].angle_deg:.2f} deg (its radius {test.segments[i].radius_deg:.2f}, its own "
                      f"test p = {test.segments[i].p_value:.2g})" for i in bad)
    S = len(test.segments)  # the words say which test carries the verdict: each segment's own
    own = (f"each by its own test against {'the consistent part' if test.consistent else 'the others'}"
           + (f", p below {test.level:g} / {S} segments = {test.level / S:.2g}"
              if all(test.segments[i].p_value < test.level / S for i in bad) else ", left out of it one by one"))
    whole = (f"the test of all the segments together: p = {test.p_value:.2g}"
             + ("" if test.significant else f", not significant alone (level {test.level:g})"))
    keep = (f"the consistent part (the majority, whose segments agree; the pairs cannot tell whether it or the "
            f"rest is right) is {spans}: calibrate on it with use='consistent' (--use consistent) where its "
            f"tracking is known to be the good one" if test.consistent else "no half of the segments agrees")
    out.append(Reason("segments_disagree", level, worst, bound,
                      f"R0 differs along the recording: segments of {ANALYSIS_INTERVAL_S:g} s pairs disagree with "
                      f"the rest beyond their noise ({named}; {own}; {whole}): a "
                      f"trajectory whose frame wanders or is lost for a stretch, or a re-mount; the radius from the "
                      f"spread between segments is {test.between_radius_deg:.2f} deg (from the pairs "
                      f"{test.pairs_radius_deg:.2f}); {keep}"))
    return out
