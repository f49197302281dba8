import dataclasses
import json
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from replication._io import PROJECT_ROOT
from replication.core import so3
from replication.core.so3 import random_rotations
from replication.rig.realdata import data_root, real_data_available
from replication.study import ledger
from replication.study.lab.settings import LabSettings
from replication.testing import rig_streams

#: Skips a test of where a warning points (its ``stacklevel``) under mutmut (``scripts/mutation``):
#: there every mutated function is called through a trampoline, one more stack frame, so the warning
#: points into mutmut; those mutants are listed as not judged under mutmut.
sees_stacklevel = pytest.mark.skipif("mutmut" in sys.modules,
                                     reason="mutmut's trampolines add a stack frame to every mutated function")


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def problem(rng):
    """A noise-free problem: R0, camera motions A (J=20, Haar), sensor motions B = R0^T A R0."""
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, 20)
    return R0, A, R0.T @ A @ R0


#: A small simulated lab (2 data sets of 4 poses, a 4 s dynamic trial) for the loader and chain
#: tests.
#: numpy's reprs: never in a message
NUMPY_REPR = re.compile(r"np\.(float|int|bool|str)|array\(")

SMALL_LAB = dataclasses.replace(LabSettings(), n_sets=2, poses_per_set=(4, 4), dynamic_seconds=4.0)


@pytest.fixture(scope="session")
def lab_recording(tmp_path_factory):
    """A folder written by ``write_lab`` from :data:`SMALL_LAB` (shared: do not modify, use
    ``lab_dir``)."""
    from replication.study.lab import simulate_lab, write_lab

    return write_lab(simulate_lab(SMALL_LAB), tmp_path_factory.mktemp("lab") / "rec")


@pytest.fixture
def lab_dir(lab_recording, tmp_path):
    """A private copy of :func:`lab_recording` that a test may corrupt."""
    shutil.copytree(lab_recording, tmp_path / "rec")
    return tmp_path / "rec"


def exact_problem(seed=0, J=8):
    """``(R0, A, B)``: ``J`` random camera motions and the sensor motions ``R0^T A R0`` they imply
    (no noise)."""
    rng = np.random.default_rng(seed)
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, J)
    return R0, A, np.swapaxes(R0, -1, -2) @ A @ R0


def noisy_problem(seed=2, J=30, noise_deg=0.2):
    """:func:`exact_problem` with ``noise_deg`` (deg per axis) of noise on each sensor motion."""
    from replication.core.so3 import matrix_from_rotation_vector

    rng = np.random.default_rng(seed)
    R0, A, B = exact_problem(seed, J)
    B = B @ matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal((J, 3)))
    return R0, A, B


def turning_streams(n_cam=40, dt=0.05, sensor_span=(-1.0, 3.0), rate=(0.4, 0.9, -0.3)):
    """``(camera, sensor)`` orientation streams turning at the constant ``rate`` (rad/s): ``n_cam``
    camera samples ``dt`` apart from 0, the sensor at 100 Hz over ``sensor_span``."""
    from replication.core import so3
    from replication.rig.streams import OrientationStream

    w = np.array(rate)
    tc = np.arange(n_cam) * dt
    ts = np.arange(sensor_span[0], sensor_span[1], 0.01)
    cam = OrientationStream(tc, so3.matrix_from_rotation_vector(tc[:, None] * w), "cam")
    sen = OrientationStream(ts, so3.matrix_from_rotation_vector(ts[:, None] * w), "sen")
    return cam, sen


def drift_pairs(seed, n_before=400, n_drift=1500, rate_deg=0.002, noise_deg=0.3):
    """Pairs of :func:`replication.study.live_study.pair_stream`: ``n_before`` at a random ``R0``,
    then ``n_drift`` whose ``R0`` turns ``rate_deg`` a pair about a random axis."""
    from replication.core import so3
    from replication.study.live_study import pair_stream

    rng = np.random.default_rng([seed, 7])
    R0 = so3.random_rotations(rng, ())
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    A, B = pair_stream(rng, n_before, R0, noise_deg=noise_deg)
    more = [pair_stream(rng, 1, R0 @ so3.matrix_from_rotation_vector(np.radians(rate_deg * (k + 1)) * axis),
                        noise_deg=noise_deg)
            for k in range(n_drift)]
    return np.concatenate([A] + [m[0] for m in more]), np.concatenate([B] + [m[1] for m in more])


