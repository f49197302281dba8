"""Registry of rotation-only hand-eye solvers: adding a baseline is one decorated function.

Every solver has one public door that validates (:func:`solve`, or the function
:func:`register` returns) and one private core that receives a validated
:class:`replication.core.motions.Motions` and never validates again (the pattern of
OpenCV's ``calibration_handeye.cpp``).
"""
from __future__ import annotations

import functools
import inspect
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..checks import _first_index, det3
from ..handeye import vec
from ..motions import Motions, prepare_motions
from ..so3 import angle_between_deg
from ._warnings import AccuracyWarning, ConvergenceWarning, LocalMinimumWarning, ObservabilityWarning
from .certificate import _derivatives, _gap_to_global, certified_solution, global_certificate

__all__ = ["SolverInfo", "register", "available", "solver_info", "solve",
           "LOCAL_RTOL", "LOCAL_ATOL", "LOCAL_ANGLE_TOL_DEG", "WRONG_POINT_DEG", "GROSS_FACTOR", "WEAK_GAP_FACTOR",
           "ANSWER_ATOL", "check_answer", "warn_if_weak", "SolverAnswerError", "checked_core"]

#: A local solver's answer is flagged (:class:`LocalMinimumWarning`) when its cost (8) exceeds the
#: certified global minimum ``f*`` by more than ``LOCAL_RTOL * f* + LOCAL_ATOL * J``. Near the
#: minimum the excess grows like ``J delta^2`` (``delta`` the angle to the minimiser, radians, times
#: a curvature of order 2-3), so either term corresponds to about 0.03 deg at the paper's noise:
#: well above SLSQP's own stopping jitter (0.01 deg seen), far below an answer in another basin or
#: stopped far away at an iteration limit (0.3-43 % of ``f*`` and tens of degrees off).
LOCAL_RTOL = 1e-3
LOCAL_ATOL = 1e-6
#: Within the basin of the global minimum, a local solver's answer farther than this from the
#: certified minimiser gets a :class:`ConvergenceWarning` (it stopped short, e.g. on SLSQP's
#: objective tolerance).
LOCAL_ANGLE_TOL_DEG = 1e-4
#: An answer above the certified minimum and farther than this from the minimiser did not reach the
#: global minimum (:class:`LocalMinimumWarning`: another stationary point, or stopped before
#: converging); closer, it stopped short (:class:`ConvergenceWarning`). The minima of eq. (8) seen
#: here lie 100 deg and more apart (notebook 06); SLSQP's short stops are hundredths of a degree.
WRONG_POINT_DEG = 1.0
#: ``|grad f| / J`` above which an answer is not a stationary point of eq. (8) (the warning then
#: says the solver stopped before converging rather than on another stationary point).
STATIONARY_TOL = 1e-3
#: A non-local solver's answer gets an :class:`AccuracyWarning` when its cost (8) exceeds
#: ``GROSS_FACTOR`` times the certified minimum plus ``LOCAL_ATOL * J``: a failure, not a less
#: efficient estimate. Measured on 300 problems each at the paper's noise and J = 3, 5, 20 (and 5
#: deg noise): the closed forms stay within 1.2x of the minimum cost, OpenCV (whose pose chain
#: accumulates noise) within 6x, the two-step fixed point within 4.4x at J >= 5; the half-turn sign
#: flips of Park & Martin, Horaud & Dornaika and Tsai & Lenz cost 35-8000x.
GROSS_FACTOR = 10.0
#: The motions count as weakly determining ``R0`` (:class:`ObservabilityWarning`) when the gap
#: between the two largest eigenvalues of ``sym(K)`` is below this many times the data's
#: inconsistency ``1 - lambda_1``.
WEAK_GAP_FACTOR = 3.0
#: :func:`solve` refuses (``ValueError``) a core's answer block with ``||R^T R - I||_F`` or ``| |det
#: R| - 1 |`` above this. Measured over the contract, solver-core, baseline and registry tests'
#: problems and 1700 harsher ones (J = 3-20, noise up to 17 deg, motions of 0.5-3 deg and of 150-180
#: deg, 40 % outliers): every registered solver stays within 1.1e-14 except OpenCV's Park & Martin
#: ((M^T M)^(-1/2) M^T of an ill-conditioned M: 4e-11 in the tests, 8e-9 at 17 deg noise with small
#: motions). 1e-6 is 100x above that, and the tolerance at which every door of the package
#: (``checks.ROTATION_ATOL``) accepts its input as a rotation, so an answer passes as ``init`` or
#: data anywhere; a non-rotation part of 1e-6 is 3e-5 deg, far below any solver's error at the
#: paper's noise.
ANSWER_ATOL = 1e-6


