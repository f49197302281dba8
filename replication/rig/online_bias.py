"""The gyro's bias for the live front end (:class:`replication.rig.live.LiveRig`; issue 34, point 1,
online half).

A raw gyro reports ``omega + b``; integrated over a pairing interval ``T`` the bias turns every
sensor motion by about ``|b| T``, which ``A_j R0 = R0 B_j`` cannot absorb: left in, it moves ``R0``
(by degrees at 0.1 rad/s). The live rig holds its first ``offset_window`` seconds anyway (for the
clock offset); on them the bias is estimated with ``R0`` as the batch does
(:func:`replication.rig.sensor_model.estimate_sensor_model`: a centred or rest start, then
Gauss-Newton on the pair residuals), removed from every rate (the held samples integrated again),
and published with its 95 % interval. What its interval leaves in ``R0`` is measured
(:func:`bias_effect_deg`: the chordal minimiser's response to the bias, by finite differences on the
window's pairs, through the bias's covariance); ``ready`` is withheld, naming the bias (a
``gyro_bias`` reason at level ``fail``), where the bias could not be estimated or where its interval
leaves ``R0`` uncertain by the target or more.

Not done online: a bias that changes later (temperature) is not followed; the window's estimate is
kept.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

__all__ = ["exp3", "start_bias", "start_rig_bias", "hold_raw", "bias_effect_deg", "reintegrate", "BIAS_STEP_RAD_S",
           "BIAS_WAIT_WINDOWS"]

#: Where the bias cannot be estimated on the first window, the live rig waits for more data up to
#: this many windows.
BIAS_WAIT_WINDOWS = 4

#: The finite-difference step of :func:`bias_effect_deg` (rad/s): small against any bias that
#: matters, large against the solver's convergence (1e-10 in the gradient).
BIAS_STEP_RAD_S = 1e-3


def exp3(x: float, y: float, z: float) -> np.ndarray:
    """``exp([w]x)`` of one rotation vector (Rodrigues' formula in plain Python: the per-sample hot
    path of a live gyro; :func:`replication.core.so3.matrix_from_rotation_vector` is the batched
    form, equal to rounding)."""
    t2 = x * x + y * y + z * z
    if t2 < 1e-16:  # second order: sin(t)/t and (1 - cos t)/t^2 to within 1e-24
        a, b = 1.0 - t2 / 6.0, 0.5 - t2 / 24.0
    else:
        t = math.sqrt(t2)
        a, b = math.sin(t) / t, (1.0 - math.cos(t)) / t2
    return np.array([[1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y],
                     [b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x],
                     [b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)]])


def reintegrate(samples, bias) -> list:
    """``[(t, Q), ...]``: the raw gyro ``samples`` ``[(t, (wx, wy, wz)), ...]`` integrated from the
    identity with ``omega - bias`` (the trapezoidal rule of
    :meth:`replication.rig.live.LiveRig.add_gyro`)."""
    bx, by, bz = (float(v) for v in bias)
    out, Q, last = [], np.eye(3), None
    for t, (wx, wy, wz) in samples:
        if last is not None:
            h = 0.5 * (t - last[0])
            vx, vy, vz = last[1]
            Q = Q @ exp3(h * (vx + wx - 2 * bx), h * (vy + wy - 2 * by), h * (vz + wz - 2 * bz))
        out.append((t, Q))
        last = (t, (wx, wy, wz))
    return out


def bias_effect_deg(camera, gyro, model, interval: float, level: float = 0.95) -> float:
    """The radius (deg, at ``level``) of ``R0``'s uncertainty that the bias's own uncertainty
    leaves: ``S C_b S^T`` with ``C_b`` the bias's covariance (``model.covariance[3:6, 3:6]``) and
    ``S`` the chordal minimiser's rotation per unit bias on the window's pairs (finite differences
    of :data:`BIAS_STEP_RAD_S` per axis)."""
    from ..core.so3 import rotation_vector_from_matrix
    from ..core.solvers.optimal import chordal_optimal
    from ..core.stats import radius_deg
    from .association import motion_pairs
    from .streams import GyroStream, integrate_gyro

    def solved(b):
        A, B, _ = motion_pairs(camera, integrate_gyro(GyroStream(gyro.t, gyro.omega - b)), interval,
                               offset=model.offset_mid_s)
        return chordal_optimal(A, B).R

    b = np.asarray(model.bias_rad_s, dtype=float)
    R = solved(b)
    S = np.stack([rotation_vector_from_matrix(R.T @ solved(b + BIAS_STEP_RAD_S * e)) / BIAS_STEP_RAD_S
                  for e in np.eye(3)], axis=-1)
    cov = S @ model.covariance[3:6, 3:6] @ S.T
    return radius_deg(cov, level) if np.all(np.isfinite(cov)) else math.inf


def start_bias(camera, gyro, *, interval: float, max_offset: float, target_deg: float):
    """The bias on the first window (``camera``: an OrientationStream, ``gyro``: the raw
    GyroStream): ``(model, effect_deg, reason)``; ``model`` None where it could not be estimated
    (``reason`` says why); ``reason`` (a :class:`replication.rig.quality.Reason`, check
    ``gyro_bias``) or None where the bias is known well enough."""
    from .quality import Reason
    from .sensor_verdict import model_or_note

    span = float(camera.t[-1] - camera.t[0]) if len(camera.t) else 0.0
    try:
        with np.errstate(invalid="ignore", divide="ignore"):  # a rig at rest: no speed to correlate, said below
            model, note = model_or_note(camera, gyro, interval, max_offset)
    except ValueError as err:  # streams too short for any pair
        model, note = None, str(err)
    if model is None:
        return None, math.inf, Reason("gyro_bias", "fail", None, None, (
            f"the gyro bias could not be estimated on the first {span:.3g} s ({note}): a bias left in the rates "
            f"turns every sensor motion and R0 with it, so R0 is not trusted; give gyro_bias=False if the rates are "
            f"already corrected"))
    try:
        effect = bias_effect_deg(camera, gyro, model, interval)
    except (ValueError, np.linalg.LinAlgError) as err:
        effect, why = math.inf, f" ({err})"
    else:
        why = ""
    if effect < target_deg:
        return model, effect, None
    lo, hi = model.bias_ci95_rad_s[:, 0], model.bias_ci95_rad_s[:, 1]
    return model, effect, Reason("gyro_bias", "fail", effect, target_deg, (
        f"the gyro bias {np.round(model.bias_rad_s, 4).tolist()} rad/s, estimated on the first {span:.3g} s, is "
        f"known only to within [{', '.join(f'{a:.3g}..{b:.3g}' for a, b in zip(lo, hi))}] rad/s: that leaves R0 "
        f"uncertain by {effect:.3g} deg (95 %){why} >= the target {target_deg:g} deg; move more (about every "
        f"axis) in the first window, or give a longer offset_window"))


def hold_raw(raw, t: float, omega, window: float) -> None:
    """Hold one raw gyro sample ``(t, omega)`` in the deque ``raw`` until the bias is estimated, the
    oldest dropped beyond ``BIAS_WAIT_WINDOWS + 1`` windows (O(1) memory where no bias is ever
    tried: no camera, no clock offset; the integration starts where the held samples do, and pairs
    use relative rotations only)."""
    raw.append((t, omega))
    while t - raw[0][0] > (BIAS_WAIT_WINDOWS + 1) * window:
        raw.popleft()


def start_rig_bias(rig) -> bool:
    """The gyro bias on the window a :class:`replication.rig.live.LiveRig` holds (:func:`start_bias`
    on every camera pose and raw rate held so far), removed from its rates (its buffer integrated
    again from the raw samples) and any reason named. False while it waits: for the first window,
    and, where the bias could not be estimated on it (a rig at rest at the start), for more data,
    every half window up to :data:`BIAS_WAIT_WINDOWS` windows (pairs are held meanwhile; at the end
    of the streams: whatever arrived)."""
    from .streams import GyroStream, OrientationStream

    gyro, cam = rig._gyro, rig._camera
    span = cam[-1][0] - cam[0][0] if cam else 0.0
    if not rig._finished and (gyro[-1][0] - gyro[0][0] < rig.offset_window or span < rig._bias_next):
        return False
    camera = OrientationStream(np.array([c[0] for c in cam]), np.array([c[1] for c in cam]), "camera (live)")
    raw = GyroStream(np.array([g[0] for g in rig._raw]), np.array([g[1] for g in rig._raw]), "gyro (live)")
    model, effect, reason = start_bias(camera, raw, interval=rig.interval, max_offset=rig.max_offset,
                                       target_deg=rig.calibrator.target_deg)
    if model is None and not rig._finished and span < BIAS_WAIT_WINDOWS * rig.offset_window:
        rig._bias_next = span + 0.5 * rig.offset_window
        return False
    rig.bias, rig.bias_effect_deg = model, effect
    rig._b = b = (0.0, 0.0, 0.0) if model is None else tuple(float(v) for v in model.bias_rad_s)
    rebuilt = reintegrate(rig._raw, b)  # every held pose covered again (the buffer keeps a window only)
    rig._gyro = deque(rebuilt)
    rig._last_gyro = (rebuilt[-1][0], tuple(w - c for w, c in zip(rig._raw[-1][1], b)), rebuilt[-1][1])
    rig._raw = None
    if reason is not None:
        rig._name(reason)
    return True
