"""Time association of two streams: the clock offset between them and the motion pairs they share. Theory and measured
numbers: ``docs/reading.md``, section ``replication.rig.association``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.checks import check_number
from ..core.handeye import relative_rotations
from ..core.so3 import rotation_vector_from_matrix
from .streams import GyroStream, OrientationStream, integrate_gyro, time_unit_mismatch

__all__ = ["OffsetEstimate", "estimate_time_offset", "offset_analysis", "offset_in_words", "motion_pairs",
           "stream_pairs"]


def _speed(Q, times) -> np.ndarray:
    """Angular speed (rad/s) between consecutive orientations along axis -3, batched over leading axes."""
    rel = np.swapaxes(Q[..., :-1, :, :], -1, -2) @ Q[..., 1:, :, :]
    return np.linalg.norm(rotation_vector_from_matrix(rel), axis=-1) / np.diff(times)


#: Most interpolated sensor samples (candidate offsets x camera times) the offset search holds at once. One
#: sample costs about 150 bytes at the peak (the slerped rotation, the relative rotations,
#: ``rotation_vector_from_matrix``'s temporaries; measured: 169 MB for 401 offsets x 2800 times), so a block
#: takes ~80 MB whatever ``max_offset`` is. The default search (``max_offset`` 0.2 s, 41 offsets) fits in one
#: block up to 12 700 camera times (10.6 min at 20 Hz).
OFFSET_BLOCK_SAMPLES = 2 ** 19


def _correlations(cam, sensor: OrientationStream, t, offsets, block_samples: int | None = None) -> np.ndarray:
    """Correlation of the camera's angular speeds ``cam`` with the sensor's at each of ``offsets``.

    The offsets are evaluated in blocks of at most ``block_samples`` (default :data:`OFFSET_BLOCK_SAMPLES`)
    interpolated samples, so memory does not grow with the number of offsets. Every step is per offset
    (slerp, speeds, centring, norms: each row's arithmetic is the same in any block) except the product of
    the centred speeds with the camera's: BLAS's matrix-vector product rounds a row differently depending on
    how many rows it is given (OpenBLAS groups rows by 4 and splits them over threads). So:

    * all offsets in one block: ``b @ a``, the computation of before, bit for bit;
    * several blocks: ``sum(b * a, axis=1)``, a per-row pairwise sum, identical for any block size and
      within a few ulp of ``b @ a``.
    """
    block = OFFSET_BLOCK_SAMPLES if block_samples is None else int(block_samples)
    per = max(1, block // len(t))
    a = cam - cam.mean()
    out = np.empty(len(offsets))
    for k in range(0, len(offsets), per):
        o = offsets[k:k + per]
        Qs = sensor.at((t[None, :] + o[:, None]).ravel()).reshape(len(o), len(t), 3, 3)
        sen = _speed(Qs, t)
        b = sen - sen.mean(axis=1, keepdims=True)
        dot = b @ a if per >= len(offsets) else np.add.reduce(b * a, axis=1)
        out[k:k + per] = dot / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))
    return out


#: Sub-grid steps per fine step: the peak is refined on offsets ``resolution / SUBGRID_STEPS`` apart within one fine
#: step of the fine grid's argmax. Measured (every grid phase 0.01 ms apart, against the curve on a 0.01 ms grid):
#: the 3-point parabola on the 0.5 ms grid alone is off by at most 0.0006 ms on TUM-VI room1 (raw gyro) but by
#: 0.014 ms on its mocap and 0.086 ms on EuRoC MH01, whose 200 Hz ground truth and 20 Hz camera share their clock
#: phase (the curve has a kink every 5 ms); on the 0.05 ms sub-grid the same parabola is off by at most 0.0011 ms
#: on all of them. Least-squares parabolas over 5 or 7 points were worse on every recording.
SUBGRID_STEPS = 10

#: The bootstrap's replicates are evaluated at the fine and sub-grid offsets and at the coarse ones within this of the
#: coarse maximum (s); a replicate whose maximum lies at either end of those is beyond them (:func:`offset_analysis`).
BOOTSTRAP_SPAN_S = 0.1

#: A competing correlation peak is a local maximum of the 10 ms coarse curve farther than this from the peak (s): a
#: 20 Hz camera's interval; nearer maxima would be ripples of the same lobe (none seen on the recordings).
PEAK_SEPARATION_S = 0.05

#: Competing peaks whose coarse correlation is within ``RIVAL_REFINED_WITHIN`` of the coarse maximum (the
#: ``RIVALS_REFINED`` highest) are refined like the peak, and the highest refined is the estimate: the coarse grid
#: lowers a sharp peak by up to 0.011 when it falls between grid offsets (measured on a 3 Hz oscillation, whose
#: aliases 167 ms apart are equally high), enough to rank the aliases wrongly: with a little aperiodic motion
#: added, the coarse maximum alone chose an alias for 9 of 15 true offsets, the highest refined for none.
RIVAL_REFINED_WITHIN = 0.1
RIVALS_REFINED = 4


def _overlap(camera, sensor, max_offset):
    """Camera times whose shifted intervals stay inside the sensor stream, and the camera's angular speeds."""
    lo = max(camera.t[0], sensor.t[0] + max_offset)
    hi = min(camera.t[-1], sensor.t[-1] - max_offset)
    keep = (camera.t >= lo) & (camera.t <= hi)
    t = camera.t[keep]
    if len(t) < 10:
        unit = time_unit_mismatch(camera, sensor)  # a time-unit mistake is named, with the spans that show it
        raise ValueError(f"the streams overlap in fewer than 10 camera samples (overlap {lo:.3f}..{hi:.3f} s)"
                         + ("" if unit is None else "; " + unit[2]))
    return t, _speed(camera.R[keep], t)


def _row_correlations(a, sensor, t, offsets, keep_rows: bool):
    """Correlations of the centred camera speeds ``a`` with the sensor's at ``offsets``; with ``keep_rows`` also the
    centred sensor speeds, one row per offset (8 bytes per offset per camera time).

    In blocks of :data:`OFFSET_BLOCK_SAMPLES` as :func:`_correlations`, but always as a per-row pairwise sum
    ``sum(b * a)``: the values, hence the refined offset, do not depend on the block size.
    """
    per = max(1, OFFSET_BLOCK_SAMPLES // len(t))
    out, rows = np.empty(len(offsets)), np.empty((len(offsets), len(a)) if keep_rows else (0, 0))
    for k in range(0, len(offsets), per):
        o = offsets[k:k + per]
        sen = _speed(sensor.at((t[None, :] + o[:, None]).ravel()).reshape(len(o), len(t), 3, 3), t)
        b = sen - sen.mean(axis=1, keepdims=True)
        out[k:k + per] = np.add.reduce(b * a, axis=1) / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))
        if keep_rows:
            rows[k:k + per] = b
    return out, rows


