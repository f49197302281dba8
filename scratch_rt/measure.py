"""Round-3 clock cases: counts per case over seeds (Wilson 95 %). Run: ../.venv/bin/python measure.py CASE BASE N"""
import sys
from gen import W, cal, err, make
from probe_clock import cam_step, drift_stops, gyro_step_nogap

case, base, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
hit = 0
for seed in range(base, base + n):
    camera, gyro = make(seed, seconds=60.0, bias=(0.03, -0.02, 0.04))
    if case == "two":
        r = cal(camera, gyro_step_nogap(gyro_step_nogap(gyro, 40, 30), 20, 20), n_bootstrap=0)
    elif case == "cam20":
        r = cal(cam_step(camera, 30, 20), gyro, n_bootstrap=0)
    elif case == "stop":
        r = cal(camera, drift_stops(gyro, 500, 30, 60.0), n_bootstrap=0)
    checks = {x.check: x for x in r.verdict.reasons}
    jumps = r.to_dict()["segments"]["clock_jumps"]
    if case == "two":
        ok = len(jumps) == 2 and abs(jumps[0]["time_s"] - 20) <= jumps[0]["time_resolution_s"] and abs(
            jumps[1]["time_s"] - 40) <= jumps[1]["time_resolution_s"] and abs(jumps[0]["size_s"] + 0.02) < 0.003 and abs(
            jumps[1]["size_s"] + 0.03) < 0.003 and "clock_drift" not in checks
    elif case == "cam20":
        ok = len(jumps) == 1 and jumps[0]["clock"] == "camera" and "camera's stamps skip" in checks["clock_jump"].message
    else:
        ok = not jumps
    hit += ok
    print(seed, r.verdict.level, sorted(checks), [(round(j["time_s"], 1), round(1e3 * j["size_s"], 1), j["clock"])
                                                  for j in jumps], f"R0 err {err(r):.3f}", "OK" if ok else "BAD",
          flush=True)
print(case, base, n, "right:", W(hit, n))