# --------------------------------------------------------------------------------------------------
# The command line's synthetic rig as files: the rig (:func:`replication.testing.rig_streams`)
# written as a TUM trajectory and an EuRoC IMU CSV on Unix-like absolute times (1.52e9 s, the scale
# at which an overlap message once printed ``1.52053e+09..1.52053e+09``) and a Kalibr camchain;
# a run of ``python -m replication``, a snapshot of a folder's bytes, a calibration that must not be
# reached, a folder this user cannot write in, a full disk.

T0 = 1.52053e9  # absolute times, as a real recording has
MAGIC = {".png": (b"\x89PNG",), ".pdf": (b"%PDF",), ".svg": (b"<?xml", b"<svg")}


def _run(*args, cwd=None):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "replication", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


@pytest.fixture(scope="module")
def cli_rig():
    from replication.testing import rig_streams

    return rig_streams(40.0, rng=np.random.default_rng(11), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)


def _tum_bytes(camera) -> bytes:
    from replication.core import so3

    q = so3.quaternion_from_matrix(camera.R)
    rows = np.column_stack([camera.t + T0, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]])
    return "".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows).encode()


def _imu_bytes(gyro) -> bytes:
    ns = np.round(gyro.t * 1e9).astype(np.int64) + int(T0 * 1e9)
    return "".join(f"{n}," + ",".join(f"{v:.9f}" for v in (*w, 0.0, 0.0, 9.81)) + "\n"
                   for n, w in zip(ns, gyro.omega)).encode()


def _camchain_text(R0) -> str:
    T = np.eye(4)
    T[:3, :3] = R0
    return "cam0:\n  T_cam_imu:\n" + "".join(f"  - [{', '.join(f'{v:.12f}' for v in row)}]\n" for row in T)


@pytest.fixture(scope="module")
def rig_bytes(cli_rig):
    R0, camera, gyro, _ = cli_rig
    return {"cam.txt": _tum_bytes(camera), "imu.csv": _imu_bytes(gyro), "camchain.yaml": _camchain_text(R0).encode()}


@pytest.fixture
def files(tmp_path, rig_bytes):
    """A private copy of the rig's files (tests may link, chmod or replace them)."""
    d = tmp_path / "in"
    d.mkdir()
    for name, data in rig_bytes.items():
        (d / name).write_bytes(data)
    return d


