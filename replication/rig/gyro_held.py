"""What the gyro's held axes terms can do to ``R0``, and which frame ``R0`` refers to
(:mod:`replication.rig.sensor_model`): :func:`held_effect_deg` is how far ``R0`` could move (first
order, the free parameters re-fitted) were the scales held at 1 and the misalignment terms held at 0
as far off as a MEMS gyro's are (:data:`HELD_PRIORS`), worst signs; :func:`triangular_frame_deg` is
the angle between ``R0``'s sensor frame (the gyro's orthogonalised frame, the polar factor of
``T_g``) and the frame of a triangular ``T_g`` (Kalibr's, OpenVINS's: one gyro axis defines the
frame) with the same symmetric part; :func:`held_reasons` turns both into verdict reasons,
:func:`held_report` into the report's fields and :func:`held_lines` into the summary's lines
(``docs/conventions.md``, ``docs/judging.md``).
"""
from __future__ import annotations

import itertools
import math

import numpy as np

__all__ = ["HELD_PRIORS", "HELD_R0_BOUND_DEG", "held_effect_deg", "triangular_frame_deg", "held_reasons",
           "held_report", "held_lines", "triangular_words"]

#: The plausible size of a held term, per kind: ``scale`` ``|s - 1|``, ``misalignment`` ``|mu|``.
#: A MEMS gyro's sensitivity (scale) tolerance is +-3 % and its cross-axis sensitivity (an
#: off-diagonal element of ``T_g``, so a symmetric term of up to as much) +-2 % (InvenSense's
#: MPU-6000/MPU-6050 product specification PS-MPU-6000A-00 rev. 3.4, section 6.1, gyroscope:
#: "Sensitivity Scale Factor Tolerance -3 / +3 %", "Cross-Axis Sensitivity +-2 %"); the online
#: estimator gives a held scale the same 3 % (``replication.rig.online_bias.SCALE_PRIOR``).
HELD_PRIORS = {"scale": 0.03, "misalignment": 0.02}
#: A held term that could move ``R0`` further than this (deg), or a triangular frame this far from
#: ``R0``'s, is named (a warning): EuRoC's reference floor, the angle between two published
#: calibrations of the same camera (Kalibr's and Basalt's cam0), below which no claim on ``R0`` is
#: checked.
HELD_R0_BOUND_DEG = 0.343
_TERMS = ("scale x", "scale y", "scale z", "misalignment xy", "misalignment xz", "misalignment yz")


def held_effect_deg(normal_matrix, free, held, priors) -> tuple:
    """How far ``R0`` could move (deg, first order) were the ``held`` parameters off by up to
    ``priors`` (one per held parameter, in its own units: log scale or term), worst signs, the
    ``free`` parameters (indices into the normal matrix, ``R0``'s rotation first three) re-fitted.

    Returns ``(degrees, per-parameter degrees)``: the worst combination and each held parameter's
    own effect at its prior. ``normal_matrix`` is ``J^T W J`` at the solution over all parameters
    (``SensorModel.normal_matrix``); ``free`` must hold 0, 1, 2 (``R0``).
    """
    H = np.asarray(normal_matrix, float)
    free, held = np.asarray(free, int), np.asarray(held, int)
    priors = np.broadcast_to(np.asarray(priors, float), held.shape)
    if not set(range(3)) <= set(free.tolist()):
        raise ValueError("the free parameters must include R0's rotation (indices 0, 1, 2)")
    if held.size == 0:
        return 0.0, np.zeros(0)
    if not (np.all(np.isfinite(H)) and np.all(np.isfinite(priors)) and np.all(priors >= 0)):
        raise ValueError("the normal matrix and the priors must be finite, the priors non-negative")
    Hff = H[np.ix_(free, free)]
    scale = np.sqrt(np.maximum(np.diag(Hff), 1e-300))
    moves = -np.linalg.lstsq(Hff / np.outer(scale, scale), H[np.ix_(free, held)] / scale[:, None],
                             rcond=None)[0] / scale[:, None]
    per = moves[[list(free).index(i) for i in range(3)]] * priors  # R0's rotation (rad) per held parameter at its prior
    worst = max(np.linalg.norm(per @ np.array(signs)) for signs in itertools.product((1.0, -1.0), repeat=held.size))
    return math.degrees(worst), np.degrees(np.linalg.norm(per, axis=0))