@dataclass(frozen=True)
class SolverInfo:
    """A registered solver.

    Attributes
    ----------
    name : str
        The ``method`` name given to :func:`solve`.
    core : callable
        ``core(motions, **options) -> ndarray (..., 3, 3)``; receives a validated
        :class:`replication.core.motions.Motions`. It returns one rotation per problem (a reflection
        is warned about), or a whole 3x3 block of NaN for a problem it declares failed;
        :func:`solve` refuses anything else (see :data:`ANSWER_ATOL`).
    reference : str
        The paper the solver implements.
    min_motions : int
        Fewest motion pairs ``J`` it accepts.
    local : bool
        ``True`` for a local method whose answer depends on a start ``init`` (an option it accepts);
        from a start far from ``R0`` it may stop short of the minimum (an iteration limit) or on
        another stationary point. :func:`solve` then checks its answer against the certified global
        minimum of eq. (8).
    equivariant : bool
        ``True`` if re-expressing the camera frame by ``G`` (``A -> G A G^T``)
        maps the estimate to ``G R``, and likewise for the sensor frame
        (``B -> G B G^T``, ``R -> R G^T``), also with noisy data. Tsai & Lenz's
        Gibbs-vector parametrisation is not.
    relaxed_start : bool
        ``True`` for a solver that reads the eigenvectors of ``sym(K)`` (the relaxed solution,
        ``motions.sym_eigh``): :func:`solve` then decomposes ``sym(K)`` once, vectors included, and
        its answer checks read its eigenvalues (equal to ``eigvalsh``'s to rounding) instead of
        decomposing again: one decomposition, not two.
    """

    name: str
    core: Callable[..., np.ndarray]
    reference: str
    min_motions: int
    local: bool = False
    equivariant: bool = True
    relaxed_start: bool = False


_REGISTRY: dict[str, SolverInfo] = {}


