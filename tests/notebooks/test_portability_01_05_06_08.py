"""Stored notebook outputs hold on another machine: strict nbval with jittered inputs, numpy's AVX2
paths, other BLAS kernels, one thread and Agg.

Re-executes every notebook (one test per notebook, so that a failure names it) in a subprocess under
the variant ``avx2`` of :data:`replication._jitter.VARIANTS`: every generated and loaded input moved
at its last bits (``REPLICATION_JITTER``), numpy's SIMD dispatch limited to AVX2
(``NPY_DISABLE_CPU_FEATURES``: an AVX-512 machine computes as one without it; on a machine without
AVX-512 it changes nothing), OpenBLAS forced to its Haswell kernels with one thread, and
``MPLBACKEND=Agg``; every stored output is compared as the normal nbval run does. A stored digit
that rounding can flip fails here. The longer matrix (the SSE4.2 baseline, Nehalem and SkylakeX
kernels, a 1e-11 jitter with doubled guards) is ``scripts/spread.py``, run before committing
notebook outputs. The notebooks are split between this file and ``test_portability_02_03_04_07.py``
so that two xdist workers (``--dist loadfile``) share the re-runs. Deselect with ``-m "not
portability"``.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from replication._jitter import VARIANTS

ROOT = Path(__file__).resolve().parents[2]
OTHER_MACHINE = {**VARIANTS["avx2"], "MPLBACKEND": "Agg"}
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
#: The notebooks this file re-runs, read from its name (about half the time: 08, 05, 06, 01 took
#: 160, 128, 61, 10 s); the rest are test_portability_02_03_04_07.py's (tests/test_layout.py checks
#: that the two names share out every notebook).
PART1 = tuple(Path(__file__).stem.removeprefix("test_portability_").split("_"))


def notebooks(part1: bool):
    return [p for p in NOTEBOOKS if (p.name[:2] in PART1) == part1]


def check_on_another_machine(notebook, tmp_path):
    env = {**os.environ, **OTHER_MACHINE, "REPLICATION_RESULTS_DIR": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
         str(notebook.relative_to(ROOT))],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800,
    )
    tail = "\n".join(out.stdout.splitlines()[-40:])
    assert out.returncode == 0, f"nbval under {OTHER_MACHINE} failed:\n{tail}\n{out.stderr[-2000:]}"


def test_every_numbered_notebook_is_rerun_once():
    assert [p.name[:2] for p in NOTEBOOKS] == [f"{k:02d}" for k in range(1, len(NOTEBOOKS) + 1)]
    assert len(NOTEBOOKS) >= 8 and set(PART1) < {p.name[:2] for p in NOTEBOOKS}
    assert sorted(notebooks(True) + notebooks(False)) == NOTEBOOKS


@pytest.mark.portability
@pytest.mark.parametrize("notebook", notebooks(True), ids=lambda p: p.stem)
def test_the_notebook_passes_strict_nbval_on_another_machine(notebook, tmp_path):
    check_on_another_machine(notebook, tmp_path)
