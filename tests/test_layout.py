"""The house rules of the package layout (README, "Layout").

Three rooms, the command line's room and a hall: ``replication/core`` (the maths and the solvers),
``replication/rig`` (calibrating a real rig), ``replication/study`` (the paper's replication),
``replication/cli`` (the commands, on the top floor), and the package face, ``__main__``, the atomic
writer and the testing helpers. Arrows run cli -> study -> rig -> core only, at module level and
inside functions; only ``__main__`` imports cli, and only cli imports argparse; no import cycle
anywhere; every name has one home; notebooks call public names in short cells.
"""
import ast
import functools
import importlib
import json
import pkgutil
import subprocess
import sys
import types
from pathlib import Path

import pytest
import tomllib

import replication

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "replication"
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
#: The packages (only they have submodules a name could shadow), the top one included.
PACKAGES = ["replication"] + sorted(m.name for m in pkgutil.walk_packages(replication.__path__, "replication.")
                                    if m.ispkg)
#: Rank of each room: a module imports only from its own room or a lower one. The three leaves of
#: the hall (the atomic writer, the version and the optional packages) import nothing of the package
#: and serve every room; the testing helpers (the synthetic rig) stand with rig, whose streams they
#: build, so that the online studies use the same rig as the tests; the rest of the hall and the
#: command line are on top, and ``__main__`` (the entry that runs the command line) above them.
ROOMS = {"_io": 0, "_version": 0, "_extras": 0, "_jitter": 0, "core": 1, "rig": 2, "testing": 2, "study": 3,
         "__init__": 4, "cli": 4, "__main__": 5}
MAX_TOP_LEVEL_MODULES = 8
MAX_CELL_LINES = 60


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The syntax tree of a file of the package, parsed once per session (the rules only read it):
    the test-file rule would otherwise parse every module again for each of about 100 test files."""
    return ast.parse(path.read_text(encoding="utf-8"))


def _room(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _type_checking_lines(tree) -> set:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, child.end_lineno + 1))
    return lines


def imports_of(module: str):
    """``(line, target)`` for every import of a package module in ``module``, at any depth
    (functions included) and of every name that is itself a module (``from . import so3``); ``if
    TYPE_CHECKING:`` blocks left out."""
    path = MODULES[module]
    tree = _tree(path)
    skip = _type_checking_lines(tree)
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "replication":
                    yield node.lineno, _existing(alias.name)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = ".".join(package[: len(package) - node.level + 1] + ([node.module] if node.module else []))
            elif (node.module or "").split(".")[0] == "replication":
                base = node.module
            else:
                continue
            yield node.lineno, _existing(base)
            for alias in node.names:
                if f"{base}.{alias.name}" in MODULES:
                    yield node.lineno, f"{base}.{alias.name}"


def _existing(name: str) -> str:
    assert name in MODULES, f"{name} is not a module of the package"
    return name


def test_every_subpackage_is_installed():
    declared = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in PACKAGE.rglob("__init__.py")}
    assert declared == found


def test_the_top_level_is_three_rooms_and_a_small_hall():
    modules = sorted(p.name for p in PACKAGE.glob("*.py"))
    folders = sorted(p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists())
    assert folders == ["cli", "core", "rig", "study"]
    assert len(modules) <= MAX_TOP_LEVEL_MODULES, modules
    assert {m.removesuffix(".py") for m in modules} <= set(ROOMS), f"{modules}: a module in no room of ROOMS"


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_god_module(path):
    assert len(path.read_text(encoding="utf-8").splitlines()) <= 500


@pytest.mark.parametrize("module", ["replication.core.so3", "replication.core.checks", "replication.core.handeye",
                                    "replication.core.motions", "replication.rig.streams", "replication.rig.datafile",
                                    "replication.study.paper", "replication.rig.realdata",
                                    "replication.study.lab.recording", "replication.study.table2",
                                    "replication.study.ledger"])
def test_maths_and_data_modules_load_no_solver(module):
    probe = (f"import sys; import {module}; "
             "print(sorted(m for m in ('scipy.optimize', 'replication.core.solvers', 'replication.rig.calibration', "
             "'cv2') if m in sys.modules))")
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


@pytest.mark.parametrize("module", sorted(MODULES))
def test_arrows_run_study_rig_core_only(module):
    own = ROOMS[_room(module)]
    for line, target in imports_of(module):
        assert ROOMS[_room(target)] <= own, (f"{MODULES[module].relative_to(ROOT)}:{line} imports {target}: "
                                             f"{_room(module)} may import only from its own room or below")


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _room(m) != "cli"))
def test_only_the_entry_imports_the_command_line(module):
    """The command line imports the library, never the reverse: outside ``replication/cli`` only
    ``__main__`` may."""
    if module == "replication.__main__":
        assert any(_room(target) == "cli" for _, target in imports_of(module)), "__main__ does not run replication.cli"
        return
    into = [(line, target) for line, target in imports_of(module) if _room(target) == "cli"]
    assert not into, f"{MODULES[module].relative_to(ROOT)} imports the command line: {into}"


def argparse_lines(source: str) -> list:
    """The lines of ``source`` importing argparse (``import argparse``, ``from argparse import
    ...``), at any depth."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "argparse" for a in node.names):
            found.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "argparse" and not node.level:
            found.append(node.lineno)
    return found


