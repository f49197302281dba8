"""OpenCV's ``cv2.calibrateHandEye`` as rotation-only solvers of ``A X = X B``. Theory and measured
numbers: ``docs/methods.md``, section ``replication.core.solvers.opencv``."""
from __future__ import annotations

import numpy as np

from ..motions import prepare_motions
from ._registry import register

__all__ = ["calibrate_hand_eye", "all_pairs", "OPENCV_METHODS", "UNUSABLE_FOR_ROTATION_ONLY", "MAX_PAIRS"]

#: Registered OpenCV methods: registry name -> (``cv2`` constant, the paper it implements).
OPENCV_METHODS = {
    "opencv_tsai": ("CALIB_HAND_EYE_TSAI", "Tsai & Lenz 1989"),
    "opencv_park": ("CALIB_HAND_EYE_PARK", "Park & Martin 1994"),
    "opencv_horaud": ("CALIB_HAND_EYE_HORAUD", "Horaud & Dornaika 1995"),
}
#: OpenCV methods that need translations and fail on rotation-only data.
UNUSABLE_FOR_ROTATION_ONLY = ("CALIB_HAND_EYE_ANDREFF", "CALIB_HAND_EYE_DANIILIDIS")
#: Most motion pairs ``J`` per problem the wrappers pass to OpenCV (a chain of ``J + 1`` poses, of
#: which OpenCV forms all ``J (J + 1) / 2`` pairs). One ``cv2.calibrateHandEye`` call takes about
#: ``3.2e-6 N^2`` s for ``N`` poses (``CALIB_HAND_EYE_PARK``, the slowest;
#: ``benchmarks/bench_bounded.py``): at this limit 0.5 s, and ``calibrate``'s 200 bootstrap
#: replicates about 100 s. Notebook 07 passes at most 181 non-overlapping pairs per recording and
#: notebook 06 at most 50; a whole recording's overlapping pairs (2700 for TUM-VI room1) would take
#: ~24 s per call, over an hour with the bootstrap.
MAX_PAIRS = 400
#: Seconds per squared pose of one ``cv2.calibrateHandEye`` call, measured per method (2 cores,
#: OpenCV 4.14); only for the estimate in the refusal message.
_SECONDS_PER_POSE2 = {"CALIB_HAND_EYE_TSAI": 1.8e-6, "CALIB_HAND_EYE_PARK": 3.2e-6, "CALIB_HAND_EYE_HORAUD": 2.5e-6}


def _cv2():
    try:
        import cv2
    except ImportError as err:  # pragma: no cover - opencv is a dependency
        raise ImportError(
            "the opencv_* solvers need opencv-python-headless<5 (OpenCV 5 wheels lack calibrateHandEye)"
        ) from err
    if not hasattr(cv2, "calibrateHandEye"):  # pragma: no cover
        raise ImportError(f"OpenCV {cv2.__version__} has no calibrateHandEye; install opencv-python-headless<5")
    return cv2


def _chain(A, B):
    """Absolute poses whose consecutive relative motions are ``(A_k, B_k)`` (see the module
    notes)."""
    J = A.shape[0]
    Hg = np.empty((J + 1, 3, 3))
    Hc = np.empty((J + 1, 3, 3))
    Hg[0] = Hc[0] = np.eye(3)
    for k in range(J):
        Hg[k + 1] = Hg[k] @ A[k].T  # Hg_{k+1}^{-1} Hg_k = A_k
        Hc[k + 1] = B[k] @ Hc[k]  # Hc_{k+1} Hc_k^{-1} = B_k
    return Hg, Hc


