"""The clock offset's numerical core, below :mod:`replication.rig.association`'s doors: the angular
speeds, their correlation curve evaluated block by block in bounded memory, the refined peak and its
rivals (the coarse, fine and sub-grid searches, the parabola's vertex), and the block-bootstrap
replicates of the peak. Theory and measured numbers: ``docs/reading.md``, section
``replication.rig.association``."""
from __future__ import annotations

import numpy as np

from ..core.checks import check_number
from ..core.so3 import rotation_vector_from_matrix
from .streams import OrientationStream, time_unit_mismatch

__all__ = ["OFFSET_BLOCK_SAMPLES", "SUBGRID_STEPS", "BOOTSTRAP_SPAN_S", "PEAK_SEPARATION_S", "RIVAL_REFINED_WITHIN",
           "RIVALS_REFINED", "speed", "correlations", "overlap", "vertex", "local_maxima", "bootstrap_offsets"]


def speed(Q, times) -> np.ndarray:
    """Angular speed (rad/s) between consecutive orientations along axis -3, batched over leading
    axes.

    Parameters
    ----------
    Q : array_like (..., N, 3, 3)
        Rotation matrices at ``times``.
    times : array_like (N,)
        Their time stamps (s), increasing.

    Returns
    -------
    (..., N - 1) ndarray
        The angle of ``Q[k]^T Q[k + 1]`` over ``times[k + 1] - times[k]``.
    """
    rel = np.swapaxes(Q[..., :-1, :, :], -1, -2) @ Q[..., 1:, :, :]
    return np.linalg.norm(rotation_vector_from_matrix(rel), axis=-1) / np.diff(times)


#: Most interpolated sensor samples (candidate offsets x camera times) the offset search holds at
#: once. One sample costs about 150 bytes at the peak (the slerped rotation, the relative rotations,
#: ``rotation_vector_from_matrix``'s temporaries; measured: 169 MB for 401 offsets x 2800 times), so
#: a block takes ~80 MB whatever ``max_offset`` is. The default search (``max_offset`` 0.2 s, 41
#: offsets) fits in one block up to 12 700 camera times (10.6 min at 20 Hz).
OFFSET_BLOCK_SAMPLES = 2 ** 19


def correlations(cam, sensor: OrientationStream, t, offsets, block_samples: int | None = None) -> np.ndarray:
    """Correlation of the camera's angular speeds ``cam`` with the sensor's at each of ``offsets``,
    evaluated in blocks of at most ``block_samples`` interpolated samples, so memory does not grow
    with the number of offsets.

    Parameters
    ----------
    cam : array_like (N - 1,)
        The camera's angular speeds between the camera times ``t`` (:func:`overlap`).
    sensor : OrientationStream
        Slerped at ``t + offset``.
    t : array_like (N,)
        Camera times whose shifted intervals stay inside the sensor stream.
    offsets : array_like (M,)
        Candidate clock offsets (s).
    block_samples : int, optional
        Most interpolated samples held at once; default :data:`OFFSET_BLOCK_SAMPLES`.

    Returns
    -------
    (M,) ndarray
        Pearson correlation at each offset (NaN where either speed is constant).

    Notes
    -----
    Every step is per offset (slerp, speeds, centring, norms: each row's arithmetic is the
    same in any block) except the product of the centred speeds with the camera's: BLAS's
    matrix-vector product rounds a row differently depending on how many rows it is given (OpenBLAS
    groups rows by 4 and splits them over threads). So:

    * all offsets in one block: ``b @ a``, the computation of before, bit for bit;
    * several blocks: ``sum(b * a, axis=1)``, a per-row pairwise sum, identical for any block size
      and within a few ulp of ``b @ a``.
    """
    block = OFFSET_BLOCK_SAMPLES if block_samples is None else int(block_samples)
    per = max(1, block // len(t))
    a = cam - cam.mean()
    out = np.empty(len(offsets))
    for k in range(0, len(offsets), per):
        o = offsets[k:k + per]
        Qs = sensor.at((t[None, :] + o[:, None]).ravel()).reshape(len(o), len(t), 3, 3)
        sen = speed(Qs, t)
        b = sen - sen.mean(axis=1, keepdims=True)
        dot = b @ a if per >= len(offsets) else np.add.reduce(b * a, axis=1)
        out[k:k + per] = dot / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))
    return out


