"""Timestamped rotation streams: orientations, gyroscope rates, and gyro integration. Theory and
measured numbers: ``docs/reading.md``, section ``replication.rig.streams``."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.checks import check_rotation_matrices
from ..core.so3 import cumulative_product, matrix_from_rotation_vector, slerp_interpolator

__all__ = ["OrientationStream", "GyroStream", "integrate_gyro", "time_unit_mismatch", "PLAUSIBLE_SPAN_S"]


@dataclass(frozen=True)
class OrientationStream:
    """Timestamped orientations: ``world_from_body[k]`` at time ``t[k]`` (s, strictly increasing).

    Parameters
    ----------
    t : array_like (N,)
        Times in seconds, N >= 2, finite, strictly increasing.
    world_from_body : array_like (N, 3, 3)
        Rotations mapping body-frame vectors into the world (checked to 1e-5).
    source : str
        Where the stream comes from (used in error messages).

    Notes
    -----
    ``R`` is a read-only alias of ``world_from_body``; ``OrientationStream(t, R, source)``
    (positional) builds the same stream.
    """

    t: np.ndarray
    world_from_body: np.ndarray
    source: str = ""
    _interpolator: object = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        R = check_rotation_matrices(self.world_from_body, f"{self.source or 'orientation stream'} R", atol=1e-5)
        _validate_stream(self, "world_from_body", R, (3, 3))

    @property
    def R(self) -> np.ndarray:
        """``world_from_body`` (the same array)."""
        return self.world_from_body

    def at(self, times) -> np.ndarray:
        """``world_from_body`` slerp-interpolated at ``times`` (which must lie inside the stream).

        The interpolator (:func:`replication.core.so3.slerp_interpolator`) is built on the first
        call and kept on the stream.
        """
        interpolator = self._interpolator
        if interpolator is None:
            interpolator = slerp_interpolator(self.t, self.world_from_body)
            object.__setattr__(self, "_interpolator", interpolator)
        return interpolator(times)

    def between(self, start: float, stop: float) -> OrientationStream:
        """The samples with ``start <= t <= stop``."""
        keep = (self.t >= start) & (self.t <= stop)
        return OrientationStream(self.t[keep], self.world_from_body[keep], self.source)


@dataclass(frozen=True)
class GyroStream:
    """Angular velocity ``omega[k]`` (rad/s, body frame) at time ``t[k]`` (s, strictly
    increasing)."""

    t: np.ndarray
    omega: np.ndarray
    source: str = ""

    def __post_init__(self):
        w = np.asarray(self.omega, dtype=float)
        if not np.all(np.isfinite(w)):
            raise ValueError(f"{self.source}: angular velocity contains NaN or inf")
        _validate_stream(self, "omega", w, (3,))


def _validate_stream(stream, name: str, values: np.ndarray, tail: tuple) -> None:
    """Check shapes and timestamps of a frozen stream and store the converted arrays on it."""
    t = np.asarray(stream.t, dtype=float)
    if t.ndim != 1 or values.shape != t.shape + tail:
        raise ValueError(f"{stream.source}: need t of shape (N,) and {name} of shape (N, {', '.join(map(str, tail))}), "
                         f"got {t.shape}, {values.shape}")
    _check_times(t, stream.source)
    object.__setattr__(stream, "t", t)
    object.__setattr__(stream, name, values)


def _check_times(t, source):
    """At least 2 finite, strictly increasing timestamps."""
    if len(t) < 2:
        raise ValueError(f"{source}: need at least 2 samples, got {len(t)}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{source}: timestamps contain NaN or inf")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise ValueError(f"{source}: timestamps not strictly increasing at sample {bad[0] + 1} "
                         f"({float(t[bad[0]])!r} then {float(t[bad[0] + 1])!r})")


def integrate_gyro(gyro: GyroStream) -> OrientationStream:
    """Orientation ``world_from_body`` (``Q(t_0) = I``) from body-frame rates, trapezoidal rule.

    ``Q_{k+1} = Q_k exp([(omega_k + omega_{k+1}) / 2] dt_k)``; the products are a batched prefix
    scan (:func:`replication.core.so3.cumulative_product`). No bias is removed here:
    :func:`replication.rig.calibration.calibrate` estimates a gyro's bias with ``R0`` and removes it
    first (:mod:`replication.rig.sensor_model`; ``gyro_bias=False`` keeps the rates as recorded).
    """
    dt = np.diff(gyro.t)
    steps = matrix_from_rotation_vector(0.5 * (gyro.omega[:-1] + gyro.omega[1:]) * dt[:, None])
    Q = np.concatenate([np.eye(3)[None], cumulative_product(steps)])
    return OrientationStream(gyro.t, Q, f"integrated {gyro.source}")


#: Spans (s) a calibration recording plausibly has (a second to about three hours); a time-unit
#: mistake puts one stream far outside, as does a first time stamp beyond 1e10 s (Unix seconds reach
#: that in 2286).
PLAUSIBLE_SPAN_S = (1.0, 1e4)
_UNITS = ("seconds", "milliseconds", "microseconds", "nanoseconds")
_SHORT = {"seconds": "s", "milliseconds": "ms", "microseconds": "us", "nanoseconds": "ns"}


def _misreadings(factor: float, finer: bool) -> list:
    """The (file's unit, unit read in) pairs ``factor`` apart, the file's unit the finer one when
    ``finer``: one read in s (a TUM trajectory) or ns (a CSV) first."""
    step = round(np.log10(factor) / 3)
    pairs = [(_UNITS[i + step], _UNITS[i]) if finer else (_UNITS[i], _UNITS[i + step])
             for i in range(len(_UNITS) - step)]
    return sorted(pairs, key=lambda pair: pair[1] not in ("seconds", "nanoseconds"))


def time_unit_mismatch(camera, sensor):
    """``(ratio, factor, sentence)`` when the two streams' spans differ by about 1e3, 1e6 or 1e9
    (one file's time stamps in another unit than its loader read them in), else None. The sentence
    blames the stream whose span (or first stamp, beyond 1e10 s) is implausible for a recording
    (:data:`PLAUSIBLE_SPAN_S`), says whether its unit is finer or coarser than the one it was read
    in, names the pairs of units that fit (the unit read in is not known here: microseconds read
    as nanoseconds and seconds as milliseconds look alike) and the option that reads the file."""
    cs, ss = camera.t[-1] - camera.t[0], sensor.t[-1] - sensor.t[0]
    if not (cs > 0 and ss > 0):
        return None
    ratio = max(cs, ss) / min(cs, ss)
    factor = next((f for f in (1e3, 1e6, 1e9) if 0.5 < ratio / f < 2.0), None)
    if factor is None:
        return None
    lo, hi = PLAUSIBLE_SPAN_S
    odd = [(name, span) for name, span, start in (("camera", cs, camera.t[0]), ("sensor", ss, sensor.t[0]))
           if not lo <= span <= hi or abs(start) > 1e10]
    if len(odd) == 1:
        name, span = odd[0]
        finer = span == max(cs, ss)
        pairs = _misreadings(factor, finer)
        how = ", or ".join(f"{unit} read as {read}" for unit, read in pairs)
        culprit = (f"the {name} file's time stamps are likely in another unit than they were read in, one "
                   f"{factor:.0e} times {'finer' if finer else 'coarser'} ({how})")
        option = f"--{name}-time-unit " + (_SHORT[pairs[0][0]] if len(pairs) == 1 else "with the file's unit")
    else:
        culprit = (f"one of the two files' time stamps are likely in another unit than they were read in, one "
                   f"{factor:.0e} times finer or coarser")
        option = "--camera-time-unit / --sensor-time-unit with the file's unit"
    return float(ratio), factor, (
        f"the camera stream spans {cs:.4g} s and the sensor stream {ss:.4g} s, a factor of about {factor:.0e}: "
        f"{culprit}; {option} reads it (TUM trajectories and EuRoC / TUM-VI CSV files alike; a CSV's default is "
        f"ns)")