def _check_size(J: int, method: str, max_pairs: int) -> None:
    """Refuse a chain of more than ``max_pairs`` motions: OpenCV's time grows as the square of its
    poses."""
    if int(max_pairs) != max_pairs or max_pairs < 1:
        raise ValueError(f"max_pairs must be a positive integer, got {max_pairs!r}")
    if J <= max_pairs:
        return
    N = J + 1
    seconds = _SECONDS_PER_POSE2.get(method, max(_SECONDS_PER_POSE2.values())) * N ** 2
    raise ValueError(
        f"cv2.calibrateHandEye({method}) on J = {J} motion pairs refused (max_pairs = {int(max_pairs)}): the "
        f"wrapper chains them into N = {N} poses and OpenCV forms all N (N - 1) / 2 = {N * (N - 1) // 2} pose "
        f"pairs, so one call takes time growing as N^2 (measured about {seconds:.3g} s per problem here, 0.5 s at "
        f"401 poses), and calibrate repeats it for every bootstrap replicate. Use non-overlapping pairs "
        f"(calibrate(..., stride=k) with k about interval / camera period), fewer poses, or a solver linear in "
        f"J such as chordal_optimal or park_martin; or pass max_pairs={J} to accept the cost"
    )


def calibrate_hand_eye(A, B=None, method: str = "CALIB_HAND_EYE_TSAI", *, on_failure: str = "raise",
                       max_pairs: int = MAX_PAIRS) -> np.ndarray:
    """``R0`` from ``cv2.calibrateHandEye`` on the pose chain of ``(A, B)``, one call per problem.

    OpenCV's own log messages are silenced during the call; its output is checked instead.
    ``CALIB_HAND_EYE_TSAI`` (OpenCV 4.14) sometimes gives up ("Not enough informative motions", seen
    with J = 3 and with small motions) and returns its initial value, the identity; an exact
    identity is treated as a failure unless it is the certified minimum of eq. (8) (within the
    tolerance of :func:`replication.core.solvers._registry.check_local_answer`).
    ``CALIB_HAND_EYE_PARK`` computes ``(M^T M)^{-1/2} M^T`` without a determinant check and returns
    a *reflection* (det -1) when few noisy motions make ``det M < 0`` (seen with J = 3 at the
    paper's noise level).

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera / sensor relative rotations (validated here; or a
        :class:`~replication.core.motions.Motions` as ``A``).
    method : str
        Name of a ``cv2.CALIB_HAND_EYE_*`` constant.
    on_failure : {"raise", "nan"}
        What to do when OpenCV's result is not a rotation (NaN or det -1):
        raise ``ValueError`` naming the problem, or return NaN for that problem
        (for studies that count failures).
    max_pairs : int
        Most motion pairs ``J`` per problem (default :data:`MAX_PAIRS`, 400): OpenCV forms all
        ``J (J + 1) / 2`` pairs of the pose chain, so its time grows as ``J^2``.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor`` (OpenCV's ``R_cam2gripper``).

    Raises
    ------
    ValueError
        ``J > max_pairs`` (the message names the measured cost and the alternatives: non-overlapping
        pairs, ``stride`` in :func:`replication.calibrate`, fewer poses, or ``chordal_optimal`` /
        ``park_martin``); OpenCV's result is not a rotation and ``on_failure="raise"``.
    """
    from ._registry import check_answer, warn_if_weak

    m = prepare_motions(A, B)
    warn_if_weak(m)
    R = _calibrate_hand_eye(m, method, on_failure=on_failure, max_pairs=max_pairs)
    check_answer(m, R, f"cv2.calibrateHandEye({method})")
    return R


