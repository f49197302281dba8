"""A calibrate-only install: the core dependencies leave out the notebook stack, and ``calibrate``
and ``--version`` run without it.

A fresh virtual environment per test run would take minutes; instead the core list is read from
pyproject.toml, and the command line runs in a subprocess whose imports of the optional packages
fail as if they were not installed (a meta-path finder placed first). environment.md records the
check in a real fresh venv.
"""
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import tomllib

from replication._extras import OPTIONAL, MissingExtra, require
from replication.core import so3
from replication.testing import RIG_R0, rig_motion

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
#: The notebook stack and the studies' packages: none of them in the core install.
NOTEBOOK_STACK = ["nbclient", "nbformat", "ipykernel", "jupyter", "pandas", "tqdm", "tabulate", "ahrs"]
#: What calibrate, the rig API and the solvers import.
CORE = ["numpy", "scipy", "matplotlib", "opencv-python-headless", "pyyaml", "clarabel"]


def _names(requirements):
    return [re.match(r"[A-Za-z0-9_.\-]+", r).group(0).lower() for r in requirements]


def _blocked_run(args, blocked=NOTEBOOK_STACK, cwd=None):
    """``python -m replication *args`` in a subprocess where importing any of ``blocked`` (or a
    submodule) raises ``ModuleNotFoundError``, as if not installed."""
    code = textwrap.dedent(f"""
        import runpy, sys
        BLOCKED = {sorted(blocked)!r}

        class Blocker:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in BLOCKED:
                    raise ModuleNotFoundError(f"No module named {{name!r}} (blocked by the test)", name=name)
                return None

        sys.meta_path.insert(0, Blocker())
        sys.argv = ["python -m replication", *{[str(a) for a in args]!r}]
        runpy.run_module("replication", run_name="__main__", alter_sys=True)
    """)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=cwd)


