import os
import subprocess
import sys

import nbformat


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


def test_generate_lab_writes_a_loadable_recording(tmp_path, capsys):
    """(That the committed data/lab equal the generator's output is tests/test_lab.py's check.)"""
    from replication.__main__ import main
    from replication.study.lab import load_lab

    assert main(["generate-lab", "--out", str(tmp_path / "a"), "--seed", "7"]) == 0
    assert "seed 7" in capsys.readouterr().out
    rec = load_lab(tmp_path / "a")
    assert rec.truth["camera_from_sensor"].shape == (3, 3)
    assert main(["generate-lab", "--out", str(tmp_path / "b"), "--seed", "8"]) == 0
    assert (tmp_path / "a" / "static_imu.csv").read_text() != (tmp_path / "b" / "static_imu.csv").read_text()
