"""Per-sample cost of LiveRig.add_gyro (no camera: the correction and the integration only)."""
import time
import numpy as np
from replication.rig.live import LiveRig
from replication.rig.online import OnlineCalibrator
best = np.inf
w = np.random.default_rng(0).normal(0, 0.5, (20000, 3))
for _ in range(5):
    rig = LiveRig(OnlineCalibrator(), gyro_bias=False)
    rig._Ti = ((1.01, 0.01, 0.0), (0.01, 0.99, 0.02), (0.0, 0.02, 1.0)) if hasattr(rig, "_Ti") else None
    if not hasattr(rig, "_Ti"):
        rig._s = (1.01, 0.99, 1.0)
    t0 = time.perf_counter()
    for k in range(20000):
        rig.add_gyro(0.005 * k, w[k])
    best = min(best, (time.perf_counter() - t0) / 20000 * 1e6)
print(f"add_gyro: {best:.2f} us per sample (best of 5, 20000 samples)")
