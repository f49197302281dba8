"""RT6: perturbed real recordings through the command line, as a user runs it. TUM-VI room1:
ORB-SLAM3 mono cam0 trajectory + raw imu0 gyro, reference Kalibr camchain (floor 0.343 deg used as
the lie line; TUM-VI's own references agree to 0.034). Each case writes its files in /tmp/rt6 and
runs `python -m replication calibrate ... --bootstrap 50 --out` and reads the JSON report.
Usage: real_perturb.py [CASE ...]"""
import json
import os
import subprocess
import sys

import numpy as np

from common import exp_map

D = os.environ.get("REPLICATION_REAL_DATA", "/work/shared/data/real") + "/tumvi_room1_orbslam3mono"
CAM, GYRO, REF = D + "/orbslam3_mono_cam0_traj.txt", D + "/imu0_data.csv", D + "/camchain.yaml"
TMP = "/tmp/segcause"
PY = "/work/wt-segcause/.venv/bin/python"
os.makedirs(TMP, exist_ok=True)


def read_cam():
    a = np.loadtxt(CAM)
    return a


def write_cam(a, name):
    p = f"{TMP}/{name}.txt"
    with open(p, "w") as f:
        for r in a:
            f.write(f"{r[0]:.6f} " + " ".join(f"{x:.9f}" for x in r[1:]) + "\n")
    return p


def read_gyro():
    with open(GYRO) as f:
        head = f.readline()
    a = np.loadtxt(GYRO, delimiter=",", skiprows=1, dtype=np.float64)
    t = np.loadtxt(GYRO, delimiter=",", skiprows=1, usecols=0, dtype=np.int64)
    return head, t, a


def write_gyro(head, t, a, name):
    p = f"{TMP}/{name}.csv"
    with open(p, "w") as f:
        f.write(head)
        for ti, r in zip(t, a):
            f.write(f"{ti}," + ",".join(f"{x:.10f}" for x in r[1:]) + "\n")
    return p


def quat_xyzw_to_R(q):
    from scipy.spatial.transform import Rotation
    return Rotation.from_quat(q).as_matrix()


def R_to_quat_xyzw(R):
    from scipy.spatial.transform import Rotation
    return Rotation.from_matrix(R).as_quat()


def run(cam, gyro, name, extra=()):
    out = f"{TMP}/{name}.json"
    cmd = [PY, "-m", "replication", "calibrate", "--camera", cam, "--sensor", gyro, "--sensor-kind", "gyro",
           "--reference", REF, "--bootstrap", "50", "--out", out, "--accept", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 3):
        print(f"{name}: rc {p.returncode}: {p.stderr[-600:]}")
        return None
    r = json.load(open(out))
    v = r["verdict"]
    ang = r.get("reference", {}).get("angle_deg") if isinstance(r.get("reference"), dict) else None
    txt = p.stdout
    line = [x for x in txt.splitlines() if x.startswith("angle to the reference")]
    rad = [x for x in txt.splitlines() if x.startswith("bootstrap 95% radius")]
    print(f"{name}: verdict {v['level']}; {line[0] if line else ang}; {rad[0][:40] if rad else ''}; reasons "
          f"{[(x['check'], x['level']) for x in v['reasons']]}", flush=True)
    for x in v["reasons"]:
        print(f"    {x['level']}: {x.get('message', x)[:400]}")
    return r


def t_s(a):
    return (a[:, 0] - a[0, 0]) * 1e-9


def world_jump(deg, at):  # the SLAM map re-initialised: every pose after `at` s in another world frame
    a = read_cam()
    W = exp_map(np.radians(deg) * np.array([0.3, 0.9, 0.3]) / np.linalg.norm([0.3, 0.9, 0.3]))
    m = t_s(a) > at
    R = quat_xyzw_to_R(a[m, 4:8])
    a[m, 4:8] = R_to_quat_xyzw(W @ R)
    return a


def cam_gap(t0, t1):
    a = read_cam()
    s = t_s(a)
    return a[(s < t0) | (s > t1)]


def world_wander(deg, t0, t1):  # the map's frame wanders by `deg` over [t0, t1] then snaps back (loop closure)
    a = read_cam()
    s = t_s(a)
    m = (s > t0) & (s < t1)
    f = (s[m] - t0) / (t1 - t0)
    ax = np.array([1.0, 0.2, -0.4]) / np.linalg.norm([1.0, 0.2, -0.4])
    Wm = exp_map(np.radians(deg) * f[:, None] * ax)
    a[m, 4:8] = R_to_quat_xyzw(Wm @ quat_xyzw_to_R(a[m, 4:8]))
    return a


def cam_clock_step(ms, at):
    a = read_cam()
    s = t_s(a)
    a[s > at, 0] += ms * 1e6
    return a


def cam_noisy(deg, t0, t1, seed=0):
    rng = np.random.default_rng(seed)
    a = read_cam()
    s = t_s(a)
    m = (s > t0) & (s < t1)
    a[m, 4:8] = R_to_quat_xyzw(quat_xyzw_to_R(a[m, 4:8]) @ exp_map(rng.normal(0, np.radians(deg) / np.sqrt(3),
                                                                                  (m.sum(), 3))))
    return a


