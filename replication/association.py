"""Time association of two streams: the clock offset between them and the motion pairs they share.

* :func:`estimate_time_offset`: the offset ``d`` (a sensor sample at ``t + d`` matches the camera at ``t``)
  that maximises the correlation of the two streams' angular speeds, refined below the search grid;
* :func:`motion_pairs`: for every camera time ``t_i`` the camera time ``t_j`` closest to ``t_i + interval``;
  ``A = Qc_j^T Qc_i``, ``B = Qs(t_j)^T Qs(t_i)`` with ``Qs`` slerp-interpolated (eqs. (3)-(4) with
  ``C = Q^T``; :func:`replication.handeye.relative_rotations`);
* :func:`stream_pairs`: both, after integrating a gyro stream.

Data model in :mod:`replication.streams`, file I/O in :mod:`replication.realdata`, the solve in
:mod:`replication.calibration` (the layout of evo). Conventions: ``docs/conventions.md``.
"""
from __future__ import annotations

import numpy as np

from .checks import check_number
from .handeye import relative_rotations
from .so3 import log_map
from .streams import GyroStream, OrientationStream, integrate_gyro

__all__ = ["estimate_time_offset", "motion_pairs", "stream_pairs"]


def _speed(Q, times) -> np.ndarray:
    """Angular speed (rad/s) between consecutive orientations along axis -3, batched over leading axes."""
    rel = np.swapaxes(Q[..., :-1, :, :], -1, -2) @ Q[..., 1:, :, :]
    return np.linalg.norm(log_map(rel), axis=-1) / np.diff(times)


#: Most interpolated sensor samples (candidate offsets x camera times) the offset search holds at once. One
#: sample costs about 150 bytes at the peak (the slerped rotation, the relative rotations, ``log_map``'s
#: temporaries; measured: 169 MB for 401 offsets x 2800 times), so a block takes ~80 MB whatever
#: ``max_offset`` is. The default search (``max_offset`` 0.2 s, 41 offsets) fits in one block up to 12 700
#: camera times (10.6 min at 20 Hz).
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

def _overlap(camera, sensor, max_offset):
    """Camera times whose shifted intervals stay inside the sensor stream, and the camera's angular speeds."""
    lo = max(camera.t[0], sensor.t[0] + max_offset)
    hi = min(camera.t[-1], sensor.t[-1] - max_offset)
    keep = (camera.t >= lo) & (camera.t <= hi)
    t = camera.t[keep]
    if len(t) < 10:
        raise ValueError(f"the streams overlap in fewer than 10 camera samples (overlap {lo:.3f}..{hi:.3f} s)")
    return t, _speed(camera.R[keep], t)


def _row_correlations(a, sensor, t, offsets):
    """Correlations of the centred camera speeds ``a`` with the sensor's at ``offsets``.

    In blocks of :data:`OFFSET_BLOCK_SAMPLES` as :func:`_correlations`, but always as a per-row pairwise sum
    ``sum(b * a)``: the values, hence the refined offset, do not depend on the block size.
    """
    per = max(1, OFFSET_BLOCK_SAMPLES // len(t))
    out = np.empty(len(offsets))
    for k in range(0, len(offsets), per):
        o = offsets[k:k + per]
        sen = _speed(sensor.at((t[None, :] + o[:, None]).ravel()).reshape(len(o), len(t), 3, 3), t)
        b = sen - sen.mean(axis=1, keepdims=True)
        out[k:k + per] = np.add.reduce(b * a, axis=1) / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))
    return out


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


def _search(camera, sensor, max_offset, resolution) -> dict:
    """The coarse, fine and sub-grid searches of :func:`estimate_time_offset`."""
    max_offset = float(check_number("max_offset", max_offset, minimum=0))
    resolution = float(check_number("resolution", resolution, minimum=0))
    t, cam = _overlap(camera, sensor, max_offset)
    a = cam - cam.mean()
    coarse = np.arange(-max_offset, max_offset + 1e-12, 0.01)
    c_coarse = _correlations(cam, sensor, t, coarse)
    best = coarse[np.argmax(c_coarse)]
    fine = np.unique(np.clip(np.arange(best - 0.01, best + 0.01 + 1e-12, resolution), -max_offset, max_offset))
    c_fine = _row_correlations(a, sensor, t, fine)
    grid = fine[np.argmax(c_fine)]
    steps = np.concatenate([np.arange(1 - SUBGRID_STEPS, 0), np.arange(1, SUBGRID_STEPS)])
    sub = np.setdiff1d(np.clip(grid + steps * (resolution / SUBGRID_STEPS), -max_offset, max_offset), fine)
    c_sub = _row_correlations(a, sensor, t, sub)
    order = np.argsort(np.concatenate([fine, sub]), kind="stable")
    x, y = np.concatenate([fine, sub])[order], np.concatenate([c_fine, c_sub])[order]
    offset = float(_vertex(x, y))
    corr = float(_row_correlations(a, sensor, t, np.array([offset]))[0])
    curve_x, first = np.unique(np.concatenate([coarse, x, [offset]]), return_index=True)
    return dict(grid=float(grid), offset=offset, corr=corr,
                curve=(curve_x, np.concatenate([c_coarse, y, [corr]])[first]))


def estimate_time_offset(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                         resolution: float = 0.5e-3, full_output: bool = False):
    """Clock offset by cross-correlating angular speeds; returns ``(offset_s, correlation)``.

    The offset ``d`` maximises the correlation ``r(d)`` between the camera's angular speed over
    ``[t_k, t_{k+1}]`` and the sensor's over ``[t_k + d, t_{k+1} + d]`` (sensor slerped). It is searched on a
    10 ms grid in ``[-max_offset, max_offset]``, then on a ``resolution`` grid within 10 ms of the coarse maximum,
    then on the sub-grid ``h = resolution / SUBGRID_STEPS`` within one ``resolution`` of the fine maximum, and
    refined there by the parabola through the maximum and its two neighbours (:func:`_vertex`; for a smooth peak
    its error is ``O(h^2 r'''/r'')``, at most 0.0011 ms on the recordings of :data:`SUBGRID_STEPS`).

    Cost: time ``O((max_offset / 10 ms + 0.02 s / resolution) x camera times)``; memory bounded by
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
        offset, sorted) and their correlations (for :meth:`replication.report.CalibrationResult.plot`).

    Returns
    -------
    (offset_s, correlation) : (float, float)
        The refined offset and ``r`` evaluated at it (one more evaluation, not the parabola's value). With
        ``full_output``: ``(offset_s, correlation, (offsets, correlations))``.

    Raises
    ------
    ValueError
        ``max_offset`` or ``resolution`` not a positive finite number; the streams overlap in fewer than 10
        camera samples once shifted by ``max_offset``.
    """
    s = _search(camera, sensor, max_offset, resolution)
    return (s["offset"], s["corr"], s["curve"]) if full_output else (s["offset"], s["corr"])


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
