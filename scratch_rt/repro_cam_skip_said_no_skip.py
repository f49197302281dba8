"""WRONG WORDS: a 20 ms jump of the camera's clock (its stamps skip 70 ms instead of 50 ms at 30 s) is found as a
clock_jump (fail) but said to have "no skip in either clock's stamps ... (which one cannot be told from the data)",
clock "unknown": the camera's stamps do skip (less than the 1.5 median intervals the gap test needs). 10/10 (seeds
6000-6009), 20/20 fresh (6100-6119). Run: ../.venv/bin/python repro_cam_skip_said_no_skip.py"""
import numpy as np

from gen import cal, make
from probe_clock import cam_step

camera, gyro = make(6100, seconds=60.0, bias=(0.03, -0.02, 0.04))
c = cam_step(camera, 30, 20)
print("camera intervals around 30 s (ms):", np.round(1e3 * np.diff(c.t[598:602]), 1))
r = cal(c, gyro)
print(r.verdict.level, [(x.check, x.message[:260]) for x in r.verdict.reasons])