def _snapshot(folder) -> dict:
    """Every file under ``folder`` (links followed) and the SHA-256 of its bytes; folders as
    ``None``."""
    import hashlib

    return {str(p.relative_to(folder)): (hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


@pytest.fixture
def no_work(monkeypatch):
    """Make the calibration fail the test if it is reached."""
    import replication.rig.calibration as cal
    import replication.rig.poses as poses

    def reached(*args, **kwargs):
        pytest.fail("the calibration ran: the check must come before any work")

    monkeypatch.setattr(cal, "calibrate", reached)
    monkeypatch.setattr(poses, "calibrate_poses", reached)


def _calibrate(files, *extra):
    from replication.cli import main

    return main(["calibrate", "--camera", str(files / "cam.txt"), "--sensor", str(files / "imu.csv"),
                 "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", *map(str, extra)])


@pytest.fixture
def locked(tmp_path):
    """A folder this user cannot write in (skipped where permissions are not enforced: root),
    restored afterwards."""
    import os

    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("folder permissions are not enforced for this user (root)")
        yield folder
    finally:
        folder.chmod(0o700)


def _disk_full(*args, **kwargs):
    import errno
    import os

    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


# --------------------------------------------------------------------------------------------------
# Real recordings and dataset files: the marker of the tests that need the shared recordings, a
# TUM trajectory's lines, EuRoC's 17-column ground truth header and a writer of its rows.

HAVE_REAL = real_data_available()

needs_real = pytest.mark.skipif(not HAVE_REAL, reason="real recordings absent: run 'python -m replication "
                                "fetch-data DEST' and set REPLICATION_REAL_DATA=DEST (or provide ../shared/data/real)")

TUM_LINES = [
    "# t tx ty tz qx qy qz qw",
    "1520530313249735680.0 0 0 0 0 0 0 1",
    "1520530313299737600.0 0 0 0 0.0087265 0 0 0.9999619",
    "1520530313349738752.0 0 0 0 0.0174524 0 0 0.9998477",
]


def write(tmp_path, name, lines):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


#: EuRoC's state_groundtruth_estimate0/data.csv header, as shipped.
GT_HEADER = ("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
             "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
             "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]")


def _line(row):
    return ",".join(str(int(v)) if i == 0 else f"{v:.9f}" for i, v in enumerate(row))


def _write(path, header, rows):
    path.write_text("\n".join([header] + [r if isinstance(r, str) else _line(r) for r in rows]) + "\n")
    return path


# --------------------------------------------------------------------------------------------------
# The ledger's claims file, and every record valid against it.

CLAIMS_CSV = Path(__file__).resolve().parents[1] / "data" / "paper" / "claims.csv"


def _valid(records):
    from replication.study import ledger, paper

    claims = paper.load_claim_table(CLAIMS_CSV)
    for rec in records:
        ledger.check_record(**rec, claims=claims, claims_path=CLAIMS_CSV)


def one_axis_rig(scale, seed, wobble=0.05, seconds=15.0, bias=(0.03, -0.02, 0.04)):
    """``(camera, gyro)``: a rig turning about the camera's z axis (1.2 rad amplitude) and rocking
    by ``wobble`` rad about the other two, camera 20 Hz (0.05 deg noise), gyro 200 Hz (0.2 deg/s)
    reading ``scale * omega + bias`` in the frame of ``replication.testing.RIG_R0`` (the motion's
    phases drawn from ``seed``): the motion that does not separate the gyro's scales."""
    from replication.core.so3 import matrix_from_rotation_vector, rotation_vector_from_matrix
    from replication.rig.streams import GyroStream, OrientationStream
    from replication.testing import RIG_R0

    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)

    def motion(t):
        v = np.stack([wobble * np.sin(0.9 * t + phase[1]), wobble * np.cos(0.5 * t + phase[2]),
                      1.2 * np.sin(0.6 * t + phase[0])], axis=-1)
        return matrix_from_rotation_vector(v)

    t_cam = np.arange(0.0, seconds, 0.05)
    noise = rng.normal(0.0, np.radians(0.05) / np.sqrt(3.0), (len(t_cam), 3))
    C = motion(t_cam) @ matrix_from_rotation_vector(noise)
    t = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = motion(t) @ RIG_R0
    omega = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    omega = omega * np.asarray(scale, float) + np.asarray(bias, float) + rng.normal(0.0, np.radians(0.2), omega.shape)
    return OrientationStream(t_cam, C, "camera"), GyroStream(0.5 * (t[1:] + t[:-1]), omega, "gyro")


# --------------------------------------------------------------------------------------------------
# The paper's simulation at 40 problems (seed 11), with its noise and without: the convexity
# study's tests (a test file's own fixture of the same name takes precedence).


@pytest.fixture(scope="module")
def noisy():
    from replication.study.simulation import simulate

    return simulate(11, 40)


@pytest.fixture(scope="module")
def clean():
    from replication.study.simulation import simulate

    return simulate(11, 40, noise_camera=0.0, noise_sensor=0.0)


# --------------------------------------------------------------------------------------------------
# The clock tests' rig: ``replication.testing``'s noisy rig (60 s, camera noise 0.05 deg, gyro noise
# 0.005 rad/s), a drift of the sensor's clock from 30 s, and calibrate without bootstrap, diagnosis
# or warnings.


def clock_rig(seed, bias=0.0):
    from replication.testing import noisy_rig

    return noisy_rig(seed, 60.0, 0.05, 0.005, bias_rad_s=bias)


def drifting(gyro, ppm):
    from replication.testing import clock_drifting

    return clock_drifting(gyro, ppm, 30.0)


def quiet_calibrate(camera, gyro, **kw):
    import warnings

    from replication.rig.calibration import calibrate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, gyro, n_bootstrap=0, diagnose=False, **kw)


def _drawn(ax) -> int:
    """The data an axes shows: lines, collections, patches, images, texts, error bars."""
    return len(ax.lines) + len(ax.collections) + len(ax.patches) + len(ax.images) + len(ax.texts) + len(ax.containers)