def test_the_argparse_finder_sees_every_form():
    assert argparse_lines("import argparse\ndef f():\n    from argparse import Namespace\n") == [1, 3]
    assert argparse_lines("import argparsex\nimport json as argparse\n") == []


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _room(m) != "cli"))
def test_library_modules_are_free_of_argparse(module):
    lines = argparse_lines(MODULES[module].read_text(encoding="utf-8"))
    assert not lines, f"{MODULES[module].relative_to(ROOT)}:{lines} imports argparse: a command's parser lives in cli/"


def find_cycle(graph: dict):
    """One import cycle of ``graph`` (module -> set of modules) as a list that starts and ends at
    the same module, or None."""
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        state[node] = "done"
        stack.pop()
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_the_cycle_finder_finds_a_cycle_inside_a_function_and_none_in_a_chain():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": set()}) is None
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"a"}}) == ["a", "a"]


def test_no_import_cycle_even_inside_functions():
    graph = {m: {t for _, t in imports_of(m) if t != m} for m in MODULES}
    # a package's face imports its modules; a module importing its own package's face is the cycle
    # this finds
    assert find_cycle(graph) is None, " -> ".join(find_cycle(graph))


def _defined_names(tree) -> set:
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for target in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                names.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
    return names


@pytest.mark.parametrize("module", sorted(m for m, p in MODULES.items() if p.name != "__init__.py"))
def test_every_public_name_has_one_home(module):
    """A module (not a package's face) exports only what it defines, and has no module
    ``__getattr__``: no alias of a name that lives elsewhere."""
    tree = _tree(MODULES[module])
    defined = _defined_names(tree)
    assert "__getattr__" not in defined, f"{module} answers names it does not define (__getattr__)"
    exported = next((ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
                     and any(getattr(t, "id", None) == "__all__" for t in n.targets)), [])
    elsewhere = [name for name in exported if name not in defined]
    assert not elsewhere, f"{module}.__all__ lists names defined elsewhere: {elsewhere}"


def test_the_package_face_exports_what_it_lists():
    for name in replication.__all__:
        assert getattr(replication, name) is not None, name
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        replication.nonexistent  # noqa: B018


