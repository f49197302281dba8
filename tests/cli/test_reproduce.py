"""The ``reproduce`` command (``replication/cli/reproduce.py``): every notebook executed in order in
a fresh process, ``results/`` written, notebooks that need absent real data skipped, and a results
folder that clashes with the notebooks or cannot be made refused before any notebook runs."""
import os
import subprocess
import sys

import nbformat
import pytest

from conftest import _snapshot
from replication.cli import main


def test_reproduce_executes_notebooks_in_order_and_writes_results(tmp_path):
    nbdir, results = tmp_path / "nb", tmp_path / "results"
    nbdir.mkdir()
    for name, code in [
        ("01_a.ipynb", "from replication.study.notebook import save_table\nimport pandas as pd\n"
                       "save_table(pd.DataFrame({'x': [1]}), 'first')"),
        ("02_b.ipynb", "from replication.study.notebook import results_dir\n"
                       "assert (results_dir() / 'tables' / 'first.csv').exists()\nprint('ok')"),
    ]:
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
        nb.metadata["kernelspec"] = {"name": "someone-elses-kernel", "display_name": "x", "language": "python"}
        nbformat.write(nb, nbdir / name)
    out = subprocess.run(
        [sys.executable, "-m", "replication", "reproduce", "--notebooks", str(nbdir), "--results", str(results)],
        capture_output=True, text=True, timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert (results / "tables" / "first.csv").exists() and (results / "tables" / "first.md").exists()
    nb = nbformat.read(nbdir / "02_b.ipynb", as_version=4)
    assert nb.cells[0].outputs[0]["text"] == "ok\n"  # executed in place, outputs stored
    assert nb.metadata["kernelspec"]["name"] == "python3"  # kernelspec normalised


def test_reproduce_without_notebooks_fails_clearly(tmp_path):
    out = subprocess.run([sys.executable, "-m", "replication", "reproduce", "--notebooks", str(tmp_path)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode != 0 and "no numbered notebooks" in out.stderr


def test_reproduce_skips_notebooks_that_need_absent_real_data(tmp_path):
    nbdir = tmp_path / "nb"
    nbdir.mkdir()
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("raise SystemExit('must not run')")])
    nb.metadata["replication"] = {"requires_real_data": True}
    nbformat.write(nb, nbdir / "01_real.ipynb")
    env = {**os.environ, "REPLICATION_REAL_DATA": str(tmp_path / "nowhere")}
    out = subprocess.run([sys.executable, "-m", "replication", "reproduce", "--notebooks", str(nbdir),
                          "--results", str(tmp_path / "results")], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert "skipping 01_real.ipynb" in out.stdout and "nowhere" in out.stdout


@pytest.fixture
def notebook_folder(tmp_path, monkeypatch):
    import nbformat

    import replication.cli.reproduce as entry

    folder = tmp_path / "nb"
    folder.mkdir()
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1")]), folder / "01_a.ipynb")
    monkeypatch.setattr(entry, "execute_notebook", lambda *a, **k: pytest.fail("a notebook ran"))
    return folder


@pytest.mark.parametrize("case, message", [
    ("the notebooks folder", "--results {results} is the --notebooks folder"),
    ("a notebook", "--results is the notebook 01_a.ipynb input file: {results}"),
    ("under a file", "--results {resolved}: cannot create this folder (Not a directory)"),
])
def test_reproduce_refuses_a_results_folder_that_clashes_or_cannot_be_made(notebook_folder, case, message, capsys):
    results = {"the notebooks folder": notebook_folder, "a notebook": notebook_folder / "01_a.ipynb",
               "under a file": notebook_folder / "01_a.ipynb" / "results"}[case]
    before = _snapshot(notebook_folder)
    assert main(["reproduce", "--notebooks", str(notebook_folder), "--results", str(results)]) == 2
    err = capsys.readouterr().err
    assert message.format(results=results, resolved=results.resolve()) in err, err
    assert _snapshot(notebook_folder) == before
