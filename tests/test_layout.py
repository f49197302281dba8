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
#: The packages (only they have submodules a name could shadow), the top one included.
PACKAGES = ["replication"] + sorted(m.name for m in pkgutil.walk_packages(replication.__path__, "replication.")
                                    if m.ispkg)


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


def test_the_shadowing_check_sees_every_package():
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    assert sorted(PACKAGES) == sorted(declared)


@pytest.mark.parametrize("module", PACKAGES)
def test_no_name_shadows_a_submodule(module):
    mod = importlib.import_module(module)
    subs = list(pkgutil.iter_modules(mod.__path__))
    assert subs, f"{module} has no submodules"
    for sub in subs:
        value = getattr(mod, sub.name, None)
        assert value is None or isinstance(value, types.ModuleType), f"{module}.{sub.name} is a {type(value).__name__}"


#: The layers of README's "Layout", top first; a module imports (at module level) only from its own layer or above.
LAYERS = {
    "foundation": ["_io", "checks", "datafile"],
    "maths": ["so3", "handeye", "motions", "stats"],
    "data": ["streams", "realdata", "paper", "fetch"],
    "solvers": ["solvers"],
    "pipeline": ["simulation", "association", "quality", "report", "diagnose", "calibration", "estimate", "poses",
                 "changepoint", "table2", "online_events", "online", "live", "vins_rule", "lab",
                 "lab.settings", "lab.recording", "lab.simulate", "lab.chain"],
    "studies": ["table1", "fig5", "baselines", "real_study", "live_study", "lab.study", "ledger", "figures",
                "notebook"],
    "entry points and tools": ["__init__", "__main__", "calibrate_cli", "lab_io", "testing"],
}
RANK = {name: rank for rank, names in enumerate(LAYERS.values()) for name in names}


def _layer_of(module: str) -> int:
    """Rank of ``replication.<module>``: its longest listed prefix."""
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in RANK:
            return RANK[".".join(parts[:k])]
    raise KeyError(f"replication.{module} is in no layer of README's Layout (add it to tests/test_layout.py:LAYERS)")


def _module_level_imports(path: Path, module: str):
    """Intra-package modules imported at module level (``if TYPE_CHECKING:`` blocks left out)."""
    import ast

    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
                names = [target] if node.module else [f"{target}.{a.name}" for a in node.names]
            elif (node.module or "").startswith("replication"):
                names = [node.module]
            else:
                continue
            for name in names:
                yield name.removeprefix("replication.").removeprefix("replication")


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_go_only_to_the_same_layer_or_above(path):
    rel = path.relative_to(PACKAGE).with_suffix("")
    module = ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts) or "__init__"
    own = _layer_of(module)
    for target in _module_level_imports(path, "replication." + module if module != "__init__" else "replication"):
        if not target:
            continue
        assert _layer_of(target) <= own, (f"replication.{module} ({list(LAYERS)[own]}) imports replication.{target} "
                                           f"({list(LAYERS)[_layer_of(target)]}), a lower layer")
