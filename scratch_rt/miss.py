import sys
import numpy as np
sys.path.insert(0, ".")
from bench_clock import case
for s in range(int(sys.argv[2]), int(sys.argv[3])):
    r = case(sys.argv[1], s)
    if not r.segments["clock_jumps"]:
        p = r.segments["clock_profile"]
        print(s, np.round(1e3 * np.array(p["offset_s"]), 1).tolist(), np.round(1e3 * np.array(p["se_s"]), 1).tolist(),
              {k: round(v, 1) for k, v in p["chi2"].items()}, round(p["scale"], 1), flush=True)