def register(name: str, *, reference: str, min_motions: int = 2, local: bool = False,
             equivariant: bool = True, relaxed_start: bool = False):
    """Decorator adding a solver core to the registry; returns its public, validating door.

    The decorated ``core(motions, **options)`` receives a :class:`replication.core.motions.Motions`
    already validated by :func:`solve` (rotations, same shape, ``J >= min_motions``, not
    degenerate): ``motions.A`` (camera relative rotations), ``motions.B`` (sensor relative
    rotations), both ``(..., J, 3, 3)``, and the cached ``motions.K``. It returns
    ``camera_from_sensor``, a numpy array of shape ``(..., 3, 3)``: a rotation per problem, or a
    whole 3x3 block of NaN for a problem it declares failed; :func:`solve` refuses anything else.

    The decorator returns ``public(A, B, **options) = solve(name, A, B, **options)``,
    so the exported name validates its input like every other door.

    Raises
    ------
    ValueError
        If ``name`` is already registered or ``min_motions < 1``.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"solver name must be a non-empty string, got {name!r}")
    if min_motions < 1:
        raise ValueError(f"min_motions must be >= 1, got {min_motions}")

    def decorate(core):
        if name in _REGISTRY:
            raise ValueError(f"a solver named {name!r} is already registered")
        _REGISTRY[name] = SolverInfo(name, core, reference, int(min_motions), bool(local), bool(equivariant),
                                     bool(relaxed_start))

        @functools.wraps(core)
        def public(A, B=None, **options):
            return solve(name, A, B, _stacklevel=4, **options)

        public.core = core
        public.__signature__ = _door_signature(core)  # what the door takes, not the core's (motions, ...)
        return public

    return decorate


def _door_signature(core) -> inspect.Signature:
    """``(A, B=None, *, full_output=False, warn_axis_spread_deg=1.0, <the core's options>)``:
    :func:`solve`'s."""
    P = inspect.Parameter
    head = [P("A", P.POSITIONAL_OR_KEYWORD), P("B", P.POSITIONAL_OR_KEYWORD, default=None),
            P("full_output", P.KEYWORD_ONLY, default=False, annotation="bool"),
            P("warn_axis_spread_deg", P.KEYWORD_ONLY, default=1.0, annotation="float")]
    options = [p if p.kind in (P.KEYWORD_ONLY, P.VAR_KEYWORD) else p.replace(kind=P.KEYWORD_ONLY)
               for p in list(inspect.signature(core).parameters.values())[1:] if p.kind != P.VAR_POSITIONAL]
    return inspect.Signature(head + options, return_annotation="np.ndarray | Solution")


def available() -> list[str]:
    """Names of all registered solvers, sorted."""
    return sorted(_REGISTRY)


def solver_info(method: str) -> SolverInfo:
    """The :class:`SolverInfo` of ``method``; unknown names raise ``ValueError`` listing all."""
    try:
        return _REGISTRY[method]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown solver {method!r}; available: {', '.join(available())}"
        ) from None


def warn_if_weak(motions: Motions, warn_axis_spread_deg: float = 1.0, stacklevel: int = 3) -> None:
    """Issue an :class:`ObservabilityWarning` where the motions weakly determine ``R0``.

    Three tests, each naming what it measured: nearly single-axis motion (axis spread below
    ``warn_axis_spread_deg``; reported as small motions when the RMS motion itself is that small);
    motion about one axis but for one pair (``J >= 3``: the spread without the pair that turns most
    about other axes below ``warn_axis_spread_deg``,
    :attr:`replication.core.motions.Motions.leave_one_out_spread_deg`); and a second rotation
    fitting eq. (8) almost as well (gap between the two largest eigenvalues of ``sym(K)`` below
    ``WEAK_GAP_FACTOR`` times the data's inconsistency ``1 - lambda_1``: motions small for the
    noise, outlier pairs, or near-symmetric motions).
    """
    # the cached pieces of motions.observability these tests need, without the singular values of K
    # it also holds
    camera_spread, sensor_spread = motions.axis_spread_deg
    rms_motion = motions.rms_motion_deg
    ev = motions.sym_eigvals
    symmetric_gap, inconsistency = ev[..., 0] - ev[..., 1], 1.0 - ev[..., 0]
    spread = np.minimum(camera_spread, sensor_spread)
    weak = spread < warn_axis_spread_deg
    if np.any(weak):
        small = weak & (rms_motion < warn_axis_spread_deg)
        what = (f"small motions (RMS rotation down to {float(np.min(rms_motion[weak])):.3g} deg)"
                if np.all(small[weak]) else "nearly single-axis motion")
        warnings.warn(
            f"{int(np.sum(weak))} of {weak.size} problems have {what}: axis spread down to "
            f"{float(np.min(spread)):.3g} deg < {warn_axis_spread_deg:g} deg, so the rotation about the dominant axis "
            f"is poorly determined; add larger motions about other axes",
            ObservabilityWarning,
            stacklevel=stacklevel,
        )
    loo, pair = motions.leave_one_out_spread_deg
    single = ~weak & (loo < warn_axis_spread_deg)  # NaN (J < 3) never
    if np.any(single):
        i = _first_index(single)
        warnings.warn(
            f"{int(np.sum(single))} of {single.size} problems rest on one pair for the rotation about their dominant "
            f"axis: without pair {int(pair[i])} (the largest turn about other axes) the axis spread falls from "
            f"{float(spread[i]):.3g} deg to {float(loo[i]):.3g} deg < {warn_axis_spread_deg:g} deg, so that one "
            f"pair's error decides R0 unseen; add larger motions about other axes",
            ObservabilityWarning, stacklevel=stacklevel)
    flat = symmetric_gap < WEAK_GAP_FACTOR * np.maximum(inconsistency, 0.0)
    flat &= ~weak & ~single  # already reported
    if np.any(flat):
        i = np.unravel_index(int(np.argmin(np.where(flat, symmetric_gap / np.maximum(inconsistency, 1e-300),
                                                    np.inf))), flat.shape) if flat.ndim else ()
        warnings.warn(
            f"{int(np.sum(flat))} of {flat.size} problems determine R0 poorly: another rotation fits eq. (8) almost "
            f"as well (gap between the two largest eigenvalues of sym(K) {float(symmetric_gap[i]):.3g} < "
            f"{WEAK_GAP_FACTOR:g} x the data's inconsistency 1 - lambda_1 = {float(inconsistency[i]):.3g}): "
            f"motions small for the noise, outlier pairs (use robust), or motions that nearly admit a second "
            f"solution",
            ObservabilityWarning,
            stacklevel=stacklevel,
        )