#: Sub-grid steps per fine step: the peak is refined on offsets ``resolution / SUBGRID_STEPS`` apart
#: within one fine step of the fine grid's argmax. Measured (every grid phase 0.01 ms apart, against
#: the curve on a 0.01 ms grid): the 3-point parabola on the 0.5 ms grid alone is off by at most
#: 0.0006 ms on TUM-VI room1 (raw gyro) but by 0.014 ms on its mocap and 0.086 ms on EuRoC MH01,
#: whose 200 Hz ground truth and 20 Hz camera share their clock phase (the curve has a kink every 5
#: ms); on the 0.05 ms sub-grid the same parabola is off by at most 0.0011 ms on all of them.
#: Least-squares parabolas over 5 or 7 points were worse on every recording.
SUBGRID_STEPS = 10

#: The bootstrap's replicates are evaluated at the fine and sub-grid offsets and at the coarse ones
#: within this of the coarse maximum (s); a replicate whose maximum lies at either end of those is
#: beyond them (:func:`~replication.rig.association.offset_analysis`).
BOOTSTRAP_SPAN_S = 0.1

#: A competing correlation peak is a local maximum of the 10 ms coarse curve farther than this from
#: the peak (s): a 20 Hz camera's interval; nearer maxima would be ripples of the same lobe (none
#: seen on the recordings).
PEAK_SEPARATION_S = 0.05

#: Competing peaks whose coarse correlation is within ``RIVAL_REFINED_WITHIN`` of the coarse maximum
#: (the ``RIVALS_REFINED`` highest) are refined like the peak, and the highest refined is the
#: estimate: the coarse grid lowers a sharp peak by up to 0.011 when it falls between grid offsets
#: (measured on a 3 Hz oscillation, whose aliases 167 ms apart are equally high), enough to rank the
#: aliases wrongly: with a little aperiodic motion added, the coarse maximum alone chose an alias
#: for 9 of 15 true offsets, the highest refined for none.
RIVAL_REFINED_WITHIN = 0.1
RIVALS_REFINED = 4


def overlap(camera, sensor, max_offset):
    """Camera times whose shifted intervals stay inside the sensor stream, and the camera's angular
    speeds between them.

    Parameters
    ----------
    camera, sensor : OrientationStream
    max_offset : float
        Largest offset searched (s): a kept time ``t`` has ``t +- max_offset`` in the sensor's span.

    Returns
    -------
    t : (N,) ndarray
        The camera times kept (at least 10).
    speeds : (N - 1,) ndarray
        The camera's angular speeds between them (rad/s, :func:`speed`).

    Raises
    ------
    ValueError
        Fewer than 10 camera times are kept (naming a time-unit mistake when the spans show one).
    """
    lo = max(camera.t[0], sensor.t[0] + max_offset)
    hi = min(camera.t[-1], sensor.t[-1] - max_offset)
    keep = (camera.t >= lo) & (camera.t <= hi)
    t = camera.t[keep]
    if len(t) < 10:
        unit = time_unit_mismatch(camera, sensor)  # a time-unit mistake is named, with the spans that show it
        raise ValueError(f"the streams overlap in fewer than 10 camera samples (overlap {lo:.3f}..{hi:.3f} s)"
                         + ("" if unit is None else "; " + unit[2]))
    return t, speed(camera.R[keep], t)