def _vertex(x, y) -> np.ndarray:
    """Offset of the maximum of each curve ``y[..., :]`` over the sorted offsets ``x``, refined by the parabola through
    the maximum and its two neighbours.

    With ``d1 = (y1 - y0) / (x1 - x0)`` and ``c = ((y2 - y1) / (x2 - x1) - d1) / (x2 - x0)`` the parabola is
    ``y0 + d1 (x - x0) + c (x - x0)(x - x1)``, its vertex ``(x0 + x1) / 2 - d1 / (2 c)`` when ``c < 0``, clipped to
    ``[x0, x2]``. A maximum at either end of ``x``, or where the curve is not concave, is not refined; a curve with
    no finite value gives NaN.
    """
    y = np.where(np.isfinite(y), y, -np.inf)
    k = np.argmax(y, axis=-1)
    j = np.clip(k, 1, len(x) - 2)[..., None] + np.array([-1, 0, 1])
    (x0, x1, x2), (y0, y1, y2) = np.moveaxis(x[j], -1, 0), np.moveaxis(np.take_along_axis(y, j, axis=-1), -1, 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        d1 = (y1 - y0) / (x1 - x0)
        c = ((y2 - y1) / (x2 - x1) - d1) / (x2 - x0)
        v = np.clip(0.5 * (x0 + x1) - d1 / (2 * c), x0, x2)
    v = np.where((k == j[..., 1]) & (c < 0) & np.isfinite(v), v, x[k])
    return np.where(np.isfinite(np.max(y, axis=-1)), v, np.nan)


def _refine(a, sensor, t, best, max_offset, resolution, keep_rows: bool) -> dict:
    """The fine and sub-grid searches around the coarse offset ``best`` and the refined peak (see
    :func:`estimate_time_offset`); with ``keep_rows`` the centred sensor speeds at the fine and sub-grid offsets."""
    fine = np.unique(np.clip(np.arange(best - 0.01, best + 0.01 + 1e-12, resolution), -max_offset, max_offset))
    c_fine, rows_fine = _row_correlations(a, sensor, t, fine, keep_rows)
    grid = fine[np.argmax(c_fine)]
    steps = np.concatenate([np.arange(1 - SUBGRID_STEPS, 0), np.arange(1, SUBGRID_STEPS)])
    sub = np.setdiff1d(np.clip(grid + steps * (resolution / SUBGRID_STEPS), -max_offset, max_offset), fine)
    c_sub, rows_sub = _row_correlations(a, sensor, t, sub, keep_rows)
    order = np.argsort(np.concatenate([fine, sub]), kind="stable")
    x, y = np.concatenate([fine, sub])[order], np.concatenate([c_fine, c_sub])[order]
    offset = float(_vertex(x, y))
    corr = float(_row_correlations(a, sensor, t, np.array([offset]), False)[0][0])
    return dict(best=best, fine=fine, x=np.append(x, offset), y=np.append(y, corr), grid=float(grid), offset=offset,
                corr=corr, rows=np.concatenate([rows_fine, rows_sub])[order] if keep_rows else None,
                rows_x=np.concatenate([fine, sub])[order])


def _local_maxima(corr) -> np.ndarray:
    """Indices of the interior local maxima of a curve (higher than the left neighbour, not lower than the right)."""
    return np.flatnonzero((corr[1:-1] > corr[:-2]) & (corr[1:-1] >= corr[2:])) + 1


def _search(camera, sensor, max_offset, resolution, keep_rows: bool) -> dict:
    """The searches of :func:`estimate_time_offset`: ``offset``, ``corr``, ``grid``, ``curve`` and the rival peak
    ``second`` (offset, correlation). With ``keep_rows`` also ``boot_x``, the fine and sub-grid offsets and the
    coarse ones within :data:`BOOTSTRAP_SPAN_S` of the peak's coarse maximum (sorted), and ``rows``, the centred
    sensor speeds there (for :func:`_bootstrap_offsets`)."""
    max_offset = float(check_number("max_offset", max_offset, minimum=0))
    resolution = float(check_number("resolution", resolution, minimum=0))
    t, cam = _overlap(camera, sensor, max_offset)
    a = cam - cam.mean()
    coarse = np.arange(-max_offset, max_offset + 1e-12, 0.01)
    c_coarse = _correlations(cam, sensor, t, coarse)
    if not np.isfinite(c_coarse).any():  # a stream whose angular speed does not vary (a rig at rest): no information
        return dict(t=t, a=a, grid=0.0, offset=0.0, corr=float("nan"), second=(float("nan"), float("nan")),
                    curve=(coarse, c_coarse), rows=None)
    top = int(np.argmax(c_coarse))
    rivals = [i for i in _local_maxima(c_coarse) if abs(coarse[i] - coarse[top]) > PEAK_SEPARATION_S]
    close = sorted((i for i in rivals if c_coarse[top] - c_coarse[i] < RIVAL_REFINED_WITHIN),
                   key=lambda i: -c_coarse[i])[:RIVALS_REFINED]
    refined = [_refine(a, sensor, t, coarse[top], max_offset, resolution, keep_rows)]
    refined += [_refine(a, sensor, t, coarse[i], max_offset, resolution, False) for i in close]
    peak = max(refined, key=lambda r: r["corr"])  # the first of equals: the coarse maximum's
    if keep_rows and peak["rows"] is None:
        peak = _refine(a, sensor, t, peak["best"], max_offset, resolution, True)
    far = [(r["offset"], r["corr"]) for r in refined if abs(r["offset"] - peak["offset"]) > PEAK_SEPARATION_S]
    far += [(coarse[i], c_coarse[i]) for i in _local_maxima(c_coarse)
            if abs(coarse[i] - peak["best"]) > PEAK_SEPARATION_S and i not in close and i != top]
    second = max(far, key=lambda p: p[1]) if far else (float("nan"), float("nan"))
    curve_x, first = np.unique(np.concatenate([coarse] + [r["x"] for r in refined]), return_index=True)
    curve = (curve_x, np.concatenate([c_coarse] + [r["y"] for r in refined])[first])
    out = dict(t=t, a=a, grid=peak["grid"], offset=peak["offset"], corr=peak["corr"],
               second=(float(second[0]), float(second[1])), curve=curve)
    if keep_rows:
        fine, rows, x = peak["fine"], peak["rows"], peak["rows_x"]
        outside = (coarse < fine[0] - 1e-9) | (coarse > fine[-1] + 1e-9)
        near = coarse[(np.abs(coarse - peak["best"]) <= BOOTSTRAP_SPAN_S + 1e-9) & outside]
        rows_near = _row_correlations(a, sensor, t, near, True)[1]
        order = np.argsort(np.concatenate([near, x]), kind="stable")
        out.update(boot_x=np.concatenate([near, x])[order], rows=np.concatenate([rows_near, rows])[order])
    return out


def estimate_time_offset(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                         resolution: float = 0.5e-3, full_output: bool = False):
    """Clock offset by cross-correlating angular speeds; returns ``(offset_s, correlation)``.

    The offset ``d`` maximises the correlation ``r(d)`` between the camera's angular speed over
    ``[t_k, t_{k+1}]`` and the sensor's over ``[t_k + d, t_{k+1} + d]`` (sensor slerped). It is searched on a
    10 ms grid in ``[-max_offset, max_offset]``, then on a ``resolution`` grid within 10 ms of the coarse maximum,
    then on the sub-grid ``h = resolution / SUBGRID_STEPS`` within one ``resolution`` of the fine maximum, and
    refined there by the parabola through the maximum and its two neighbours (:func:`_vertex`; for a smooth peak
    its error is ``O(h^2 r'''/r'')``, at most 0.0011 ms on the recordings of :data:`SUBGRID_STEPS`). Other
    local maxima of the coarse curve within :data:`RIVAL_REFINED_WITHIN` of its maximum (periodic motion) are refined
    the same way, and the highest refined peak is ``d``. ``d`` is Kalibr's ``timeshift_cam_imu``
    (:func:`offset_in_words`).

    Cost: time ``O((max_offset / 10 ms + 0.02 s / resolution) x camera times)``, the second term once more for each
    rival refined (at most :data:`RIVALS_REFINED`; none on the recordings measured); memory bounded by
    :data:`OFFSET_BLOCK_SAMPLES` interpolated samples (~80 MB) plus 8 bytes per candidate offset, whatever
    ``max_offset`` is (the candidates are evaluated block by block, see :func:`_correlations`).

    Parameters
    ----------
    camera, sensor : OrientationStream
    max_offset : float
        Largest offset searched (s), positive and finite.
    resolution : float
        Step of the fine search (s), positive and finite.
    full_output : bool
        Also return the correlation curve: the candidate offsets searched (coarse, fine, sub-grid and the refined
        offset, sorted) and their correlations (for :meth:`replication.rig.report.CalibrationResult.plot`).

    Returns
    -------
    (offset_s, correlation) : (float, float)
        The refined offset and ``r`` evaluated at it (one more evaluation, not the parabola's value). With
        ``full_output``: ``(offset_s, correlation, (offsets, correlations))``.

    Where either stream's angular speed does not vary at all (a rig at rest) no offset can be estimated: 0 with a NaN
    correlation (the verdict then fails on the correlation).

    Raises
    ------
    ValueError
        ``max_offset`` or ``resolution`` not a positive finite number; the streams overlap in fewer than 10
        camera samples once shifted by ``max_offset``.
    """
    s = _search(camera, sensor, max_offset, resolution, keep_rows=False)
    return (s["offset"], s["corr"], s["curve"]) if full_output else (s["offset"], s["corr"])


@dataclass(frozen=True, eq=False)
class OffsetEstimate:
    """A clock offset from :func:`offset_analysis`, with its 95 % interval and the ambiguity of its peak.

    Attributes
    ----------
    offset_s : float
        The refined offset ``d`` (s): the sensor sample stamped ``t + d`` matches the camera sample stamped ``t``
        (Kalibr's ``timeshift_cam_imu``; :func:`offset_in_words`).
    correlation : float
        The correlation of the angular speeds evaluated at ``offset_s``.
    grid_offset_s : float
        The maximum of the fine grid, before the sub-grid refinement.
    ci95_s : (float, float)
        The 2.5 and 97.5 percentiles of the block-bootstrap offsets (the order statistics at or outside them);
        an end is infinite when more than 2.5 % of the replicates peak beyond the offsets they are evaluated on
        (:data:`BOOTSTRAP_SPAN_S`); ``(nan, nan)`` without replicates.
    second_peak_offset_s, second_peak_correlation : float
        The highest other peak farther than ``peak_separation_s`` from ``offset_s``: a local maximum of the coarse
        (10 ms) curve, refined like the peak if its coarse correlation is within :data:`RIVAL_REFINED_WITHIN` of the
        coarse maximum (see :func:`estimate_time_offset`); NaN if there is none.
    peak_margin : float
        ``correlation - second_peak_correlation``: small when another offset matches the speeds almost as well
        (periodic motion); NaN if there is no other peak in the search.
    curve : (ndarray, ndarray)
        Every offset evaluated (coarse, fine, sub-grid, refined; sorted) and its correlation.
    n_bootstrap : int
    block_s : float
        Length of the bootstrap's blocks (s).
    peak_separation_s : float
        :data:`PEAK_SEPARATION_S`.
    """

    offset_s: float
    correlation: float
    grid_offset_s: float
    ci95_s: tuple
    second_peak_offset_s: float
    second_peak_correlation: float
    peak_margin: float
    curve: tuple
    n_bootstrap: int
    block_s: float
    peak_separation_s: float = PEAK_SEPARATION_S

    def in_words(self) -> str:
        """:func:`offset_in_words` of ``offset_s`` and its interval (a direction only where it excludes 0)."""
        return offset_in_words(self.offset_s, ci95_s=self.ci95_s)


def _bootstrap_offsets(a, rows, x, n_bootstrap: int, block: int, rng) -> np.ndarray:
    """The refined offset of each of ``n_bootstrap`` circular block-bootstrap replicates of the camera speeds.

    A replicate draws ``ceil(n / block)`` blocks of ``block`` consecutive speeds (indices modulo ``n``, uniform
    starts: Politis & Romano's circular block bootstrap, every sample equally likely); ``w_i`` counts the draws of
    speed ``i``. With ``a`` the camera's and ``b_j`` the sensor's speeds at offset ``x_j`` (rows, centred), the
    replicate's correlation at every offset is, with ``W = sum w``, ``S_a = w . a``, ``S_j = w . b_j``,

        ``r_j = (w . (a b_j) - S_a S_j / W) / sqrt((w . a^2 - S_a^2 / W) (w . b_j^2 - S_j^2 / W))``,

    for all replicates at once by matrix products (replicates and samples in chunks of at most
    :data:`OFFSET_BLOCK_SAMPLES` weights or products' terms);
    its maximum is refined as the estimate's (:func:`_vertex`), and is -inf or +inf at the first or last offset
    (the replicate's peak may lie beyond). The starts are drawn all at once, so the chunking changes the result
    only by rounding (BLAS's products round by shape).
    """
    n, J = len(a), len(rows)
    starts = rng.integers(0, n, size=(n_bootstrap, -(-n // block)))
    out, per = np.empty(n_bootstrap), max(1, OFFSET_BLOCK_SAMPLES // (3 * J + 2))
    chunks = -(-n_bootstrap * n // OFFSET_BLOCK_SAMPLES)
    for r in np.array_split(np.arange(n_bootstrap), chunks):
        picks = np.bincount((starts[r] + n * np.arange(len(r))[:, None]).ravel(), minlength=len(r) * n)
        ext = np.concatenate([np.zeros((len(r), 1)), picks.reshape(len(r), n)[:, n - block + 1:],
                              picks.reshape(len(r), n)], axis=1).cumsum(axis=1)
        w = ext[:, block:] - ext[:, :-block]  # w_i = draws of the starts i - block + 1 .. i (mod n)
        W, S = w.sum(axis=1, keepdims=True), np.zeros((len(r), 3 * J + 2))
        for i in range(0, n, per):  # every weighted sum in one product, the speeds in chunks of samples
            b, c = rows[:, i:i + per], a[i:i + per]
            S += w[:, i:i + per] @ np.vstack([c, c * c, b, b * b, b * c]).T
        sa, saa, sb, sbb, sab = S[:, :1], S[:, 1:2], S[:, 2:J + 2], S[:, J + 2:2 * J + 2], S[:, 2 * J + 2:]
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = (sab - sa * sb / W) / np.sqrt((saa - sa * sa / W) * (sbb - sb * sb / W))
        ends = np.argmax(np.where(np.isfinite(corr), corr, -np.inf), axis=1)
        out[r] = np.where(ends == 0, -np.inf, np.where(ends == len(x) - 1, np.inf, _vertex(x, corr)))
    return out


def offset_analysis(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                    resolution: float = 0.5e-3, n_bootstrap: int = 200, seed: int = 0,
                    block_s: float = 1.0) -> OffsetEstimate:
    """The clock offset of :func:`estimate_time_offset` with a 95 % block-bootstrap interval and its peak's margin.

    * ``offset_s``, ``correlation``: as :func:`estimate_time_offset` (the same computation, the same values).
    * ``ci95_s``: the camera's angular speeds are resampled in circular blocks of ``block_s`` seconds (neighbouring
      speeds share a pose, so their errors are correlated), the correlation recomputed for each replicate at every
      fine and sub-grid offset and at the coarse ones within :data:`BOOTSTRAP_SPAN_S`, and its maximum refined the
      same way; the interval is the 2.5 and 97.5 percentiles of the replicates' offsets
      (:func:`_bootstrap_offsets`). It describes the spread due to the samples; an error every sample shares (a
      latency of the SLAM front end, a mis-stamped stream) is invisible to it.
    * ``peak_margin``: the correlation at the peak minus the highest other local maximum of the 10 ms coarse
      curve farther than :data:`PEAK_SEPARATION_S` from it, refined if close (NaN if none): periodic motion makes
      several near-equal peaks, and the margin says how close the runner-up came.

    Cost: :func:`estimate_time_offset`'s and the sensor speeds at the ``~2 BOOTSTRAP_SPAN_S / 10 ms`` coarse offsets
    again; 8 bytes per camera time for each offset the replicates use (78 at the default ``resolution``: 0.6 kB
    per camera time), plus ``O(n_bootstrap x camera times x offsets)`` time for the products, their weights and
    terms held in chunks of at most :data:`OFFSET_BLOCK_SAMPLES` values.

    Parameters
    ----------
    camera, sensor : OrientationStream
    max_offset, resolution : float
        As :func:`estimate_time_offset`.
    n_bootstrap : int
        Replicates, ``>= 0`` (0: no interval).
    seed : int
        Seed of ``numpy.random.default_rng``, ``>= 0``.
    block_s : float
        Block length (s), positive; a block holds ``round(block_s / median camera interval)`` speeds (at least
        one), and the overlap must hold at least two blocks.

    Returns
    -------
    OffsetEstimate

    Raises
    ------
    ValueError
        A parameter out of its range, named; the errors of :func:`estimate_time_offset`.
    """
    n_bootstrap = int(check_number("n_bootstrap", n_bootstrap, minimum=0, integer=True, strict=False))
    seed = int(check_number("seed", seed, minimum=0, integer=True, strict=False))
    block_s = float(check_number("block_s", block_s, minimum=0))
    check_number("resolution", resolution, minimum=0)
    t, _ = _overlap(camera, sensor, float(check_number("max_offset", max_offset, minimum=0)))
    block = max(1, int(round(block_s / np.median(np.diff(t)))))
    if 2 * block > len(t) - 1:
        raise ValueError(f"block_s={block_s!r} s makes blocks of {block} camera speeds, more than half of the "
                         f"{len(t) - 1} in the overlap: use a shorter block_s")
    s = _search(camera, sensor, max_offset, resolution, keep_rows=n_bootstrap > 0)
    ci = (float("nan"), float("nan"))
    if n_bootstrap and s["rows"] is not None:
        boot = _bootstrap_offsets(s["a"], s["rows"], s["boot_x"], n_bootstrap, block, np.random.default_rng(seed))
        ci = (float(np.nanpercentile(boot, 2.5, method="lower")), float(np.nanpercentile(boot, 97.5, method="higher")))
    second = s["second"]
    return OffsetEstimate(s["offset"], s["corr"], s["grid"], ci, second[0], second[1], s["corr"] - second[1],
                          s["curve"], n_bootstrap, block_s)


def offset_in_words(offset_s: float, decimals: int = 1, ci95_s=None) -> str:
    """The clock offset ``d`` and its sign in words, in ms to ``decimals`` decimals.

    With ``ci95_s`` (its 95 % interval, s) the direction is said only where it excludes 0, else "no offset resolved".

    ``d`` is defined by "the sensor sample stamped ``t + d`` matches the camera sample stamped ``t``": one instant
    is stamped ``t_cam`` by the camera and ``t_imu = t_cam + d`` by the sensor, so ``d > 0`` means the sensor clock
    reads ahead of the camera's. That is Kalibr's ``timeshift_cam_imu``, documented as "timeshift between camera
    and IMU timestamps in seconds (t_imu = t_cam + shift)" (ethz-asl/kalibr wiki, "yaml formats"), and in
    ``IccSensors.py`` (``IccCamera.findTimeshiftCameraImuPrior``: "store the timeshift (t_imu = t_cam +
    timeshiftCamToImuPrior)"; ``addCameraErrorTerms`` evaluates the IMU-time pose spline at
    ``obs.time() + timeshiftCamToImuPrior + cameraTimeToImuTimeDv``, the camera stamp plus the shift;
    ``getResultTimeShift`` returns that sum). Kalibr places the camera sample stamped ``t`` at IMU time
    ``t + shift``, where :func:`motion_pairs` reads the sensor for the camera at ``t``: ``t + d``. So ``d`` equals
    Kalibr's shift, sign included.

    >>> print(offset_in_words(-0.0123))  # doctest: +NORMALIZE_WHITESPACE
    -12.3 ms: the sensor sample stamped t - 12.3 ms matches the camera sample stamped t (sensor clock behind the
    camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)
    """
    offset_s = float(check_number("offset_s", offset_s))
    decimals = int(check_number("decimals", decimals, minimum=0, integer=True, strict=False))
    ms = round(1e3 * abs(offset_s), decimals)
    kalibr = "Kalibr's timeshift_cam_imu, t_imu = t_cam + shift"
    def _ms(value_s):  # in ms with its sign; two significant digits where the decimals would print a non-zero as 0
        text = f"{1e3 * value_s:+.{decimals}f}"
        return f"{1e3 * value_s:+.2g}" if value_s != 0 and math.isfinite(value_s) and float(text) == 0 else text
    interval = ""
    if ci95_s is not None:
        lo, hi = (float(v) for v in ci95_s)
        interval = f"[{_ms(lo)}, {_ms(hi)}] ms"
        if math.isnan(lo) or math.isnan(hi):
            missing = "no 95 % interval was measured (no bootstrap)" if math.isnan(lo) and math.isnan(hi) else (
                f"its 95 % interval {interval} is not fully measured")
            return f"{_ms(offset_s)} ms, no direction resolved: {missing}, so the data do not say whether the sensor " \
                f"clock is ahead or behind ({kalibr})"
        if lo <= 0 <= hi:
            return (f"no offset resolved: {_ms(offset_s)} ms, its 95 % interval {interval} includes 0 (the "
                    f"clocks agree within it; {kalibr})")
        interval = f", 95 % interval {interval} excludes 0"
    if ms == 0:
        return (f"{0:.{decimals}f} ms: the sensor sample stamped t matches the camera sample stamped t (the clocks "
                f"agree to {0.5 * 10.0 ** -decimals:g} ms; {kalibr})")
    v = f"{ms:.{decimals}f}"
    sign, side = ("+", "ahead of") if offset_s > 0 else ("-", "behind")
    return (f"{sign}{v} ms: the sensor sample stamped t {sign} {v} ms matches the camera sample stamped t (sensor "
            f"clock {side} the camera's by {v} ms{interval}; {kalibr})")


def motion_pairs(camera: OrientationStream, sensor: OrientationStream, interval: float, *, offset: float = 0.0):
    """Relative-rotation pairs ``(A, B)`` at ``interval`` seconds (see the module notes).

    Returns
    -------
    (A, B, t_start) : ndarray (J, 3, 3), ndarray (J, 3, 3), ndarray (J,)
    """
    if not interval > 0:
        raise ValueError(f"interval must be positive, got {interval!r}")
    t = camera.t
    inside = (t + offset >= sensor.t[0]) & (t + offset <= sensor.t[-1])
    t, Qc = t[inside], camera.R[inside]
    j = np.clip(np.searchsorted(t, t + interval), 1, len(t) - 1)
    j = np.where(np.abs(t[j - 1] - t - interval) < np.abs(t[j] - t - interval), j - 1, j)
    tol = 0.5 * np.median(np.diff(t))
    i = np.flatnonzero((np.abs(t[j] - t - interval) <= tol) & (j > np.arange(len(t))))
    j = j[i]
    if len(i) < 2:
        raise ValueError(f"fewer than 2 motion pairs at interval {interval:g} s (streams overlap "
                         f"{t[-1] - t[0] if len(t) else 0:.2f} s)")
    A = relative_rotations(Qc, pairs=(i, j), convention="world_from_body", atol=1e-5)  # eq. (3): C_k C_t^T, C = Q^T
    B = relative_rotations(sensor.at(t + offset), pairs=(i, j), convention="world_from_body", atol=1e-5)  # eq. (4)
    return A, B, t[i]


def stream_pairs(camera: OrientationStream, sensor, *, interval: float = 1.0, max_offset: float = 0.2,
                 correct_offset: bool = True):
    """Steps 1-3 of :func:`calibrate`: integrate a gyro, estimate the clock offset, form the pairs.

    Returns
    -------
    (A, B, offset_s, correlation)
    """
    if isinstance(sensor, GyroStream):
        sensor = integrate_gyro(sensor)
    if not isinstance(camera, OrientationStream) or not isinstance(sensor, OrientationStream):
        raise ValueError("camera must be an OrientationStream and sensor an OrientationStream or GyroStream")
    offset, corr = estimate_time_offset(camera, sensor, max_offset=max_offset)
    A, B, _ = motion_pairs(camera, sensor, interval, offset=offset if correct_offset else 0.0)
    return A, B, offset, corr