def _texts(fig) -> str:
    """Every text of a figure: its title, each axes' title, labels, texts, annotations and legend
    entries."""
    out = [fig.get_suptitle()] + [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()] + [t.get_text() for t in ax.texts]
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    return "\n".join(out)


#: A field of a stored claim record that :func:`_edit` deletes.
_DROP = object()


def _where(collected, claim):
    """The notebook (in the project) and the cell of claim ``claim``'s record in the ledger
    ``collected``."""
    row = collected.loc[collected["claim"] == claim].iloc[0]
    return PROJECT_ROOT / "notebooks" / f"{row.notebook}.ipynb", int(row.cell)


def _copy(path, folder, name=None):
    """A copy of the file ``path`` in ``folder`` (under ``name``, or its own)."""
    target = folder / (name or Path(path).name)
    shutil.copyfile(path, target)
    return target


def _edit(path, which, **changes):
    """Change the stored record of claim ``which`` in the notebook ``path`` (a copy); ``_DROP``
    deletes a field."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    for cell in nb["cells"]:
        for out in cell.get("outputs", []):
            rec = out.get("data", {}).get(ledger.CLAIM_MIME)
            if rec is not None and rec["claim"] == which:
                rec.update(changes)
                for key in [k for k, v in changes.items() if v is _DROP]:
                    del rec[key]
                path.write_text(json.dumps(nb, indent=1, ensure_ascii=False), encoding="utf-8")
                return
    raise AssertionError(f"no record of {which} in {path}")


def _noisy_batch(rng, n=300, J=10, noise_deg=1.0):
    """``(A, B)``: ``n`` problems of ``J`` Haar camera motions and the sensor motions they imply,
    each with up to ``noise_deg`` of noise."""
    R0 = so3.random_rotations(rng, (n,))
    A = so3.random_rotations(rng, (n, J))
    B = np.swapaxes(R0, -1, -2)[:, None] @ A @ R0[:, None]
    return A, B @ so3.random_rotations(rng, (n, J), angle_range_deg=(0.0, noise_deg))


def _one_axis_plus_one_turn(rng, J=20, turn_deg=30.0, noise_deg=0.1, second_turn_deg=0.0):
    """``J`` motions about z (10-40 deg) but the last, ``turn_deg`` about x (and, if given, the one
    before it ``second_turn_deg`` about y), with ``noise_deg`` on each side."""
    R0 = so3.matrix_from_rotation_vector(np.array([0.4, -0.3, 0.8]))
    w = np.zeros((J, 3))
    w[:, 2] = np.radians(rng.uniform(10.0, 40.0, J))
    w[-1] = np.radians([turn_deg, 0.0, 0.0])
    if second_turn_deg:
        w[-2] = np.radians([0.0, second_turn_deg, 0.0])
    B = so3.matrix_from_rotation_vector(w)
    sd = np.radians(noise_deg) / np.sqrt(3)
    A = so3.matrix_from_rotation_vector(rng.normal(0, sd, (J, 3))) @ R0 @ B @ R0.T
    return R0, A, so3.matrix_from_rotation_vector(rng.normal(0, sd, (J, 3))) @ B


#: Each rig's published calibrations, as files: the dataset's own (Kalibr), and Basalt's.
_REFERENCES = {"euroc_mh01_orbslam3": ("euroc_cam0_sensor.yaml", "openvins_euroc_kalibr_imucam_chain.yaml",
                                       "basalt_euroc_eucm_calib.json", "basalt_euroc_ds_calib.json"),
               "tumvi_room1_orbslam3mono": ("camchain.yaml", "openvins_tum_vi_kalibr_imucam_chain.yaml",
                                            "basalt_tumvi_512_eucm_calib.json", "basalt_tumvi_512_ds_calib.json")}

#: Two real reference files (Basalt's EuRoC calibration, TUM-VI's camchain) and the mark of
#: the tests that read them.
REAL = data_root() if real_data_available() else Path("/nonexistent")
BASALT = REAL / "euroc_mh01_orbslam3" / "basalt_euroc_ds_calib.json"
CAMCHAIN = REAL / "tumvi_room1_orbslam3mono" / "camchain.yaml"
needs_real_ea = pytest.mark.skipif(not (BASALT.exists() and CAMCHAIN.exists()), reason="real files not available")

#: A 4x4 transform (no rotation, a translation of 0.1, 0.2, 0.3) as an OpenCV matrix's 16 numbers.
I16 = "1.,0.,0.,0.1, 0.,1.,0.,0.2, 0.,0.,1.,0.3, 0.,0.,0.,1."


def _angle(A, B):
    """The angle between two rotations (deg)."""
    return np.degrees(np.linalg.norm(so3.rotation_vector_from_matrix(np.asarray(A) @ np.asarray(B).T)))


#: The calibration report's JSON schema (docs/calibration_report.schema.json).
SCHEMA = json.loads((Path(__file__).resolve().parents[1] / "docs" / "calibration_report.schema.json").read_text())


def _rig(seconds=60.0, phase=0.0):
    """``(camera, gyro, sensor)`` of the synthetic rig (:func:`replication.testing.rig_streams`),
    noise-free."""
    return rig_streams(seconds, phase=phase)[1:]


@pytest.fixture(scope="module")
def rig():
    """The noise-free synthetic rig of :func:`_rig`, once per test module."""
    return _rig()


def _reasons(result):
    """A result's verdict reasons by check."""
    return {r.check: r for r in result.verdict.reasons}