def triangular_frame_deg(scale, misalignment) -> dict:
    """The angle (deg) between the frame of the gyro's symmetric axes ``P = diag(scale) + N(mu)``
    (``R0``'s sensor frame: the gyro reads ``P R omega`` for a ``T_g = P R``) and the frame of a
    triangular ``T_g = P R`` (``upper``: the gyro's z axis lies along the frame's, its y axis in the
    frame's y-z plane; ``lower``: its x axis along the frame's x, its y axis in the x-y plane), per
    convention: the rotation ``R`` of ``P``'s RQ decomposition. To first order both are
    ``|mu|`` (rad): a triangular ``T_g``'s term ``m`` is a symmetric ``m / 2`` and a rotation by
    ``m / 2``."""
    from scipy.linalg import rq

    P = np.diag(np.asarray(scale, float))
    for m, (a, c) in zip(np.asarray(misalignment, float), ((0, 1), (0, 2), (1, 2))):
        P[a, c] = P[c, a] = m
    if not (np.all(np.isfinite(P)) and np.linalg.det(P) > 0):
        raise ValueError("the gyro's axes (scale, misalignment) must be finite with a positive determinant")
    out = {}
    flip = np.eye(3)[::-1]
    for name, M in (("upper", P), ("lower", flip @ P @ flip)):
        U, R = rq(M)
        R = np.diag(np.sign(np.diag(U))) @ R  # U's diagonal positive: R the rotation
        if name == "lower":
            R = flip @ R @ flip
        out[name] = math.degrees(math.acos(float(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))
    return out


def _held(model):
    """The held misalignment terms (indices into the 14) and their priors; none where the model held
    them all for another reason (``scale_note``: no plausible scale) or carries no normal matrix."""
    if getattr(model, "normal_matrix", None) is None or model.scale_note is not None:
        return np.zeros(0, int), np.zeros(0)
    # the held scales are judged from the data by sensor_verdict's gyro_scale_held (their interval
    # fitted free): here only the misalignment terms, so that one cause is named once
    held = 11 + np.flatnonzero(~np.asarray(model.misalignment_resolved, bool))
    return held, np.full(held.size, HELD_PRIORS["misalignment"])


def held_report(model) -> dict:
    """The report's fields (under ``sensor_model``): ``held_terms`` (the names of the parameters
    held), ``held_R0_deg`` (:func:`held_effect_deg` at :data:`HELD_PRIORS`, worst signs),
    ``held_priors`` and ``triangular_frame_deg`` (:func:`triangular_frame_deg` of the estimate)."""
    held, priors = _held(model)
    effect = 0.0
    if held.size:
        free = np.concatenate([np.arange(8), np.setdiff1d(np.arange(8, 14), held)])
        effect = held_effect_deg(model.normal_matrix, free, held, priors)[0]
    return {"held_terms": [_TERMS[i - 8] for i in held], "held_R0_deg": float(effect),
            "held_priors": dict(HELD_PRIORS), "triangular_frame_deg": triangular_frame_deg(model.scale,
                                                                                          model.misalignment)}


def triangular_words(model) -> str:
    """The words a misalignment reason ends with: ``R0``'s frame and the triangular ``T_g``'s angle
    from it (:func:`triangular_frame_deg`, the larger convention's)."""
    angle = max(triangular_frame_deg(model.scale, model.misalignment).values())
    return (f"; R0 refers to the gyro's orthogonalised frame, {angle:.2g} deg from the frame of a triangular T_g with "
            f"these terms (Kalibr's, OpenVINS's convention)")


def held_reasons(model) -> list:
    """The verdict's reasons (warnings, :class:`replication.rig.quality.Reason`): ``gyro_held``
    where the held terms could move ``R0`` by more than :data:`HELD_R0_BOUND_DEG` at their plausible
    size; ``gyro_triangular_frame`` where a triangular ``T_g``'s frame lies further than it from
    ``R0``'s (a user whose sensor frame follows that convention reads ``R0`` that far off)."""
    from .quality import Reason

    out, fields, bound = [], held_report(model), HELD_R0_BOUND_DEG
    if fields["held_R0_deg"] > bound:
        out.append(Reason(
            "gyro_held", "warning", fields["held_R0_deg"], bound,
            f"gyro terms held, not resolved by the motion: {', '.join(fields['held_terms'])} (held at 0); were they "
            f"as far off as a MEMS gyro's can be (+-{100 * HELD_PRIORS['misalignment']:g} %) they could "
            f"move R0 by up to {fields['held_R0_deg']:.2g} deg on this motion (first order) > {bound:g} deg, "
            f"which R0's radius does not hold; record longer, turning about every axis, or calibrate the gyro's "
            f"T_g first"))
    angle = max(fields["triangular_frame_deg"].values())
    if angle > bound and model.misalignment_resolved.any():
        out.append(Reason(
            "gyro_triangular_frame", "warning", float(angle), bound,
            f"R0 refers to the gyro's orthogonalised frame (T_g's symmetric part removed); the frame of a "
            f"triangular T_g with the same terms (Kalibr's, OpenVINS's convention: one gyro axis defines the "
            f"frame) lies {angle:.2g} deg from it > {bound:g} deg: where the sensor frame follows that convention, "
            f"R0 differs from it by that rotation"))
    return out


def held_lines(details) -> list:
    """The summary's lines from a report's ``sensor_model`` details (:func:`held_report`'s fields;
    none where absent): the frame ``R0`` refers to and the triangular frame's angle, the held terms
    and what they could do to ``R0``."""
    tri = details.get("triangular_frame_deg")
    if tri is None:
        return []
    lines = [f"R0's sensor frame: the gyro's orthogonalised frame (T_g's symmetric part removed); a triangular "
             f"T_g with these terms (Kalibr's, OpenVINS's convention) has its frame {tri['upper']:.3f} deg (upper) / "
             f"{tri['lower']:.3f} deg (lower triangular) from it"]
    if details.get("held_terms"):
        priors = details.get("held_priors", HELD_PRIORS)
        lines.append(f"gyro terms held (not resolved): {', '.join(details['held_terms'])}; as far off as a MEMS "
                     f"gyro's can be (scale +-{100 * priors['scale']:g} %, misalignment "
                     f"+-{100 * priors['misalignment']:g} %) they could move R0 by up to "
                     f"{details['held_R0_deg']:.3g} deg (first order)")
    return lines