def test_the_core_dependencies_leave_out_the_notebook_stack():
    core = _names(PYPROJECT["dependencies"])
    assert sorted(core) == sorted(CORE)
    assert not set(core) & set(NOTEBOOK_STACK)
    extras = PYPROJECT["optional-dependencies"]

    def installed_by(extra):  # the extra's packages, those of the extras it names ("camimu-replication[study]") too
        names = set(_names(extras[extra]))
        for inner in re.findall(r"^camimu-replication\[(\w+)\]$", "\n".join(extras[extra]), re.M):
            names |= installed_by(inner)
        return names - {"camimu-replication"}

    for module, extra in OPTIONAL.items():  # the extra a missing module's message names installs it
        assert module in installed_by(extra), (module, extra)
    assert set(OPTIONAL) == set(NOTEBOOK_STACK)
    assert "camimu-replication[study]" in PYPROJECT["optional-dependencies"]["notebooks"]
    setup = (ROOT / "scripts" / "setup.sh").read_text()
    assert re.search(r'-e "\$ROOT\[study,test,notebooks(,docs)?\]"', setup)  # README's two commands install everything


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """30 s of a camera (TUM, 20 Hz) and a rigidly attached gyro (EuRoC imu0 CSV, 200 Hz)."""
    d = tmp_path_factory.mktemp("light")
    R0, world_from_camera = RIG_R0, rig_motion

    t = np.arange(0.0, 30.0, 0.05)
    q = so3.quaternion_from_matrix(world_from_camera(t))
    np.savetxt(d / "cam.txt", np.column_stack([t + 1e3, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    t_imu = np.arange(-1.0, 31.0, 0.005)
    Q = world_from_camera(t_imu) @ R0
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    t_mid = 0.5 * (t_imu[1:] + t_imu[:-1]) + 1e3
    np.savetxt(d / "imu.csv", np.column_stack([np.round(t_mid * 1e9), omega, np.tile([0, 0, 9.81], (len(t_mid), 1))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",", header="timestamp,wx,wy,wz,ax,ay,az")
    return d, R0


def test_the_blocker_blocks():
    """The control: with the blocker, importing pandas fails; without it, it works (else the next
    test proves nothing)."""
    out = _blocked_run(["--version"], blocked=["replication"])
    assert out.returncode != 0 and "blocked by the test" in out.stderr
    assert _blocked_run(["--version"], blocked=[]).returncode == 0


def test_calibrate_and_version_run_without_the_notebook_stack(rig, tmp_path):
    d, R0 = rig
    out = _blocked_run(["--version"])
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"replication {__import__('replication').__version__}"
    report, figure = tmp_path / "r.json", tmp_path / "r.png"
    out = _blocked_run(["calibrate", "--camera", d / "cam.txt", "--sensor", d / "imu.csv", "--sensor-kind", "gyro",
                        "--bootstrap", "20", "--out", report, "--plot", figure], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "verdict: OK" in out.stdout and out.stderr == ""
    estimate = np.array(__import__("json").loads(report.read_text())["R0_camera_from_sensor"])
    assert so3.angle_between_deg(estimate, R0) < 1e-3  # noise-free: measured 8e-6 deg (the gyro's integration)
    assert figure.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("args, needs", [
    (["calibrate", "--online"], "calibrate --online needs pandas"),
    (["reproduce", "--only", "nothing"], "python -m replication reproduce needs"),
])
def test_a_command_that_needs_the_extra_says_which_to_install(rig, tmp_path, args, needs):
    d, _ = rig
    if args[0] == "calibrate":
        args = [*args, "--camera", d / "cam.txt", "--sensor", d / "imu.csv", "--sensor-kind", "gyro", "--bootstrap", 0]
    else:
        args = [*args, "--results", tmp_path / "results"]
    out = _blocked_run(args)
    assert out.returncode == 2, out.stderr
    assert needs in out.stderr and "in the project's clone, pip install -c requirements.lock '.[study]'" in out.stderr
    assert "Traceback" not in out.stderr and "verdict" not in out.stdout  # refused before any work


def test_require_names_the_extra():
    assert require("math", "x").pi > 3
    with pytest.raises(MissingExtra, match=r"the replay needs no_such_module_x, which is not installed: in the "
                                           r"project's clone, pip install -c requirements.lock '\.\[study\]'") as info:
        require("no_such_module_x", "the replay")
    assert isinstance(info.value, ImportError) and info.value.name == "no_such_module_x"


# --------------------------------------------------------------------- the distribution and a wheel

def test_the_distribution_is_not_pypis_unrelated_replication_and_ships_what_commands_cite():
    """Issue 35: ``replication`` on PyPI is another project; the name is checked free with ``pip
    index versions camimu-replication`` (nothing found, 2026-12-04). The files commands read or cite
    outside the package are copied into a wheel by setup.py, included in an sdist by MANIFEST.in,
    and listed once in _extras.SHIPPED."""
    from replication._extras import DISTRIBUTION, SHIPPED, shipped

    assert PYPROJECT["name"] == DISTRIBUTION == "camimu-replication"
    import ast

    tree = ast.parse((ROOT / "setup.py").read_text())
    assigned = {t.id: n.value for n in tree.body if isinstance(n, ast.Assign) for t in n.targets}
    assert ast.literal_eval(assigned["SHIPPED"]) == SHIPPED
    assert sorted(ln.split()[1] for ln in (ROOT / "MANIFEST.in").read_text().splitlines()) == sorted(SHIPPED)
    for name in SHIPPED:
        assert shipped(name) == ROOT / name and shipped(name).is_file()
    assert "data/real_data_manifest.csv" in SHIPPED and "docs/conventions.md" in SHIPPED


def test_a_wheel_in_a_fresh_venv_runs_calibrate_export_and_fetch_data(rig, tmp_path):
    """Issue 35: build the wheel, install it with the lock in a new virtual environment, and run the
    commands from a folder outside the clone: every help text, a calibration, its export and
    fetch-data's manifest, with no file missing. About 50 s (most of it pip installing the core's
    wheels); skipped if pip cannot reach them."""
    d, R0 = rig
    wheels, venv = tmp_path / "whl", tmp_path / "venv"
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", wheels, ROOT],
                           capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    subprocess.run([sys.executable, "-m", "venv", venv], check=True, timeout=120)
    python = venv / "bin" / "python"
    installed = subprocess.run([python, "-m", "pip", "install", "-q", "-c", ROOT / "requirements.lock",
                                *wheels.glob("camimu_replication-*.whl")], capture_output=True, text=True, timeout=600)
    if installed.returncode != 0 and "No matching distribution" in installed.stderr:
        pytest.skip(f"pip could not get the core's dependencies here: {installed.stderr.strip()[-200:]}")
    assert installed.returncode == 0, installed.stderr
    outside = tmp_path / "elsewhere"
    outside.mkdir()

    def run(*args):
        return subprocess.run([python, "-m", "replication", *map(str, args)], capture_output=True, text=True,
                              cwd=outside, timeout=300)

    where = subprocess.run([python, "-c", "import replication; print(replication.__file__)"], capture_output=True,
                           text=True, cwd=outside)
    assert str(venv) in where.stdout and str(ROOT / "replication") not in where.stdout  # the wheel, not the clone
    for command in ("calibrate", "export", "fetch-data"):
        out = run(command, "--help")
        assert out.returncode == 0 and out.stderr == "" and "usage:" in out.stdout, (command, out.stderr)
    package = Path(where.stdout.strip()).parent
    assert (package / "_shipped" / "docs" / "conventions.md").is_file()  # what export --help cites
    out = run("calibrate", "--camera", d / "cam.txt", "--sensor", d / "imu.csv", "--sensor-kind", "gyro",
              "--bootstrap", 0, "--out", "r.json")
    assert out.returncode == 0 and "verdict: OK" in out.stdout, out.stderr
    out = run("export", "r.json", "--to", "ros2")
    assert out.returncode == 0 and "static_transform_publisher" in out.stdout, out.stderr
    out = run("fetch-data", "--check", outside / "empty")  # the manifest read offline: every file missing, none read
    assert out.returncode == 1 and "files missing or not matching the manifest" in out.stderr, out.stderr
    assert "No such file" not in out.stderr and "Traceback" not in out.stderr