def check_local_answer(motions: Motions, R: np.ndarray, method: str, stacklevel: int = 3) -> np.ndarray:
    """Warn where a local solver's ``R`` is not the certified global minimiser of eq. (8):
    :class:`LocalMinimumWarning` (cost (8) above the certified minimum ``f*`` by more than
    ``LOCAL_RTOL * f* + LOCAL_ATOL * J`` and farther than ``WRONG_POINT_DEG`` from the minimiser:
    another stationary point, or stopped far away, the gradient of (8) tells which); else
    :class:`ConvergenceWarning` farther than ``LOCAL_ANGLE_TOL_DEG`` from it (stopped short).

    Answers that are not rotations (NaN, a solver's declared failure; a reflection), which
    :func:`solve` warns about itself, are skipped. Returns the boolean mask of problems flagged
    either way.
    """
    cert_R = global_certificate(motions).R
    finite = np.isfinite(R).all(axis=(-2, -1))
    rotation = finite & (det3(np.where(finite[..., None, None], R, np.eye(3))) > 0)
    R = np.where(rotation[..., None, None], R, cert_R)  # stands in as the minimiser: never flagged here
    _, lower, gap = _gap_to_global(motions, R)
    angle = angle_between_deg(R, cert_R)
    above = gap > LOCAL_RTOL * np.abs(lower) + LOCAL_ATOL * motions.J
    off = above & (angle > WRONG_POINT_DEG)  # another stationary point
    short = ~off & (angle > LOCAL_ANGLE_TOL_DEG)  # in the right basin, not at its bottom
    if np.any(off):
        grad = _derivatives(motions.sym, np.asarray(R, dtype=float))[1]
        moving = 2.0 * np.linalg.norm(grad, axis=-1) > STATIONARY_TOL  # |grad (8)| / J: not a stationary point
        parts = []
        if np.any(off & moving):
            parts.append(f"{int(np.sum(off & moving))} where eq. (8) still has a gradient (up to "
                         f"{float(np.max((2.0 * np.linalg.norm(grad, axis=-1))[off & moving])):.3g} J): "
                         f"the solver stopped before converging (e.g. its iteration limit)")
        if np.any(off & ~moving):
            parts.append(f"{int(np.sum(off & ~moving))} at another stationary point of (8)")
        warnings.warn(
            f"{method} did not reach the global minimum of eq. (8) in {int(np.sum(off))} of {off.size} problems: "
            f"its cost exceeds the certified minimum f* by up to {float(np.max(gap[off])):.3g} (tolerance "
            f"{LOCAL_RTOL:g} f* + {LOCAL_ATOL:g} J) and its answer is {float(np.min(angle[off])):.3g}-"
            f"{float(np.max(angle[off])):.3g} deg from the certified minimiser; " + "; ".join(parts)
            + ". A local method from a start far from R0 does this; use chordal_optimal, or a start near R0",
            LocalMinimumWarning,
            stacklevel=stacklevel,
        )
    if np.any(short):
        warnings.warn(
            f"{method} stopped short of the minimum of eq. (8) in {int(np.sum(short))} of {short.size} problems: "
            f"up to {float(np.max(angle[short])):.3g} deg from the certified minimiser (tolerance "
            f"{LOCAL_ANGLE_TOL_DEG:g} deg); tighten its tolerance or use chordal_optimal",
            ConvergenceWarning,
            stacklevel=stacklevel,
        )
    return off | short


