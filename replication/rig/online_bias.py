"""The gyro's bias, scale and axis misalignment for the live front end
(:class:`replication.rig.live.LiveRig`).

A raw gyro reports ``T omega + b`` (``T = diag(s) + N(mu)``, the scale per axis and the symmetric
misalignment, Kalibr's and OpenVINS's ``T_g``); integrated over a pairing interval the bias turns
every sensor motion by about ``|b|`` times it, which ``A_j R0 = R0 B_j`` cannot absorb: left in, it
moves ``R0`` (by degrees at 0.1 rad/s); a scale off 1 on one axis does too (3 % on x: 0.5 deg
median, the red team's reproducer), and so does a misalignment (1.5 % on two terms: ``ready`` with
``R0`` 0.3-0.5 deg off, beyond its radius). The live rig holds its first ``offset_window`` seconds
anyway (for the clock offset); on them the bias, the scale per axis and the misalignment are
estimated with ``R0`` as the batch does (:func:`replication.rig.sensor_model.estimate_sensor_model`:
a centred or rest start, then Gauss-Newton on the pair residuals), removed from every rate (``T^-1
(omega - b)``, the held samples integrated again), and published with their 95 % intervals
(:func:`bias_fields`). What their intervals leave in ``R0`` is measured (:func:`bias_effect_deg`:
the chordal minimiser's response to the bias, the log scale and the misalignment, by finite
differences on the window's pairs, through their covariance; an axis whose scale the window does not
resolve is taken as within :data:`SCALE_PRIOR`, a term held at 0 as within
:data:`MISALIGNMENT_PRIOR`); ``ready`` is withheld, naming the bias, the scale or the misalignment
(a ``gyro_bias``, ``gyro_scale`` or ``gyro_misalignment`` reason at level ``fail``, whichever leaves
most), where the bias could not be estimated or where the intervals leave ``R0`` uncertain by the
target or more. Where the scale or the misalignment is what leaves it uncertain, the rig first waits
for more data (up to :data:`BIAS_WAIT_WINDOWS` windows), as for a bias it could not estimate.

Not done online: a bias or scale that changes later (temperature) is not followed; the window's
estimate is kept. Measured (120 s, a ramp of 0.01, 0.03 or 0.05 rad/s from 20 s to the end, or a
step of 0.02 or 0.05 rad/s at 60 s; seeds 14000-14007 each): never ``ready`` at the end with ``R0``
beyond the target or the radius (0 of 40); the pairs it spoils are seen as a change
(``noise_change``, ``outliers`` or ``remount``), not named as the bias.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

__all__ = ["exp3", "start_bias", "start_rig_bias", "hold_raw", "bias_effect_deg", "reintegrate", "bias_fields",
           "rate_correction", "BIAS_STEP_RAD_S", "BIAS_WAIT_WINDOWS", "SCALE_PRIOR", "MISALIGNMENT_PRIOR", "IDENTITY3"]

#: Where the bias cannot be estimated on the first window, the live rig waits for more data up to
#: this many windows.
BIAS_WAIT_WINDOWS = 4

#: The finite-difference step of :func:`bias_effect_deg` (rad/s): small against any bias that
#: matters, large against the solver's convergence (1e-10 in the gradient).
BIAS_STEP_RAD_S = 1e-3

#: The 95 % half-width given to the scale of an axis the first window's motion does not resolve
#: (held at 1, ``scale_resolved`` False): a MEMS gyro's scale factor is within a few per cent of 1
#: (the red team's reproducer: one axis 3 % high moved R0 by 0.55 deg median, ``ready`` 20/20). What
#: such a scale can do to ``R0`` enters :func:`bias_effect_deg`; the finite-difference step on the
#: log scale is :data:`BIAS_STEP_RAD_S` too.
SCALE_PRIOR = 0.03

#: The 95 % half-width given to a misalignment term (``T_g``'s symmetric off-diagonal ``xy``,
#: ``xz``, ``yz``) the first window does not resolve (held at 0, ``misalignment_resolved`` False): a
#: MEMS gyro's cross-axis sensitivity is within about 2 % (datasheets: 1-2 %); a term moves ``R0``
#: by up to 74 deg per unit (the batch's note on its resolution,
#: :data:`replication.rig.sensor_model.MISALIGNMENT_RESOLUTION`), and 1.5 % on two terms, left at 0,
#: moved it by 0.3-0.5 deg with ``ready`` (the red team's reproducer). What such a term can do to
#: ``R0`` enters :func:`bias_effect_deg`, with the finite-difference step :data:`BIAS_STEP_RAD_S`.
MISALIGNMENT_PRIOR = 0.02

#: ``T^-1`` of a gyro read as it is (rows): the live rig's correction before any model.
IDENTITY3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


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


def rate_correction(model) -> tuple:
    """``(b, T^-1)`` of a gyro model as plain tuples (``T^-1`` by rows; the live rig's per-sample
    correction ``T^-1 (omega - b)``, :meth:`replication.rig.live.LiveRig.add_gyro`): zero and the
    identity where ``model`` is None."""
    if model is None:
        return (0.0, 0.0, 0.0), IDENTITY3
    from .gyro_model import axes_matrix

    Ti = np.linalg.inv(axes_matrix(np.log(np.asarray(model.scale, float)), model.misalignment))
    return tuple(float(v) for v in model.bias_rad_s), tuple(tuple(float(v) for v in row) for row in Ti)


def reintegrate(samples, bias, axes_inverse=IDENTITY3) -> list:
    """``[(t, Q), ...]``: the raw gyro ``samples`` ``[(t, (wx, wy, wz)), ...]`` integrated from the
    identity with ``T^-1 (omega - bias)`` (``axes_inverse``: ``T^-1`` by rows; the trapezoidal rule
    of :meth:`replication.rig.live.LiveRig.add_gyro`)."""
    bx, by, bz = (float(v) for v in bias)
    (a, b, c), (d, e, f), (g, k, m) = ((float(v) for v in row) for row in axes_inverse)
    out, Q, last = [], np.eye(3), None
    for t, (wx, wy, wz) in samples:
        if last is not None:
            h = 0.5 * (t - last[0])
            vx, vy, vz = last[1]
            ux, uy, uz = vx + wx - 2 * bx, vy + wy - 2 * by, vz + wz - 2 * bz
            Q = Q @ exp3(h * (a * ux + b * uy + c * uz), h * (d * ux + e * uy + f * uz), h * (g * ux + k * uy + m * uz))
        out.append((t, Q))
        last = (t, (wx, wy, wz))
    return out


def bias_effect_deg(camera, gyro, model, interval: float, level: float = 0.95, parts: bool = False):
    """The radius (deg, at ``level``) of ``R0``'s uncertainty that the gyro model's own uncertainty
    leaves: ``S C S^T`` with ``C`` the covariance of the bias, the log scale and the misalignment
    (``model.covariance`` rows 3-5 and 8-13; an axis whose scale is not resolved, held at 1, is
    given :data:`SCALE_PRIOR` as its 95 % half-width, a term held at 0 :data:`MISALIGNMENT_PRIOR`)
    and ``S`` the chordal minimiser's rotation per unit bias, log scale and term on the window's
    pairs (finite differences of :data:`BIAS_STEP_RAD_S`, the rates ``T^-1 (omega - b)``).
    ``parts``: ``(joint, bias's alone, scale's alone, misalignment's alone)``."""
    from ..core.so3 import rotation_vector_from_matrix
    from ..core.solvers.optimal import chordal_optimal
    from ..core.stats import radius_deg
    from .association import motion_pairs
    from .gyro_model import axes_matrix
    from .streams import GyroStream, integrate_gyro

    def solved(p):
        rates = GyroStream(gyro.t, (gyro.omega - p[:3]) @ np.linalg.inv(axes_matrix(p[3:6], p[6:])).T)
        A, B, _ = motion_pairs(camera, integrate_gyro(rates), interval, offset=model.offset_mid_s)
        return chordal_optimal(A, B).R

    p = np.concatenate([np.asarray(model.bias_rad_s, float), np.log(np.asarray(model.scale, float)),
                        np.asarray(model.misalignment, float)])
    R = solved(p)
    S = np.stack([rotation_vector_from_matrix(R.T @ solved(p + BIAS_STEP_RAD_S * e)) / BIAS_STEP_RAD_S
                  for e in np.eye(9)], axis=-1)
    rows = np.array([3, 4, 5, 8, 9, 10, 11, 12, 13])
    C = np.array(model.covariance, float)[np.ix_(rows, rows)]
    for first, resolved, prior in ((3, model.scale_resolved, SCALE_PRIOR),
                                   (6, model.misalignment_resolved, MISALIGNMENT_PRIOR)):
        held = first + np.flatnonzero(~np.asarray(resolved, bool))
        C[held, :], C[:, held] = 0.0, 0.0
        C[held, held] = (prior / 1.959963984540054) ** 2  # a 95 % half-width of the prior

    def radius(cols):
        cov = S[:, cols] @ C[np.ix_(cols, cols)] @ S[:, cols].T
        return radius_deg(cov, level) if np.all(np.isfinite(cov)) else math.inf

    joint = radius(np.arange(9))
    return (joint, radius(np.arange(3)), radius(np.arange(3, 6)), radius(np.arange(6, 9))) if parts else joint


def start_bias(camera, gyro, *, interval: float, max_offset: float, target_deg: float):
    """The bias, scale and misalignment on the first window (``camera``: an OrientationStream,
    ``gyro``: the raw GyroStream): ``(model, effect_deg, reason)``; ``model`` None where it could
    not be estimated (``reason`` says why); ``effect_deg`` the joint radius of
    :func:`bias_effect_deg`; ``reason`` (a :class:`replication.rig.quality.Reason`, check
    ``gyro_bias``, ``gyro_scale`` or ``gyro_misalignment``, whichever's share of the radius is the
    largest) or None where the gyro is known well enough."""
    model, effects, reason = _start(camera, gyro, interval, max_offset, target_deg)
    return model, effects[0], reason


def _start(camera, gyro, interval, max_offset, target_deg):
    """:func:`start_bias` with the effects ``(joint, bias's, scale's, misalignment's)``."""
    from .quality import Reason
    from .sensor_verdict import model_or_note

    span = float(camera.t[-1] - camera.t[0]) if len(camera.t) else 0.0
    try:
        with np.errstate(invalid="ignore", divide="ignore"):  # a rig at rest: no speed to correlate, said below
            model, note = model_or_note(camera, gyro, interval, max_offset)
    except ValueError as err:  # streams too short for any pair
        model, note = None, str(err)
    if model is None:
        return None, (math.inf,) * 4, Reason("gyro_bias", "fail", None, None, (
            f"the gyro bias could not be estimated on the first {span:.3g} s ({note}): a bias left in the rates "
            f"turns every sensor motion and R0 with it, so R0 is not trusted; give gyro_bias=False if the rates are "
            f"already corrected"))
    try:
        effects = bias_effect_deg(camera, gyro, model, interval, parts=True)
    except (ValueError, np.linalg.LinAlgError) as err:
        effects, why = (math.inf,) * 4, f" ({err})"
    else:
        why = ""
    effect = effects[0]
    if effect < target_deg:
        return model, effects, None
    if effects[3] > max(effects[1], effects[2]):
        return model, effects, Reason("gyro_misalignment", "fail", effect, target_deg,
                                      _misalignment_words(model, span, effects, why, target_deg))
    if effects[2] >= effects[1]:
        return model, effects, Reason("gyro_scale", "fail", effect, target_deg, _scale_words(model, span, effects, why,
                                                                                            target_deg))
    lo, hi = model.bias_ci95_rad_s[:, 0], model.bias_ci95_rad_s[:, 1]
    return model, effects, Reason("gyro_bias", "fail", effect, target_deg, (
        f"the gyro bias {np.round(model.bias_rad_s, 4).tolist()} rad/s, estimated on the first {span:.3g} s, is "
        f"known only to within [{', '.join(f'{a:.3g}..{b:.3g}' for a, b in zip(lo, hi))}] rad/s: that leaves R0 "
        f"uncertain by {effect:.3g} deg (95 %){why} >= the target {target_deg:g} deg; move more (about every "
        f"axis) in the first window, or give a longer offset_window"))


def _term_words(names, values, cis, resolved, fmt, held) -> str:
    """Each term of the gyro model: its value and interval, or that it was held (``held``)."""
    return "; ".join(f"{n} {v:{fmt}} [{lo:{fmt}}, {hi:{fmt}}]" if ok else f"{n} not resolved ({held})"
                     for n, v, (lo, hi), ok in zip(names, values, cis, resolved))


def _scale_words(model, span, effects, why, target_deg) -> str:
    """Why the gyro's scale leaves ``R0`` uncertain: each axis's scale, its interval or that it was
    held at 1."""
    axes = _term_words("xyz", model.scale, model.scale_ci95, model.scale_resolved, ".4f",
                       f"held at 1, taken as within +-{100 * SCALE_PRIOR:g} %")
    note = f"; {model.scale_note}" if model.scale_note else ""
    return (f"the gyro scale per axis, estimated on the first {span:.3g} s and removed from the rates "
            f"({axes}{note}), leaves R0 uncertain by {effects[2]:.3g} deg (95 %; with the bias "
            f"{effects[0]:.3g} deg){why} >= the target {target_deg:g} deg; turn about every axis in the first window, "
            f"or give a longer offset_window")


def _misalignment_words(model, span, effects, why, target_deg) -> str:
    """Why the gyro's axis misalignment leaves ``R0`` uncertain: each term, its interval or that it
    was held at 0."""
    terms = _term_words(("xy", "xz", "yz"), model.misalignment, model.misalignment_ci95, model.misalignment_resolved,
                        "+.4f", f"held at 0, taken as within +-{100 * MISALIGNMENT_PRIOR:g} %")
    note = f"; {model.scale_note}" if model.scale_note else ""
    return (f"the gyro axes' misalignment (T_g's symmetric off-diagonal), estimated on the first {span:.3g} s and "
            f"removed from the rates ({terms}{note}), leaves R0 uncertain by {effects[3]:.3g} deg (95 %; "
            f"with the bias and the scale: {effects[0]:.3g} deg){why} >= the target {target_deg:g} deg; turn about "
            f"every axis in the first window, or give a longer offset_window")


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
    and, where the bias could not be estimated on it (a rig at rest at the start) or its scale
    leaves ``R0`` uncertain beyond the target (an axis not yet resolved: a short window), for more
    data, every half window up to :data:`BIAS_WAIT_WINDOWS` windows (pairs are held meanwhile; at
    the end of the streams: whatever arrived)."""
    from .streams import GyroStream, OrientationStream

    gyro, cam = rig._gyro, rig._camera
    span = cam[-1][0] - cam[0][0] if cam else 0.0
    if not rig._finished and (gyro[-1][0] - gyro[0][0] < rig.offset_window or span < rig._bias_next):
        return False
    camera = OrientationStream(np.array([c[0] for c in cam]), np.array([c[1] for c in cam]), "camera (live)")
    raw = GyroStream(np.array([g[0] for g in rig._raw]), np.array([g[1] for g in rig._raw]), "gyro (live)")
    model, effects, reason = _start(camera, raw, rig.interval, rig.max_offset, rig.calibrator.target_deg)
    waits = model is None or (reason is not None and reason.check in ("gyro_scale", "gyro_misalignment"))
    if waits and not rig._finished and span < BIAS_WAIT_WINDOWS * rig.offset_window:
        rig._bias_next = span + 0.5 * rig.offset_window
        return False
    rig.bias, rig.bias_effect_deg, rig.scale_effect_deg = model, effects[0], effects[2]
    rig.misalignment_effect_deg = effects[3]
    rig._b, rig._Ti = b, Ti = rate_correction(model)
    rebuilt = reintegrate(rig._raw, b, Ti)  # every held pose covered again (the buffer keeps a window only)
    rig._gyro, rig._clock.sensor = deque(rebuilt), deque(rebuilt)  # the clock watch's too (bias removed)
    u = [w - c for w, c in zip(rig._raw[-1][1], b)]
    rig._last_gyro = (rebuilt[-1][0], tuple(sum(k * v for k, v in zip(row, u)) for row in Ti), rebuilt[-1][1])
    rig._raw = None
    if reason is not None:
        rig._name(reason)
    return True


def bias_fields(rig) -> dict:
    """The live rig's summary keys of its gyro model (None where none was estimated): the bias and
    its interval, the scale per axis and its interval (None on an axis held at 1, as the batch
    report's), the misalignment terms and their intervals (None on a term held at 0), the joint
    radius they leave in ``R0`` and the scale's and the misalignment's shares of it."""
    m = rig.bias
    return {
        "gyro_bias_rad_s": None if m is None else m.bias_rad_s.tolist(),
        "gyro_bias_ci95_rad_s": None if m is None else m.bias_ci95_rad_s.tolist(),
        "gyro_bias_R0_deg": None if m is None else float(rig.bias_effect_deg),
        "gyro_scale": None if m is None else [float(v) for v in m.scale],
        "gyro_scale_ci95": None if m is None else [[float(v) for v in ci] if ok else None
                                                   for ci, ok in zip(m.scale_ci95, m.scale_resolved)],
        "gyro_scale_R0_deg": None if m is None else float(rig.scale_effect_deg),
        "gyro_misalignment": None if m is None else [float(v) for v in m.misalignment],
        "gyro_misalignment_ci95": None if m is None else [[float(v) for v in ci] if ok else None for ci, ok in
                                                          zip(m.misalignment_ci95, m.misalignment_resolved)],
        "gyro_misalignment_R0_deg": None if m is None else float(rig.misalignment_effect_deg),
    }
