"""The batch change test near the ends of a recording: the share of pairs its splits leave on each
side.

``calibrate`` runs :func:`replication.rig.changepoint.two_segment_test` with ``min_share =
replication.rig.calibration.CHANGE_MIN_SHARE`` (0.05). This compares it with the test's default 0.15
on ``bench_changepoint.py``'s rigs: false alarms without a change (N rigs from seed BASE, over its 8
settings), and 2 and 5 deg re-mounts at 92 % and 95 % of 60 s rigs (20 each). Run twice with
disjoint seeds.

Run: python benchmarks/bench_change_ends.py [N] [BASE]      (defaults 160 40000; the fresh set: 160
60000)
"""
import sys
import warnings

import numpy as np
from bench_changepoint import CONFIGS, rig, rig_pairs, wilson

from replication.core import so3
from replication.rig.changepoint import two_segment_test

SHARES = (0.15, 0.05)


def main(n: int = 160, base: int = 40000):
    warnings.simplefilter("ignore")
    alarms = dict.fromkeys(SHARES, 0)
    for k in range(n):
        secs, cam, gyro_noise, bias = CONFIGS[k % len(CONFIGS)]
        A, B, t, block = rig_pairs(*rig(base + k, secs, cam, gyro_noise, bias))
        for share in SHARES:
            alarms[share] += two_segment_test(A, B, t, block=block, min_share=share).significant
    print("no change, flagged:", {share: wilson(v, n) for share, v in alarms.items()})
    axis = np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5, 0.81])
    for deg in (2.0, 5.0):
        for when in (0.92, 0.95):
            found = dict.fromkeys(SHARES, 0)
            for k in range(20):
                secs, cam, gyro_noise, bias = CONFIGS[(k % 2) + 1]
                remount = (when * secs, so3.matrix_from_rotation_vector(np.radians(deg) * axis))
                A, B, t, block = rig_pairs(*rig(base + 5000 + k, secs, cam, gyro_noise, bias, remount=remount))
                for share in SHARES:
                    found[share] += two_segment_test(A, B, t, block=block, min_share=share).significant
            print(f"re-mount {deg:g} deg at {100 * when:g} % of the recording: detected (of 20)", found)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