def check_answer(motions: Motions, R: np.ndarray, method: str, stacklevel: int = 3) -> np.ndarray:
    """Warn (:class:`AccuracyWarning`) where a non-local solver's answer is grossly off or not a
    rotation.

    A cheap screen first: the relaxation ``g <= 3 lambda_1(sym K)`` bounds the minimum of (8) from
    below, ``f* >= 6 J (1 - lambda_1)``; only answers whose cost exceeds ``GROSS_FACTOR`` times that
    bound (plus ``LOCAL_ATOL * J``) are compared with the certified minimum. NaN answers (a solver's
    declared failures) are skipped. Returns the boolean mask of flagged problems.
    """
    R = np.asarray(R, dtype=float)
    finite = np.isfinite(R).all(axis=(-2, -1))
    det = det3(np.where(finite[..., None, None], R, np.eye(3)))
    reflection = finite & (det < 0)
    singular = finite & ~(np.abs(det) > 0)  # no rotation either; the gross screen needs det > 0
    if np.any(singular):
        warnings.warn(f"{method} returned a singular matrix (det 0), not a rotation, in {int(np.sum(singular))} of "
                      f"{singular.size} problems", AccuracyWarning, stacklevel=stacklevel)
    _warn_not_rotations(method, np.zeros_like(finite), reflection, stacklevel + 1)
    return reflection | singular | _screen_gross(motions, R, finite & (det > 0), method, stacklevel + 1)


def _warn_not_rotations(method: str, failed: np.ndarray, reflection: np.ndarray, stacklevel: int) -> None:
    """:class:`AccuracyWarning` for declared failures (NaN blocks) and for reflections among a
    solver's answers."""
    if np.any(failed):
        warnings.warn(
            f"{method} declared a failure (returned NaN) in {int(np.sum(failed))} of {failed.size} problems, first at "
            f"batch index {_first_index(failed)}: no estimate there (with full_output: cost and duality_gap NaN, "
            f"global_optimum False)",
            AccuracyWarning, stacklevel=stacklevel)
    if np.any(reflection):
        warnings.warn(
            f"{method} returned a reflection (det -1), not a rotation, in {int(np.sum(reflection))} of "
            f"{reflection.size} problems" + (": the paper-literal variant fails so from a start more than 120 deg "
                                             "from R0" if method.startswith("two_step") else ""),
            AccuracyWarning, stacklevel=stacklevel)


