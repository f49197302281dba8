"""Last-bit jitter of every generated and loaded input, for the portability re-runs. Theory and
measured numbers: ``docs/reading.md``, section ``replication._jitter``."""
import json
import os
import zlib

import numpy as np

ENV = "REPLICATION_JITTER"
DEFAULT_SCALE = 1e-15
MARGIN_ENV = "REPLICATION_MARGIN_SCALE"
GUARD_LOG_ENV = "REPLICATION_GUARD_LOG"
_ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
#: numpy's SIMD dispatch limited to AVX2 (an AVX-512 machine computes as one without it), or to the
#: SSE4.2 baseline.
AVX2 = "X86_V4 AVX512_ICL AVX512_SPR"
SSE42 = "X86_V3 " + AVX2
#: The machines the stored notebook outputs must hold on, as environments: last-bit jitter of the
#: inputs (each variant its own draw), numpy's dispatch limited, OpenBLAS forced to another CPU's
#: kernels, one thread. ``margin`` jitters at 1e-13 (100 times the last-bit jitter, a few hundred
#: units in the last place: an output it moves sits near a rounding edge; 1e-11 broke the notebooks'
#: 1e-12 checks of exact identities) and doubles every guard's margin (:func:`margin_scale`: what
#: passes there has room for a machine's spread). The README's test command re-runs the notebooks
#: under ``avx2`` (``tests/notebooks/test_portability_*.py``); ``scripts/spread.py`` under all.
VARIANTS = {
    "jitter": {ENV: "1"},
    "avx2": {ENV: "2", "NPY_DISABLE_CPU_FEATURES": AVX2, "OPENBLAS_CORETYPE": "Haswell", **_ONE_THREAD},
    "sse42": {ENV: "3", "NPY_DISABLE_CPU_FEATURES": SSE42, "OPENBLAS_CORETYPE": "Nehalem", **_ONE_THREAD},
    "skylakex": {ENV: "4", "OPENBLAS_CORETYPE": "SkylakeX"},
    "margin": {ENV: "5:1e-13", MARGIN_ENV: "2", "NPY_DISABLE_CPU_FEATURES": AVX2, "OPENBLAS_CORETYPE": "Zen"},
}
#: The variants that model another machine (the spread); ``margin`` measures the distance to a
#: rounding edge.
LAST_BIT = ("jitter", "avx2", "sse42", "skylakex")


def margin_scale() -> float:
    """The factor (``REPLICATION_MARGIN_SCALE``, default 1) by which every guard of a rounding edge
    multiplies its margin (:func:`replication.core.stats.declared_bound`, ``bracket``,
    ``share_range``). ``scripts/spread.py`` runs one variant at 2: an output that passes there sits
    at least twice its margin inside its bound, so a machine that moves it by less than the margin
    prints the same text and passes the guard at 1."""
    text = os.environ.get(MARGIN_ENV, "").strip()
    try:
        scale = float(text) if text else 1.0
    except ValueError:
        scale = -1.0
    if not scale >= 1.0:
        raise ValueError(f"{MARGIN_ENV} must be a number >= 1, got {text!r}")
    return scale


def guard_failed(record: dict) -> bool:
    """Whether a guard of a rounding edge that does not hold should raise: yes, unless
    ``REPLICATION_GUARD_LOG`` names a file, to which the record (what, value, bound, margin) is then
    appended as a JSON line, so that one run of a notebook lists every guard that does not hold
    (``scripts/spread.py`` reads them)."""
    path = os.environ.get(GUARD_LOG_ENV, "").strip()
    if not path:
        return True
    with open(path, "a", encoding="utf-8") as log:
        log.write(json.dumps(record, default=float) + "\n")
    return False


def jitter_setting(value: str | None = None) -> tuple[int, float] | None:
    """``(seed, scale)`` from ``REPLICATION_JITTER`` (or ``value``); ``None`` when jitter is off.

    >>> jitter_setting("3"), jitter_setting("2:1e-9"), jitter_setting("0"), jitter_setting("")
    ((3, 1e-15), (2, 1e-09), None, None)
    """
    text = os.environ.get(ENV, "") if value is None else value
    text = text.strip()
    if text in ("", "0"):
        return None
    seed_text, _, scale_text = text.partition(":")
    try:
        seed = int(seed_text)
        scale = float(scale_text) if scale_text else DEFAULT_SCALE
    except ValueError:
        raise ValueError(f"{ENV} must be SEED or SEED:SCALE (a positive integer, a scale in (0, 1e-3]), "
                         f"got {text!r}") from None
    if seed < 1 or not 0.0 < scale <= 1e-3:
        raise ValueError(f"{ENV} must be SEED or SEED:SCALE (a positive integer, a scale in (0, 1e-3]), got {text!r}")
    return seed, scale


def jitter(x, setting: tuple[int, float] | None = None):
    """``x`` with every float entry moved by a relative ``scale * u``, ``|u| <= 1``; ``x`` itself
    when jitter is off.

    Integer, boolean and non-array inputs are returned unchanged. ``setting``: ``(seed, scale)``, by
    default read from ``REPLICATION_JITTER`` on every call.
    """
    setting = jitter_setting() if setting is None else setting
    if setting is None or not isinstance(x, np.ndarray) or not np.issubdtype(x.dtype, np.floating) or x.size == 0:
        return x
    seed, scale = setting
    data = np.ascontiguousarray(x)
    rng = np.random.default_rng([seed, zlib.crc32(data.tobytes()), data.size])
    return data * (1.0 + scale * rng.uniform(-1.0, 1.0, data.shape))
