"""WRONG CAUSE (sometimes): a sensor clock drifting 500 ppm that stops at 30 s (a kink in the offset, no step) is named a
clock_jump (fail, a step of ~12 ms) in 1/10 (seeds 6000-6009) and 4/20 (fresh 6100-6119): 5/30, Wilson [0.07, 0.34];
otherwise a clock_drift warning of ~245 ppm (the recording's mean drift; the kink itself is not said).
Run: ../.venv/bin/python repro_drift_stop_as_step.py"""
from gen import cal, err, make
from probe_clock import drift_stops

for seed in range(6100, 6120):
    camera, gyro = make(seed, seconds=60.0, bias=(0.03, -0.02, 0.04))
    r = cal(camera, drift_stops(gyro, 500, 30, 60.0))
    jumps = r.to_dict()["segments"]["clock_jumps"]
    if jumps:
        print(seed, r.verdict.level, f"R0 error {err(r):.3f}", [(x.check, x.message[:160]) for x in r.verdict.reasons])