def _screen_gross(motions: Motions, R: np.ndarray, usable: np.ndarray, method: str, stacklevel: int) -> np.ndarray:
    """The gross-error screen of :func:`check_answer` over the ``usable`` answers (rotations);
    returns its mask."""
    batch, J = R.shape[:-2], motions.J
    flat, usable = R.reshape(-1, 3, 3), usable.reshape(-1)
    safe = np.where(usable[:, None, None], flat, np.eye(3))
    flagged = np.zeros(len(flat), dtype=bool)
    x = vec(safe)
    g = np.einsum("na,nab,nb->n", x, motions.sym.reshape(-1, 9, 9), x)
    cost = 2.0 * J * (3.0 - g)
    lower = 6.0 * J * np.maximum(1.0 - motions.sym_eigvals[..., 0].reshape(-1), 0.0)  # relaxation bound on f*
    screen = usable & (cost > GROSS_FACTOR * lower + LOCAL_ATOL * J)
    if np.any(screen):
        A = motions.A.reshape((-1,) + motions.A.shape[-3:])[screen]
        B = motions.B.reshape((-1,) + motions.B.shape[-3:])[screen]
        cert = global_certificate(Motions._trusted(A, B))
        gross = cost[screen] > GROSS_FACTOR * cert.cost + LOCAL_ATOL * J
        if np.any(gross):
            angle = angle_between_deg(safe[screen][gross], cert.R[gross])
            ratio = cost[screen][gross] / np.maximum(cert.cost[gross], 1e-300)
            warnings.warn(
                f"{method} is far from the certified minimiser of eq. (8) in {int(np.sum(gross))} of {len(flat)} "
                f"problems: up to {float(np.max(angle)):.3g} deg from it, cost (8) up to {float(np.max(ratio)):.3g} x "
                f"the minimum (tolerance {GROSS_FACTOR:g} x + {LOCAL_ATOL:g} J); e.g. a motion of nearly 180 deg whose "
                f"axis or quaternion sign differs between the two sides, or an ill-conditioned limit; use "
                f"chordal_optimal",
                AccuracyWarning, stacklevel=stacklevel)
            flagged[np.flatnonzero(screen)[gross]] = True
    return flagged.reshape(batch)


class SolverAnswerError(ValueError):
    """A solver's core broke the contract of :class:`SolverInfo` (not one rotation, or one whole 3x3
    block of NaN, per problem); the message names the solver, where, the first offending index and
    the measured violation."""


def checked_core(method: str, motions: Motions, *, where: str = "", **options):
    """The core of ``method`` on validated ``motions``, its answer checked as :func:`solve` checks
    it: the one door for every re-solve inside a calibration (bootstrap replicates, ...), which skip
    :func:`solve`'s validation and its warnings but never its contract check.

    Returns ``(R, failed, reflection)``: the answers and the masks of declared failures (whole NaN
    blocks) and of reflections (det -1), which the caller must not use as rotations. Raises
    :class:`SolverAnswerError` (a ``ValueError`` naming the solver and ``where``, e.g. ``"on
    bootstrap replicates"``) where the answer is not a rotation or a NaN block.
    """
    return _checked_answer(method, motions, solver_info(method).core(motions, **options), where=where)