def _row_correlations(a, sensor, t, offsets, keep_rows: bool):
    """Correlations of the centred camera speeds ``a`` with the sensor's at ``offsets``; with
    ``keep_rows`` also the centred sensor speeds, one row per offset (8 bytes per offset per camera
    time).

    In blocks of :data:`OFFSET_BLOCK_SAMPLES` as :func:`correlations`, but always as a per-row
    pairwise sum ``sum(b * a)``: the values, hence the refined offset, do not depend on the block
    size.
    """
    per = max(1, OFFSET_BLOCK_SAMPLES // len(t))
    out, rows = np.empty(len(offsets)), np.empty((len(offsets), len(a)) if keep_rows else (0, 0))
    for k in range(0, len(offsets), per):
        o = offsets[k:k + per]
        sen = speed(sensor.at((t[None, :] + o[:, None]).ravel()).reshape(len(o), len(t), 3, 3), t)
        b = sen - sen.mean(axis=1, keepdims=True)
        out[k:k + per] = np.add.reduce(b * a, axis=1) / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))
        if keep_rows:
            rows[k:k + per] = b
    return out, rows


def vertex(x, y) -> np.ndarray:
    """Offset of the maximum of each curve ``y[..., :]`` over the sorted offsets ``x``, refined by
    the parabola through the maximum and its two neighbours.

    Parameters
    ----------
    x : array_like (M,)
        Offsets, increasing (not necessarily evenly spaced).
    y : array_like (..., M)
        One curve per leading index; non-finite values are never the maximum.

    Returns
    -------
    ndarray (...)
        The refined offset of each curve's maximum.

    Notes
    -----
    With ``d1 = (y1 - y0) / (x1 - x0)`` and ``c = ((y2 - y1) / (x2 - x1) - d1) / (x2 - x0)`` the
    parabola is ``y0 + d1 (x - x0) + c (x - x0)(x - x1)``, its vertex ``(x0 + x1) / 2 - d1 / (2 c)``
    when ``c < 0``, clipped to ``[x0, x2]``. A maximum at either end of ``x``, or where the curve is
    not concave, is not refined; a curve with no finite value gives NaN.
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
    :func:`~replication.rig.association.estimate_time_offset`); with ``keep_rows`` the centred
    sensor speeds at the fine and sub-grid offsets."""
    fine = np.unique(np.clip(np.arange(best - 0.01, best + 0.01 + 1e-12, resolution), -max_offset, max_offset))
    c_fine, rows_fine = _row_correlations(a, sensor, t, fine, keep_rows)
    grid = fine[np.argmax(c_fine)]
    steps = np.concatenate([np.arange(1 - SUBGRID_STEPS, 0), np.arange(1, SUBGRID_STEPS)])
    sub = np.setdiff1d(np.clip(grid + steps * (resolution / SUBGRID_STEPS), -max_offset, max_offset), fine)
    c_sub, rows_sub = _row_correlations(a, sensor, t, sub, keep_rows)
    order = np.argsort(np.concatenate([fine, sub]), kind="stable")
    x, y = np.concatenate([fine, sub])[order], np.concatenate([c_fine, c_sub])[order]
    offset = float(vertex(x, y))
    corr = float(_row_correlations(a, sensor, t, np.array([offset]), False)[0][0])
    return dict(best=best, fine=fine, x=np.append(x, offset), y=np.append(y, corr), grid=float(grid), offset=offset,
                corr=corr, rows=np.concatenate([rows_fine, rows_sub])[order] if keep_rows else None,
                rows_x=np.concatenate([fine, sub])[order])


def local_maxima(corr) -> np.ndarray:
    """Indices of the interior local maxima of a curve: higher than the left neighbour, not lower
    than the right (of a plateau, its first point only).

    Parameters
    ----------
    corr : array_like (M,)
        The curve.

    Returns
    -------
    ndarray of int
        The indices, increasing; never ``0`` nor ``M - 1``.
    """
    return np.flatnonzero((corr[1:-1] > corr[:-2]) & (corr[1:-1] >= corr[2:])) + 1