def _code_cells(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    return [(i, "".join(c["source"])) for i, c in enumerate(nb["cells"]) if c["cell_type"] == "code"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_cells_are_short(path):
    long = [(i, n) for i, src in _code_cells(path) if (n := len(src.splitlines())) > MAX_CELL_LINES]
    assert not long, f"{path.name}: cells (index, lines) over {MAX_CELL_LINES} lines: {long}"


def private_imports(source: str) -> list:
    """The private names (or modules) a piece of code imports from the package."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "replication":
            found += [f"{node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
            found += [node.module] if any(p.startswith("_") for p in node.module.split(".")) else []
        elif isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.split(".")[0] == "replication"
                      and any(p.startswith("_") for p in a.name.split("."))]
    return found


def test_the_private_import_finder_sees_names_and_modules():
    assert private_imports("from replication.core.solvers import solve") == []
    assert private_imports("from replication.core.solvers import _registry") == ["replication.core.solvers._registry"]
    assert private_imports("from replication.core.solvers._registry import check_answer") == [
        "replication.core.solvers._registry"]
    assert private_imports("import replication._io") == ["replication._io"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebooks_import_no_private_name(path):
    found = {i: names for i, src in _code_cells(path) if (names := private_imports(src))}
    assert not found, f"{path.name} imports private names (cell index: names): {found}"


# -------------------------------------------------------------------------------------------------
# the tests' homes
TESTS = ROOT / "tests"
#: Test files named for no module, each with what it tests instead.
TESTS_OF_NO_MODULE = {"tests/test_layout.py": "the package's layout as a whole"}


def _snake(name: str) -> str:
    return "".join(f"_{c.lower()}" if c.isupper() and i else c.lower() for i, c in enumerate(name))


def _commands(path: Path) -> list:
    """The names of the commands a module of the command line adds (``sub.add_parser("fetch-data",
    ...)``), with ``_`` for ``-``."""
    calls = [n for n in ast.walk(_tree(path)) if isinstance(n, ast.Call)
             and getattr(n.func, "attr", None) == "add_parser" and n.args and isinstance(n.args[0], ast.Constant)]
    return [c.args[0].value.replace("-", "_") for c in calls]


def _unit(module: str) -> str:
    """A module's unit: its path below the room, parts joined by ``_`` without leading ``_``."""
    return "_".join(p.lstrip("_") for p in module.split(".")[2:])


@functools.cache
def _public_classes(module: str) -> frozenset:
    """A module's public classes in snake case (``OnlineCalibrator``: ``online_calibrator``)."""
    body = _tree(MODULES[module]).body
    return frozenset(_snake(n.name) for n in body if isinstance(n, ast.ClassDef) and not n.name.startswith("_"))


@functools.cache
def unit_names(room: str) -> frozenset:
    """The names a test file of ``room`` may take: each module's path below the room, its parts
    joined by ``_`` without their leading underscores (``core/solvers/_registry.py``:
    ``solvers_registry``; a package: its own name), each public class of the room in snake case
    (``OnlineCalibrator``: ``online_calibrator``), and in ``cli`` each command's name
    (``fetch-data``: ``fetch_data``; test files need names unique across the folders)."""
    names = set()
    for module, path in MODULES.items():
        parts = module.split(".")
        if parts[0] != "replication":
            continue
        if room == "hall":
            if len(parts) == 2 and parts[1] in ROOMS and parts[1] not in ("core", "rig", "study", "__init__"):
                names.add(parts[1].strip("_"))
            continue
        if len(parts) < 3 or parts[1] != room:
            continue
        names.add(_unit(module))
        if room == "cli":  # a command by its name (``fetch-data``: ``fetch_data``)
            names |= set(_commands(path))
        names |= _public_classes(module)
    return frozenset(names)


def misnamed_test_file(path: Path) -> str | None:
    """Why a test file's name names nothing it could test, or None: ``tests/<room>/test_<unit>.py``
    for the rooms core, rig and study (:func:`unit_names`), ``tests/test_<module>.py`` for the
    hall's modules, ``tests/scripts/test_<script>.py`` for ``scripts/<script>.py``, and in
    ``tests/notebooks/`` the nbval sanitiser (``test_sanitize.py``) and the portability re-runs
    named by the notebooks they re-run."""
    rel = path.relative_to(ROOT).as_posix()
    if rel in TESTS_OF_NO_MODULE:
        return None
    folder = path.parent.relative_to(TESTS).as_posix()
    name = path.stem.removeprefix("test_")
    if folder in ("cli", "core", "rig", "study", "."):
        units = unit_names("hall" if folder == "." else folder)
        return None if name in units else f"{rel}: no module or public class {name!r} in {folder} ({sorted(units)})"
    if folder == "scripts":
        return None if (ROOT / "scripts" / f"{name}.py").exists() else f"{rel}: no scripts/{name}.py"
    if folder == "notebooks":
        numbers = {p.name[:2] for p in NOTEBOOKS}
        if name == "sanitize" or (name.startswith("portability_")
                                  and set(name.removeprefix("portability_").split("_")) <= numbers):
            return None
        return f"{rel}: tests/notebooks/ holds test_sanitize.py and test_portability_<notebook numbers>.py only"
    return f"{rel}: a test folder that is no room (core, rig, study, scripts, notebooks)"


def test_every_test_file_is_named_for_the_unit_it_tests():
    files = sorted(TESTS.rglob("test_*.py"))
    assert len(files) > 40
    assert [why for why in map(misnamed_test_file, files) if why] == []


def test_the_test_file_rule_refuses_history_and_missing_units(tmp_path):
    assert misnamed_test_file(TESTS / "rig" / "test_online.py") is None
    assert misnamed_test_file(TESTS / "core" / "test_solvers_registry.py") is None  # core/solvers/_registry.py
    assert misnamed_test_file(TESTS / "rig" / "test_online_calibrator.py") is None  # the public class
    assert misnamed_test_file(TESTS / "test_main.py") is None  # replication/__main__.py
    assert misnamed_test_file(TESTS / "cli" / "test_fetch_data.py") is None  # the command fetch-data
    assert misnamed_test_file(TESTS / "cli" / "test_calibrate_inputs.py") is None  # a module of cli/
    assert "no module or public class 'fetch_dat'" in misnamed_test_file(TESTS / "cli" / "test_fetch_dat.py")
    assert "no module or public class 'mutants_online'" in misnamed_test_file(TESTS / "rig" / "test_mutants_online.py")
    assert "no module or public class 'online_judging'" in misnamed_test_file(TESTS / "rig" / "test_online_judging.py")
    assert "no module or public class 'so3'" in misnamed_test_file(TESTS / "rig" / "test_so3.py")  # another room's
    assert "no scripts/nope.py" in misnamed_test_file(TESTS / "scripts" / "test_nope.py")
    history = TESTS / "notebooks" / "test_portability_part2.py"
    assert "test_portability_<notebook numbers>" in misnamed_test_file(history)
    assert "no room" in misnamed_test_file(TESTS / "misc" / "test_so3.py")


def test_the_portability_files_share_out_every_notebook_once():
    files = (TESTS / "notebooks").glob("test_portability_*.py")
    parts = [p.stem.removeprefix("test_portability_").split("_") for p in files]
    assert len(parts) == 2  # one per xdist worker (scripts/test runs two, --dist loadfile)
    assert sorted(sum(parts, [])) == [p.name[:2] for p in NOTEBOOKS]


#: A test reaches its file's unit: of the package's names it uses (functions, classes), itself or
#: through the functions of its file and of tests/conftest.py it calls or takes as fixtures, one is
#: defined in the unit or in a module that uses the unit at any remove (its doors: the online
#: estimator for its parts, ``calibrate`` for the clock). A test that reaches only other units
#: belongs in their file; one that reaches no name of the package (a subprocess, a file's text) is
#: not judged. The exceptions, with their reason (``<file>::<test>``):
STRAYS = {
    "core/test_solvers.py::test_every_exported_solver_refuses_bad_input":
        "calls each solver through the dict EXPORTED, whose values the rule does not follow",
    "core/test_solvers_opencv.py::test_opencv_wrappers_refuse_long_chains_before_calling_opencv":
        'calls the OpenCV wrappers through solve("opencv_park") and its twins, by name',
    "core/test_solvers_slsqp.py::test_registered_and_batched":
        'calls SQP through solve("sqp"), by name',
    "rig/test_export.py::test_a_hand_made_static_pose_report_keeps_kalibrs_timeshift_through_the_command":
        "runs rig.export through its command in a subprocess; the rule sees only read_vio_file reading the output",
    "rig/test_export.py::test_the_export_command_writes_a_copy_and_says_what_changed":
        "runs rig.export through its command in a subprocess; the rule sees only read_vio_file reading the output",
    "study/test_book.py::test_the_front_page_reads_in_five_minutes_in_a_real_browser":
        "the book is built in a subprocess and read in a browser; the ledger gives the counts it is checked against",
    "study/test_book.py::test_the_front_page_shows_the_counts_of_the_records":
        "the book is built in a subprocess; the test reads its HTML and the ledger it shows",
}


def _functions(tree) -> dict:
    """The module-level functions of a test file and the methods of its classes, by name."""
    found = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            found[node.name] = node
        elif isinstance(node, ast.ClassDef):
            found.update({f"{node.name}.{m.name}": m for m in node.body if isinstance(m, ast.FunctionDef)})
    return found


def _package_aliases(tree) -> dict:
    """What each name a test file imports from the package stands for (a module, function or class),
    and ``conftest`` imports by the name of their function in tests/conftest.py."""
    aliases = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "conftest":
            aliases.update({a.asname or a.name: ("conftest", a.name) for a in node.names})
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "replication":
            module = importlib.import_module(node.module)
            for a in node.names:
                found = getattr(module, a.name, None)
                aliases[a.asname or a.name] = found if found is not None else importlib.import_module(
                    f"{node.module}.{a.name}")
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "replication":
                    aliases[a.asname or "replication"] = importlib.import_module(a.asname and a.name or "replication")
    return aliases


def _dotted(node) -> list | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    return [node.id, *reversed(parts)] if isinstance(node, ast.Name) else None


@functools.cache
def _scopes(text: str) -> dict:
    """Each function of a test file's ``text`` and what its imports of the package stand for."""
    tree = ast.parse(text)
    aliases = _package_aliases(tree)
    return {name: (fn, aliases) for name, fn in _functions(tree).items()}


def reached_modules(source: str, conftest: str) -> dict:
    """For each test function of ``source``: the package modules that define a function or class it
    names, itself or through the functions of its file and of ``conftest`` it names or takes as
    fixtures (followed to any depth)."""
    scopes = {**_scopes(conftest), **_scopes(source)}  # the file's own functions shadow conftest's

    def named(fn, aliases) -> tuple:
        modules, local = set(), {a.arg for a in fn.args.args if a.arg in scopes}
        for node in ast.walk(fn):
            parts = _dotted(node) if isinstance(node, (ast.Name, ast.Attribute)) else None
            if not parts:
                continue
            if parts[0] in scopes:
                local.add(parts[0])
            found = aliases.get(parts[0])
            if isinstance(found, tuple):  # a conftest function imported by name
                local.add(found[1])
                continue
            for part in parts[1:]:
                found = getattr(found, part, None) if found is not None else None
            home = getattr(found, "__module__", None) if not isinstance(found, types.ModuleType) else None
            if isinstance(home, str) and home.startswith("replication"):
                modules.add(home)
        return modules, local

    def reach(name, seen) -> set:
        if name in seen or name not in scopes:
            return set()
        seen.add(name)
        modules, local = named(*scopes[name])
        return modules.union(*(reach(other, seen) for other in local))

    tests = [name for name in _functions(ast.parse(source)) if name.split(".")[-1].startswith("test_")]
    return {name: reach(name, set()) for name in tests}


@functools.cache
def _importers() -> dict:
    """The modules that import each module directly."""
    found = {}
    for module in MODULES:
        for _, target in imports_of(module):
            found.setdefault(target, set()).add(module)
    return found


def unit_modules(path: Path, doors: bool = True) -> set:
    """The package modules a test file of core, rig or study is named for: the module or the module
    of the public class its name names; with ``doors``, also a named package's modules and the
    modules that import the named ones (the doors through which they are tested)."""
    room, name = path.parent.name, path.stem.removeprefix("test_")
    own = set()
    for module in MODULES:
        parts = module.split(".")
        if len(parts) >= 3 and parts[1] == room and (
                _unit(module) == name or name in _public_classes(module)):
            own.add(module)
    if not doors:
        return own
    own |= {m for m in MODULES if any(m.startswith(f"{package}.") for package in own)}
    doors, new = set(own), set(own)
    while new:  # the modules that import these, at any remove
        new = set().union(*(_importers().get(m, set()) for m in new)) - doors
        doors |= new
    return doors


def strays_of(path: Path) -> tuple:
    """``(tests reaching no module of the file's unit, all tests)`` of a test file of core, rig or
    study (:func:`reached_modules`, :func:`unit_modules`)."""
    conftest = (TESTS / "conftest.py").read_text(encoding="utf-8")
    reached = reached_modules(path.read_text(encoding="utf-8"), conftest)
    own = unit_modules(path)
    return sorted(n for n, modules in reached.items() if modules and not modules & own), len(reached)


def test_the_reach_finder_follows_helpers_fixtures_and_package_faces():
    conftest = "from replication.rig.calibration import calibrate\ndef calibrated():\n    return calibrate\n"
    source = ("from replication.core import so3\nfrom replication.rig import streams as st\n"
              "from conftest import calibrated as cal\n"
              "def _helper():\n    return so3.matrix_from_rotation_vector\n"
              "def test_direct():\n    st.GyroStream\n"
              "def test_through_a_helper():\n    _helper()\n"
              "def test_through_a_fixture(calibrated):\n    pass\n"
              "def test_through_an_import_of_conftest():\n    cal()\n"
              "def test_nothing():\n    assert 1\n")
    assert reached_modules(source, conftest) == {
        "test_direct": {"replication.rig.streams"}, "test_through_a_helper": {"replication.core.so3"},
        "test_through_a_fixture": {"replication.rig.calibration"},
        "test_through_an_import_of_conftest": {"replication.rig.calibration"}, "test_nothing": set()}


def test_a_unit_is_its_module_its_public_class_and_their_doors():
    doors = unit_modules(TESTS / "rig" / "test_online_creep.py")
    assert {"replication.rig.online_creep", "replication.rig.online", "replication.rig.live"} <= doors
    assert "replication.rig.online" in unit_modules(TESTS / "rig" / "test_online_calibrator.py")
    assert "replication.study.convexity.claims" in unit_modules(TESTS / "study" / "test_convexity.py")
    assert unit_modules(TESTS / "study" / "test_convexity.py", doors=False) == {"replication.study.convexity"}
    assert unit_modules(TESTS / "rig" / "test_online.py", doors=False) == {"replication.rig.online"}
    assert unit_modules(TESTS / "rig" / "test_online_calibrator.py", doors=False) == {"replication.rig.online"}
    assert "replication.rig.quality" not in doors


TEST_FILES_OF_UNITS = sorted(p for room in ("core", "rig", "study") for p in (TESTS / room).glob("test_*.py"))


def test_every_unit_has_one_test_file():
    homes = {}
    for path in TEST_FILES_OF_UNITS:
        for module in unit_modules(path, doors=False):
            homes.setdefault(module, []).append(path.relative_to(TESTS).as_posix())
    twice = {m: files for m, files in homes.items() if len(files) > 1}
    assert not twice, f"units with more than one test file (a module and its class count as one unit): {twice}"


@pytest.mark.parametrize("path", TEST_FILES_OF_UNITS, ids=lambda p: p.relative_to(TESTS).as_posix())
def test_each_test_reaches_its_file_s_unit(path):
    off, _ = strays_of(path)
    off = [name for name in off if f"{path.relative_to(TESTS).as_posix()}::{name}" not in STRAYS]
    assert not off, (f"{path.relative_to(ROOT)}: these tests reach no name of its unit or of a module that uses it; "
                     f"move each to the file of the unit it reaches, or list it in STRAYS with its reason: {off}")


def test_the_strays_listed_still_exist_and_still_stray():
    listed = {}
    for key in STRAYS:
        listed.setdefault(key.split("::")[0], set()).add(key.split("::")[1])
    for file, names in listed.items():
        assert names <= set(strays_of(TESTS / file)[0]), f"{file}: {names} no longer stray or exist"


def test_the_workers_take_the_files_in_the_conftests_order(pytestconfig):
    """conftest.py sorts the longest files (the portability re-runs, the notebooks, the unit files
    it names) first; xdist's own reordering by number of tests, on by default, would start the
    re-runs last."""
    assert pytestconfig.pluginmanager.hasplugin("xdist")  # the test extra installs it
    assert pytestconfig.option.loadscopereorder is False
    root_conftest = next(p for p in pytestconfig.pluginmanager.get_plugins()
                         if getattr(p, "__file__", None) == str(ROOT / "conftest.py"))
    assert root_conftest.LONG_UNIT_FILES and all((ROOT / name).is_file() for name in root_conftest.LONG_UNIT_FILES)


#: The naming rule for conversions (docs/conventions.md, "Names of conversions"):
#: ``<to>_from_<from>``. A module-level public function named like another rule's conversion is
#: refused; the exceptions, with their reason:
NOT_CONVERSIONS = {
    "nearest_rotation_up_to_sign": "'up to sign' qualifies the projection; nothing is converted",
    "match_to_table1": "a verb: it matches a stopped SQP to Table I's rows",
    "cost_to_zero": "a claim's id (the paper's cost goes to zero): its record, not a conversion",
}
OTHER_RULES = r"^(as|to|from)_|_to_"


def conversion_name_violations(source: str) -> list:
    """Module-level public functions of ``source`` named against the rule (``as_*``, ``to_*``,
    ``from_*``, ``*_to_*``), the listed exceptions aside; methods (``to_dict``) and private helpers
    are not looked at."""
    import re

    return [node.name for node in ast.parse(source).body
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not node.name.startswith("_")
            and re.search(OTHER_RULES, node.name) and node.name not in NOT_CONVERSIONS]


def test_the_naming_rule_finder_sees_each_other_rule_and_spares_the_rest():
    source = ("def as_array(R): ...\ndef to_text(x): ...\ndef from_degrees(s, a): ...\n"
              "def distance_to_angle(d): ...\ndef quaternion_from_matrix(R): ...\ndef _as_array(x): ...\n"
              "def nearest_rotation_up_to_sign(M): ...\ndef world_from_body(t): ...\ndef total(x): ...\n"
              "class Result:\n    def to_dict(self): ...\n")
    assert conversion_name_violations(source) == ["as_array", "to_text", "from_degrees", "distance_to_angle"]


@pytest.mark.parametrize("module", sorted(MODULES))
def test_conversions_are_named_to_from_from(module):
    found = conversion_name_violations(MODULES[module].read_text(encoding="utf-8"))
    assert not found, (f"{module}: {found} break the naming rule <to>_from_<from> (docs/conventions.md); rename them, "
                       "or list a name that converts nothing in NOT_CONVERSIONS with its reason")


def test_the_exceptions_to_the_naming_rule_still_exist():
    defined = set().union(*(_defined_names(_tree(p)) for p in MODULES.values()))
    assert set(NOT_CONVERSIONS) <= defined, set(NOT_CONVERSIONS) - defined


def test_the_old_conversion_names_are_gone_and_the_conventions_page_names_the_new():
    from replication.core import so3
    from replication.study import ledger

    old_so3 = ["log_map", "exp_map", "as_quaternion", "quaternion_to_matrix"]  # (old names on purpose)
    old_so3 += ["yaw_pitch_roll_deg", "from_euler", "chordal_to_angle_deg"]  # (old names on purpose)
    old_ledger = ["to_markdown", "to_summary"]  # (old names on purpose)
    assert not [n for n in old_so3 if hasattr(so3, n)] and not [n for n in old_ledger if hasattr(ledger, n)]
    page = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    converters = [n for n in so3.__all__ if "_from_" in n] + ["markdown_from_ledger", "summary_from_ledger"]
    assert len(converters) == 10 and not [n for n in converters if f"`{n}`" not in page and f".{n}`" not in page]


#: Backticked words of docs/layout.md's tables that are not names in the code, with their reason.
LAYOUT_WORDS_NOT_IN_CODE = {
    "InitialEXRotation": "VINS-Mono's class, which study/vins_rule.py ports",
    "ahrs": "the third-party package of the lab's filters",
    "warning": "a verdict level, a string",
}


def _names_in_code() -> set:
    names = set()
    for path in MODULES.values():
        names.update({path.stem, *path.relative_to(ROOT).parent.parts})
        for node in ast.walk(_tree(path)):
            names.update({getattr(node, key) for key in ("name", "id", "attr", "arg")
                          if isinstance(getattr(node, key, None), str)})
    return names


def layout_words_not_in_code(page: str, names: set) -> list:
    """Backticked identifiers in the page's table rows that the code does not have; the paper's own
    symbols may follow a code name in ``(the paper's ...)``."""
    import re

    rows = [re.sub(r"\(the paper's [^)]*\)", "", line) for line in page.splitlines() if line.startswith("|")]
    words = {w for row in rows for w in re.findall(r"`([A-Za-z_]\w*)`", row)}
    return sorted(w for w in words if w not in names and w not in LAYOUT_WORDS_NOT_IN_CODE)


def test_the_layout_page_names_what_the_code_has():
    names = _names_in_code()
    assert layout_words_not_in_code("| | `handeye.py` | `H1`, `v2h` |", names) == ["H1"]
    assert layout_words_not_in_code("| | `handeye.py` | `stack_H1` (the paper's `H1`) |", names) == []
    page = (ROOT / "docs" / "layout.md").read_text(encoding="utf-8")
    assert not layout_words_not_in_code(page, names), "docs/layout.md names what the code does not have"
