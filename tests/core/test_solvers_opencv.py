"""The OpenCV wrappers (:mod:`replication.core.solvers.opencv`): their size limit, refused before
OpenCV is called.

Figures behind the limit: ``benchmarks/bench_bounded.py``.
"""
import time

import numpy as np
import pytest
from test_solvers_msac import _outlier_problem

from replication.core.solvers import calibrate_hand_eye, opencv, solve


@pytest.mark.parametrize("method", ["opencv_park", "opencv_tsai", "opencv_horaud"])
def test_opencv_wrappers_refuse_long_chains_before_calling_opencv(method, monkeypatch):
    import cv2

    def fail(*args, **kwargs):
        raise AssertionError("cv2.calibrateHandEye called")

    _, A, B = _outlier_problem(opencv.MAX_PAIRS + 1, share=0.0, seed=6)
    monkeypatch.setattr(cv2, "calibrateHandEye", fail)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"N\^2") as err:
        solve(method, A, B)
    assert time.perf_counter() - start < 1.0
    for alternative in ("stride", "non-overlapping", "fewer poses", "chordal_optimal", "park_martin", "max_pairs"):
        assert alternative in str(err.value)
    assert f"J = {opencv.MAX_PAIRS + 1}" in str(err.value)


def test_opencv_limit_is_a_documented_option():
    _, A, B = _outlier_problem(30, share=0.0, noise_deg=0.1, seed=7)
    with pytest.raises(ValueError, match="max_pairs = 10"):
        calibrate_hand_eye(A, B, "CALIB_HAND_EYE_PARK", max_pairs=10)
    with pytest.raises(ValueError, match="max_pairs must be a positive integer"):
        solve("opencv_park", A, B, max_pairs=0)
    np.testing.assert_array_equal(solve("opencv_park", A, B, max_pairs=30), solve("opencv_park", A, B))
    assert opencv.MAX_PAIRS >= 200  # notebook 07 passes up to 181 non-overlapping pairs, notebook 06 up to 50


