"""Test-session set-up.

* Notebooks run under nbval write results/ into a temporary folder.
* Under pytest-xdist, ``scripts/test`` runs two workers with ``--dist loadfile``: every cell of a
  notebook goes to the same worker, in order, so one kernel runs the notebook from top to bottom.
  The workers take the files in the order sorted here, the longest first (xdist's own reordering,
  by number of tests, is turned off).
  (``loadgroup`` with ``xdist_group`` marks does not group with pytest 9, whose node ids xdist 3.8
  cannot suffix.)
* Notebooks that declare ``metadata.replication.requires_real_data`` are skipped, with the
  reason, when the real-data folder (``$REPLICATION_REAL_DATA`` or ``../shared/data/real``)
  is absent.
"""
import os
import re
import tempfile

import pytest

#: Unit-test files with one long test, started first among the unit tests so that no worker ends
#: the run alone with it: the wheel built and installed in a fresh venv (21 s on an idle machine).
LONG_UNIT_FILES = ("tests/test_extras.py",)


def pytest_configure(config):
    if "REPLICATION_RESULTS_DIR" not in os.environ:
        os.environ["REPLICATION_RESULTS_DIR"] = tempfile.mkdtemp(prefix="replication-results-")
    # xdist 3.x hands out the files by their number of tests, most first, unless told not to: it
    # undid the sort below, and the portability re-runs (4 and 5 tests, 9-12 min each on a loaded
    # machine) started 1495 and 1538 s into a 2198 s run, their imbalance the run's tail
    if getattr(config.option, "loadscopereorder", False):
        config.option.loadscopereorder = False


def unit_test_files(rootpath, mutant):
    """The test files of the unit of a mutmut mutant (``replication.rig.online.x...``): those named
    for its module, ``tests/<room>/test_<module>.py`` and ``test_<module>_*.py``
    (``solvers/_registry.py``: ``test_solvers_registry``), and those named for its doors, the
    modules of its package that import it (``offset_search``'s tests run through ``association``);
    ``None`` for a name that is not a mutant's."""
    if "__mutmut_" not in mutant:
        return None
    module = mutant.split(".x_")[0].split(".x\u01c1")[0].split(".")
    folder = rootpath / "tests" / module[1]
    stems = {"_".join(part.strip("_") for part in module[2:])}
    imports = re.compile(rf"^from \.{module[-1]} import |^from \. import .*\b{module[-1]}\b", re.M)
    stems |= {source.stem for source in rootpath.joinpath(*module[:-1]).glob("*.py")
              if source.stem != "__init__" and imports.search(source.read_text())}
    return {path for stem in stems for path in (folder / f"test_{stem}.py", *folder.glob(f"test_{stem}_*.py"))}


def _unit_tests_only(config, items):
    """Under ``scripts/mutation --unit`` (``REPLICATION_MUTATION_TESTS=unit``), a mutant runs only
    the tests of its unit's files (:func:`unit_test_files`): a kill there is a kill by the whole
    selection, and the mutants left are re-run against every test (``--survivors``)."""
    if os.environ.get("REPLICATION_MUTATION_TESTS") != "unit":
        return
    files = unit_test_files(config.rootpath, os.environ.get("MUTANT_UNDER_TEST", ""))
    if files is None:
        return
    dropped = [item for item in items if item.path not in files]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = [item for item in items if item.path in files]


def pytest_collection_modifyitems(config, items):
    from replication.cli.reproduce import needs_real_data
    from replication.rig.realdata import data_root, real_data_available

    _unit_tests_only(config, items)

    # the longest files first (the portability re-run, then the notebooks, then LONG_UNIT_FILES), so
    # that two xdist workers finish together (in collection order the portability re-run started
    # last and ran alone for minutes); the order within a file is kept (a stable sort), and nothing
    # depends on the order between files
    long_units = {config.rootpath / name for name in LONG_UNIT_FILES}
    items.sort(key=lambda item: 0 if item.get_closest_marker("portability") else 1 if item.path.suffix == ".ipynb"
               else 2 if item.path in long_units else 3)
    if real_data_available():
        return
    try:
        data_root()
    except FileNotFoundError as err:
        reason = f"needs the real recordings: {err}"
    checked = {}
    for item in items:
        path = item.path
        if path.suffix == ".ipynb":
            if path not in checked:
                checked[path] = needs_real_data(path)
            if checked[path]:
                item.add_marker(pytest.mark.skip(reason=reason))
