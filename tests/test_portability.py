"""Stored notebook outputs hold on another machine: strict nbval under other BLAS kernels, one thread, Agg.

Re-executes every notebook in a subprocess with OpenBLAS forced to another CPU's kernels
(``OPENBLAS_CORETYPE=Sandybridge``: no FMA, other summation order), one thread, and ``MPLBACKEND=Agg``
(a common CI setting), and compares every stored output as the normal nbval run does. A stored digit that
depends on last-bit rounding (a diverging or chaotic computation printed as digits) fails here.
Deselect with ``-m "not portability"`` (about 90 s).
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
OTHER_MACHINE = {"OPENBLAS_CORETYPE": "Sandybridge", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                 "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}


@pytest.mark.portability
def test_every_notebook_passes_strict_nbval_on_other_blas_kernels_one_thread_and_agg(tmp_path):
    env = {**os.environ, **OTHER_MACHINE, "REPLICATION_RESULTS_DIR": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "notebooks"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800,
    )
    tail = "\n".join(out.stdout.splitlines()[-40:])
    assert out.returncode == 0, f"nbval under {OTHER_MACHINE} failed:\n{tail}\n{out.stderr[-2000:]}"