def _checked_answer(method: str, motions: Motions, R, where: str = ""):
    """A core's answer as a float array, with its masks ``(failed, reflection)``;
    :class:`SolverAnswerError` if it breaks the contract of :class:`SolverInfo` (one rotation, or
    one whole 3x3 block of NaN, per problem). One pass: ``||R^T R - I||_F`` and ``| |det R| - 1 |``
    against :data:`ANSWER_ATOL` (a reflection passes both and is only warned about); any NaN or inf
    in a block that is not all NaN fails them."""
    expected = motions.batch_shape + (3, 3)
    if not isinstance(R, np.ndarray) or R.shape != expected:
        got = (f"an array of shape {R.shape}" if isinstance(R, np.ndarray) else
               "None" if R is None else f"a {type(R).__name__}")
        raise SolverAnswerError(f"solver {method!r} returned {got}{where}; expected a numpy array of shape "
                                f"{expected} (one 3x3 rotation per problem of batch shape {motions.batch_shape})")
    if R.dtype.kind not in "fiu":
        raise SolverAnswerError(f"solver {method!r} returned an array of dtype {R.dtype}{where}; expected real "
                                f"numbers, shape {expected}")
    R = np.asarray(R, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
        ortho = np.sqrt(np.einsum("...ij,...ij->...", E, E))
        det = det3(R)
        violation = np.maximum(ortho, np.abs(np.abs(det) - 1.0))  # NaN wherever the block holds NaN or inf
    failed = np.isnan(R).all(axis=(-2, -1))
    bad = ~(violation <= ANSWER_ATOL) & ~failed
    if np.any(bad):
        i = _first_index(bad)
        what = ("NaN or inf in part of the block (a declared failure is a whole block of NaN)"
                if not np.isfinite(R[i]).all() else
                f"||R^T R - I||_F = {ortho[i]:.3g}, det R = {det[i]:.6g}: | |det R| - 1 | = {abs(abs(det[i]) - 1):.3g}")
        raise SolverAnswerError(f"solver {method!r} returned a matrix that is not a rotation{where} at batch index "
                                f"{i}: {what} "
                         f"(tolerance ANSWER_ATOL = {ANSWER_ATOL:g}; {int(np.sum(bad))} bad of {bad.size})")
    return R, failed, ~failed & (det < 0)


def solve(method: str, A, B=None, *, full_output: bool = False, warn_axis_spread_deg: float = 1.0,
          _stacklevel: int = 3, **options):
    """Estimate ``R0`` (camera_from_sensor) from pairs ``A_j R0 = R0 B_j`` (eq. (7)).

    Parameters
    ----------
    method : str
        A name from :func:`available`.
    A : array_like, shape (..., J, 3, 3), or Motions
        Camera relative rotations ``Delta R_c``; or a :class:`replication.core.motions.Motions`
        prepared once for several solvers (then ``B=None``).
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    full_output : bool
        ``False``: return the rotations. ``True``: return a :class:`Solution`
        with the cost (8), the observability diagnostic and the certified global
        minimum of eq. (8) (``global_optimum``, ``duality_gap``).
    warn_axis_spread_deg : float
        Issue an :class:`ObservabilityWarning` when the camera or sensor axis
        spread (:class:`replication.core.motions.MotionObservability`) of a problem is
        below this: nearly single-axis (or small) motion leaves the rotation about that
        axis poorly determined. Exactly single-axis motion raises instead.
    **options
        Passed to the solver.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3), or Solution
        Rotation matrices (det +1), unless a warning says otherwise.

    Warns
    -----
    ObservabilityWarning
        The motions weakly determine ``R0`` (see :func:`warn_if_weak`).
    LocalMinimumWarning, ConvergenceWarning
        A ``local`` solver (e.g. ``sqp``) ended above, or short of, the certified global minimum of
        eq. (8).
    AccuracyWarning
        Any solver returned a reflection (det -1) or declared a failure (a 3x3 block of NaN); any
        other solver (except ``chordal_optimal``, which certifies itself) returned an answer far
        from the certified minimiser (see :func:`check_answer`).
    IterationCapWarning, CertificateWarning
        From the solvers themselves (see each).

    Raises
    ------
    ValueError
        Unknown method (the message lists the available ones), malformed input (see
        :func:`replication.core.handeye.check_motion_pairs`), fewer motions than the solver needs,
        or degenerate motion (``R0`` not unique); or the solver's core broke its contract
        (:class:`SolverInfo`): not an array of shape ``batch shape + (3, 3)``, not real, a block
        partly NaN or inf, or a block farther than :data:`ANSWER_ATOL` from orthogonal (the message
        names the solver, the first offending batch index and the measured violation).
    """
    info = solver_info(method)
    motions = prepare_motions(A, B, min_motions=info.min_motions, _sym_vectors=info.relaxed_start)
    warn_if_weak(motions, warn_axis_spread_deg, stacklevel=_stacklevel)
    R, failed, reflection = _checked_answer(method, motions, info.core(motions, **options))
    _warn_not_rotations(method, failed, reflection, _stacklevel)
    if info.local:
        check_local_answer(motions, R, method, stacklevel=_stacklevel)
    elif method != "chordal_optimal":
        _screen_gross(motions, R, ~failed & ~reflection, method, _stacklevel)
    if not full_output:
        return R

    return certified_solution(method, motions, R)
