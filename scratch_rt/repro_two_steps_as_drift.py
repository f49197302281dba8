"""WRONG CAUSE: two steps of the sensor clock without a skip in its stamps (20 ms at 20 s, 30 ms at 40 s; samples lost,
stamps even) in a 60 s recording: no clock_jump; the verdict (warning) names a steady clock drift of about -1130 ppm
instead. Found on seeds 6000-6009 (10/10), confirmed on fresh seeds 6100-6119 (20/20, Wilson [0.84, 1.00]); R0
within 0.18 deg. Full counts: probe_clock.py.  Run: ../.venv/bin/python repro_two_steps_as_drift.py"""
from gen import cal, err, make
from probe_clock import gyro_step_nogap

for seed in (6100, 6101):
    camera, gyro = make(seed, seconds=60.0, bias=(0.03, -0.02, 0.04))
    r = cal(camera, gyro_step_nogap(gyro_step_nogap(gyro, 40, 30), 20, 20))
    print(seed, r.verdict.level, f"R0 error {err(r):.3f} deg", [(x.check, x.message[:120]) for x in r.verdict.reasons],
          "clock_jumps", r.to_dict()["segments"]["clock_jumps"])
