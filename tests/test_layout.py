"""The house rules of the package layout (README, "Layout"): every subpackage is installed, no module is over 500
lines, the maths and data layers load neither the solvers nor SciPy's optimiser, and no name shadows a submodule."""
import importlib
import pkgutil
import subprocess
import sys
import tomllib
import types
from pathlib import Path

import pytest

import replication

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "replication"
MODULES = sorted(m.name for m in pkgutil.walk_packages(replication.__path__, "replication.") if m.name != "replication.__main__")


def test_every_subpackage_is_installed():
    declared = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in PACKAGE.rglob("__init__.py")}
    assert declared == found


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_god_module(path):
    assert len(path.read_text(encoding="utf-8").splitlines()) <= 500


@pytest.mark.parametrize("module", ["replication.so3", "replication.checks", "replication.handeye",
                                    "replication.motions", "replication.streams", "replication.datafile",
                                    "replication.paper", "replication.realdata", "replication.lab.recording",
                                    "replication.lab_io", "replication.table2", "replication.ledger"])
def test_maths_and_data_layers_load_no_solver(module):
    probe = (f"import sys; import {module}; "
             "print(sorted(m for m in ('scipy.optimize', 'replication.solvers', 'replication.calibration', 'cv2') "
             "if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "[]", f"import {module} loads {loaded}"


@pytest.mark.parametrize("module", MODULES)
def test_no_name_shadows_a_submodule(module):
    mod = importlib.import_module(module)
    if not hasattr(mod, "__path__"):
        return
    for sub in pkgutil.iter_modules(mod.__path__):
        value = getattr(mod, sub.name, None)
        assert value is None or isinstance(value, types.ModuleType), f"{module}.{sub.name} is a {type(value).__name__}"