@pytest.fixture
def door_solver(monkeypatch):
    """``make(answer) -> name``: registers a solver whose core returns ``answer(R, call)`` (``R``
    the certified minimiser, ``call`` 0 for the calibration's own solve, then 1, 2, ... for each
    later call: the replicates)."""
    from replication.core.solvers import _registry, register, solver_info

    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    core = solver_info("chordal_optimal").core

    def make(answer):
        calls = []

        def bad(motions):
            calls.append(1)
            return answer(core(motions), len(calls) - 1)

        name = f"door_test_{len(_registry._REGISTRY)}"
        register(name, reference="test: a solver bad on some calls")(bad)
        return name

    return make


def _poses(rig, step=60):
    """Static pose sets ``(C, S)`` (``body_from_world``) taken from a rig's streams at every
    ``step``-th camera sample."""
    camera, _, sensor = rig
    return np.swapaxes(camera.R[::step], -1, -2), np.swapaxes(sensor.at(camera.t[::step]), -1, -2)


def _nan_like(R):
    """A solver's declared failure: NaN shaped like ``R``."""
    return np.full_like(R, np.nan)


def _random_rotation(R, call):
    """A rotation that is no solution: random (seeded by ``call``), batched like ``R``."""
    return so3.random_rotations(np.random.default_rng(call), 1)[0] if R.ndim == 2 else so3.random_rotations(
        np.random.default_rng(call), R.shape[0])


def _stations(rng, N=30, *, station_noise_deg=0.3, bad=None, bad_deg=3.0):
    """Static stations of a robot and a camera rigidly linked by R0 (``C_k = R0 S_k``, both
    ``body_from_world``), each station's two attitudes with independent noise (``bad``: one
    station's camera attitude turned by ``bad_deg``)."""
    R0 = so3.random_rotations(rng, ())
    W = so3.random_rotations(rng, ())  # the target's frame in the robot base's
    S = so3.random_rotations(rng, N, angle_range_deg=(5.0, 60.0))
    C = R0 @ S @ W
    sd = np.radians(station_noise_deg) / np.sqrt(3)
    C = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ C
    S = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ S
    if bad is not None:
        C[bad] = so3.matrix_from_rotation_vector(np.radians(bad_deg) * np.array([0.0, 0.6, 0.8])) @ C[bad]
    return R0, C, S


def _turned(R, deg, axis=(1.0, 0.0, 0.0)):
    """``R`` turned by ``deg`` about ``axis`` of its own frame."""
    return R @ so3.matrix_from_rotation_vector(np.radians(deg) * np.asarray(axis))


@pytest.fixture(scope="module")
def rig_tr():
    """``(R0, camera, gyro)``: a 40 s synthetic rig with camera noise (the two-reference tests)."""
    R0, camera, gyro, _ = rig_streams(40.0, rng=np.random.default_rng(35), camera_noise_deg=0.02)
    return R0, camera, gyro