def _search(camera, sensor, max_offset, resolution, keep_rows: bool) -> dict:
    """The searches of :func:`~replication.rig.association.estimate_time_offset`: ``offset``,
    ``corr``, ``grid``, ``curve`` and the rival peak ``second`` (offset, correlation). With
    ``keep_rows`` also ``boot_x``, the fine and sub-grid offsets and the coarse ones within
    :data:`BOOTSTRAP_SPAN_S` of the peak's coarse maximum (sorted), and ``rows``, the centred sensor
    speeds there (for :func:`bootstrap_offsets`)."""
    max_offset = float(check_number("max_offset", max_offset, minimum=0))
    resolution = float(check_number("resolution", resolution, minimum=0))
    t, cam = overlap(camera, sensor, max_offset)
    a = cam - cam.mean()
    coarse = np.arange(-max_offset, max_offset + 1e-12, 0.01)
    c_coarse = correlations(cam, sensor, t, coarse)
    if not np.isfinite(c_coarse).any():  # a stream whose angular speed does not vary (a rig at rest): no information
        return dict(t=t, a=a, grid=0.0, offset=0.0, corr=float("nan"), second=(float("nan"), float("nan")),
                    curve=(coarse, c_coarse), rows=None)
    top = int(np.argmax(c_coarse))
    rivals = [i for i in local_maxima(c_coarse) if abs(coarse[i] - coarse[top]) > PEAK_SEPARATION_S]
    close = sorted((i for i in rivals if c_coarse[top] - c_coarse[i] < RIVAL_REFINED_WITHIN),
                   key=lambda i: -c_coarse[i])[:RIVALS_REFINED]
    refined = [_refine(a, sensor, t, coarse[top], max_offset, resolution, keep_rows)]
    refined += [_refine(a, sensor, t, coarse[i], max_offset, resolution, False) for i in close]
    peak = max(refined, key=lambda r: r["corr"])  # the first of equals: the coarse maximum's
    if keep_rows and peak["rows"] is None:
        peak = _refine(a, sensor, t, peak["best"], max_offset, resolution, True)
    far = [(r["offset"], r["corr"]) for r in refined if abs(r["offset"] - peak["offset"]) > PEAK_SEPARATION_S]
    far += [(coarse[i], c_coarse[i]) for i in local_maxima(c_coarse)
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


def bootstrap_offsets(a, rows, x, n_bootstrap: int, block: int, rng) -> np.ndarray:
    """The refined offset of each of ``n_bootstrap`` circular block-bootstrap replicates of the
    camera speeds.

    Parameters
    ----------
    a : array_like (n,)
        The camera's angular speeds, centred.
    rows : array_like (J, n)
        The sensor's angular speeds at each offset of ``x``, centred.
    x : array_like (J,)
        The offsets (s), increasing.
    n_bootstrap : int
        Number of replicates.
    block : int
        Block length (samples).
    rng : numpy.random.Generator
        Draws the blocks' starts.

    Returns
    -------
    (n_bootstrap,) ndarray
        Each replicate's refined offset; -inf or +inf when its maximum is at the first or last
        offset.

    Notes
    -----
    A replicate draws ``ceil(n / block)`` blocks of ``block`` consecutive speeds (indices modulo
    ``n``, uniform starts: Politis & Romano's circular block bootstrap, every sample equally
    likely); ``w_i`` counts the draws of speed ``i``. With ``a`` the camera's and ``b_j`` the
    sensor's speeds at offset ``x_j`` (rows, centred), the replicate's correlation at every offset
    is, with ``W = sum w``, ``S_a = w . a``, ``S_j = w . b_j``,

        ``r_j = (w . (a b_j) - S_a S_j / W) / sqrt((w . a^2 - S_a^2 / W) (w . b_j^2 - S_j^2 / W))``,

    for all replicates at once by matrix products (replicates and samples in chunks of at most
    :data:`OFFSET_BLOCK_SAMPLES` weights or products' terms); its maximum is refined as the
    estimate's (:func:`vertex`), and is -inf or +inf at the first or last offset (the replicate's
    peak may lie beyond). The starts are drawn all at once, so the chunking changes the result only
    by rounding (BLAS's products round by shape).
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
        out[r] = np.where(ends == 0, -np.inf, np.where(ends == len(x) - 1, np.inf, vertex(x, corr)))
    return out
