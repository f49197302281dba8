"""Counts of the step probes with Wilson 95 % intervals. Usage: wilson.py FILE..."""
import math
import re
import sys


def wilson(k, n, z=1.96):
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


for f in sys.argv[1:]:
    lines = [x for x in open(f) if " seed " in x]
    n = len(lines)
    errs = [float(re.search(r" err ([\d.]+)", x).group(1)) for x in lines]
    counts = {
        "remount_deg named": sum("remount=True" in x for x in lines),
        "segments_disagree named": sum("segs=True" in x for x in lines),
        "fail": sum(": fail " in x for x in lines),
        "ok": sum(": ok " in x for x in lines),
        "step found at 30 +- 0.1 s": sum(bool(re.search(r"'time_s': (29\.9|30\.0|30\.05)", x)) for x in lines),
        "bias change fitted": sum("change {" in x for x in lines),
        "gyro_bias_change reason": sum("gyro_bias_change" in x for x in lines),
    }
    print(f"{f}: n {n}, R0 error max {max(errs):.3f} median {sorted(errs)[n // 2]:.3f} deg")
    for k, v in counts.items():
        lo, hi = wilson(v, n)
        print(f"    {k}: {v}/{n} [{lo:.2f}, {hi:.2f}]")