def gyro_edit(fn, name):
    head, t, a = read_gyro()
    s = (t - t[0]) * 1e-9
    a[:, 1:4] = fn(s, a[:, 1:4])
    return write_gyro(head, t, a, name)


CASES = {
    "base": lambda: run(CAM, GYRO, "base"),
    "jump30@60": lambda: run(write_cam(world_jump(30, 60), "jump30"), GYRO, "jump30@60"),
    "jump5@60": lambda: run(write_cam(world_jump(5, 60), "jump5"), GYRO, "jump5@60"),
    "jump90@60": lambda: run(write_cam(world_jump(90, 60), "jump90"), GYRO, "jump90@60"),
    "gap10s@60": lambda: run(write_cam(cam_gap(60, 70), "gap10"), GYRO, "gap10s@60"),
    "gap0.3s+jump30": lambda: run(write_cam(world_jump(30, 60)[np.abs(t_s(read_cam()) - 60.15) > 0.15],
                                            "gapjump"), GYRO, "gap0.3s+jump30"),
    "wander3deg 40-70": lambda: run(write_cam(world_wander(3, 40, 70), "wander3"), GYRO, "wander3deg 40-70"),
    "wander1deg 40-70": lambda: run(write_cam(world_wander(1, 40, 70), "wander1"), GYRO, "wander1deg 40-70"),
    "noisy2deg 50-65": lambda: run(write_cam(cam_noisy(2, 50, 65), "noisy2"), GYRO, "noisy2deg 50-65"),
    "camclock+30ms@60": lambda: run(write_cam(cam_clock_step(30, 60), "camstep"), GYRO, "camclock+30ms@60"),
    "gyro bias ramp 0.02": lambda: run(CAM, gyro_edit(lambda s, w: w + (s / s[-1])[:, None] * [0.02, -0.015, 0.01],
                                                      "biasramp"), "gyro bias ramp 0.02"),
    "gyro bias ramp 0.05": lambda: run(CAM, gyro_edit(lambda s, w: w + (s / s[-1])[:, None] * [0.05, -0.04, 0.03],
                                                      "biasramp5"), "gyro bias ramp 0.05"),
    "gyro bias step 0.03@60": lambda: run(CAM, gyro_edit(lambda s, w: w + (s > 60)[:, None] * [0.03, -0.02, 0.02],
                                                         "biasstep"), "gyro bias step 0.03@60"),
    "gyro sym misalign 1%": lambda: run(CAM, gyro_edit(lambda s, w: w @ np.array([[1, .01, 0], [.01, 1, .01],
                                                                                  [0, .01, 1]]).T, "mis1"),
                                        "gyro sym misalign 1%"),
    "gyro misalign 3% xy": lambda: run(CAM, gyro_edit(lambda s, w: w @ np.array([[1, .03, 0], [0, 1, 0],
                                                                                 [0, 0, 1]]).T, "mis3"),
                                       "gyro misalign 3% xy"),
}



def multi_jump(deg, times):
    a = read_cam()
    s = t_s(a)
    for k, at in enumerate(times):
        ax = np.array([np.cos(k), np.sin(k), 0.5])
        W = exp_map(np.radians(deg) * ax / np.linalg.norm(ax))
        m = s > at
        a[m, 4:8] = R_to_quat_xyzw(W @ quat_xyzw_to_R(a[m, 4:8]))
    return a


CASES["6 jumps 90deg"] = lambda: run(write_cam(multi_jump(90, [20, 40, 60, 80, 100, 120]), "mj90"), GYRO, "6 jumps 90deg")
CASES["6 jumps 20deg"] = lambda: run(write_cam(multi_jump(20, [20, 40, 60, 80, 100, 120]), "mj20"), GYRO, "6 jumps 20deg")
CASES["consistent jump30"] = lambda: run(write_cam(world_jump(30, 60), "jump30"), GYRO, "consistent jump30",
                                         ("--use", "consistent"))


CASES["gyro Tg upper 0.74% x3"] = lambda: run(CAM, gyro_edit(lambda s, w: w @ (np.eye(3) + 0.0074 * np.triu(np.ones((3, 3)), 1)).T,
                                                          "tgu74"), "gyro Tg upper 0.74% x3")
CASES["gyro sym misalign 1.5% online"] = lambda: run(CAM, gyro_edit(lambda s, w: w @ (np.eye(3) + 0.015 * (
    np.ones((3, 3)) - np.eye(3))).T, "mis15"), "gyro sym misalign 1.5% online", ("--online", "--track", f"{TMP}/track_mis15.csv"))

CASES["consistent bias step"] = lambda: run(CAM, gyro_edit(lambda s, w: w + (s > 60)[:, None] * [0.03, -0.02, 0.02],
                                                           "biasstep"), "consistent bias step", ("--use", "consistent"))
CASES["consistent bias ramp 0.05"] = lambda: run(CAM, gyro_edit(
    lambda s, w: w + (s / s[-1])[:, None] * [0.05, -0.04, 0.03], "biasramp5"), "consistent bias ramp 0.05",
    ("--use", "consistent"))


if __name__ == "__main__":
    for name in sys.argv[1:] or list(CASES):
        CASES[name]()