def _calibrate_hand_eye(motions, method: str, *, on_failure: str = "raise",
                        max_pairs: int = MAX_PAIRS) -> np.ndarray:
    """:func:`calibrate_hand_eye` on validated motions."""
    if on_failure not in ("raise", "nan"):
        raise ValueError(f"on_failure must be 'raise' or 'nan', got {on_failure!r}")
    cv2 = _cv2()
    if not (isinstance(method, str) and method.startswith("CALIB_HAND_EYE_") and hasattr(cv2, method)):
        raise ValueError(f"method must name a cv2.CALIB_HAND_EYE_* constant, got {method!r}")
    flag = getattr(cv2, method)
    A, B = motions.A, motions.B
    lead, J = A.shape[:-3], A.shape[-3]
    _check_size(J, method, max_pairs)  # before any O(J^2) work
    flatA, flatB = A.reshape((-1, J, 3, 3)), B.reshape((-1, J, 3, 3))
    zeros = [np.zeros((3, 1))] * (J + 1)
    out = np.empty((len(flatA), 3, 3))
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        for n in range(len(flatA)):  # OpenCV has no batched interface
            Hg, Hc = _chain(flatA[n], flatB[n])
            out[n], _ = cv2.calibrateHandEye(list(Hg), zeros, list(Hc), zeros, method=flag)
    finally:
        cv2.utils.logging.setLogLevel(level)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(out).all(axis=(-2, -1)) | ~(np.linalg.det(np.nan_to_num(out)) > 0.5)
    # OpenCV's Tsai gives up with only a log line ("Not enough informative motions") and returns its
    # initial value, the exact identity; accept an identity only if it is the certified minimum of
    # eq. (8)
    identity = np.all(out == np.eye(3), axis=(-2, -1))
    if identity.any():
        from ..motions import Motions
        from ._registry import LOCAL_ATOL, LOCAL_RTOL
        from .certificate import _gap_to_global

        sub = Motions._trusted(flatA[identity], flatB[identity])
        _, lower, gap = _gap_to_global(sub, np.broadcast_to(np.eye(3), sub.batch_shape + (3, 3)))
        bad[identity] |= gap > LOCAL_RTOL * np.abs(lower) + LOCAL_ATOL * J
    if bad.any():
        if on_failure == "raise":
            first = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), lead)) if lead else ()
            raise ValueError(
                f"cv2.calibrateHandEye({method}) failed on {int(bad.sum())} of {bad.size} problems, first at "
                f"batch index {first}: it returned NaN, a reflection (det -1), or gave up and returned "
                f"its initial identity"
            )
        out[bad] = np.nan
    return out.reshape(lead + (3, 3))


def all_pairs(A, B):
    """The ``J (J + 1) / 2`` relative pairs OpenCV forms from the pose chain of ``(A, B)``.

    Pair ``(i, j)``, ``i < j``, is ``(Hg_j^{-1} Hg_i, Hc_j Hc_i^{-1})``, i.e.
    ``(A_{j-1} ... A_i, B_{j-1} ... B_i)``. Any solver run on these pairs sees
    the same data as ``cv2.calibrateHandEye`` (used to check the wrappers). The output itself is
    ``O(J^2)`` (no limit here: it is built on request, for small ``J``).

    Parameters
    ----------
    A, B : ndarray, shape (J, 3, 3)

    Returns
    -------
    (A_all, B_all) : ndarray, shape (J (J + 1) / 2, 3, 3)
    """
    Hg, Hc = _chain(np.asarray(A, dtype=float), np.asarray(B, dtype=float))
    i, j = np.triu_indices(len(Hg), k=1)
    return np.swapaxes(Hg[j], -1, -2) @ Hg[i], Hc[j] @ np.swapaxes(Hc[i], -1, -2)


def _register(name: str, constant: str, paper: str):
    @register(name, reference=f"OpenCV cv2.calibrateHandEye({constant}): {paper}",
              equivariant=constant != "CALIB_HAND_EYE_TSAI")
    def solver(motions, *, on_failure="raise", max_pairs=MAX_PAIRS):
        return _calibrate_hand_eye(motions, constant, on_failure=on_failure, max_pairs=max_pairs)

    solver.__doc__ = (f"``cv2.calibrateHandEye`` with ``{constant}`` ({paper}); see :func:`calibrate_hand_eye` "
                      f"(at most ``max_pairs`` = :data:`MAX_PAIRS` motion pairs per problem).")
    return solver


for _name, (_constant, _paper) in OPENCV_METHODS.items():
    _register(_name, _constant, _paper)
