"""Wall time of ``replication.calibrate`` on the full TUM-VI room1 recording (raw gyro), bootstrap
included.

Usage: python benchmarks/bench_calibrate.py [--data PATH] [--bootstrap 200]
Target: <= 2 s per calibration on the 2-core machine (loading the files not counted; printed apart).
Nothing is asserted; the figures go to environment.md.
"""
import argparse
import time

from replication import calibrate
from replication.rig import realdata as rd
from replication.study.notebook import best_of


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--data", help="real-data folder (default: $REPLICATION_REAL_DATA or ../shared/data/real)")
    parser.add_argument("--bootstrap", type=int, default=200)
    args = parser.parse_args()
    d = rd.data_root(args.data) / "tumvi_room1_orbslam3mono"
    start = time.perf_counter()
    camera = rd.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt")
    gyro = rd.load_euroc_imu(d / "imu0_data.csv")
    print(f"loading: {time.perf_counter() - start:.2f} s ({len(camera.t)} camera poses, {len(gyro.t)} gyro samples)")
    for method in ("chordal_optimal", "two_step_left", "two_step_right", "park_martin"):
        seconds = best_of(lambda: calibrate(camera, gyro, method=method, n_bootstrap=args.bootstrap), 3)
        print(f"calibrate({method}, {args.bootstrap} bootstrap replicates): {seconds:.2f} s")


if __name__ == "__main__":
    main()
