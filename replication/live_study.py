"""The studies of ``notebooks/08_online.ipynb``: the online estimator's radius coverage in simulation, live replays
of the real recordings beside VINS-Mono's initialiser rule, and re-mount detection.

Every replay feeds :class:`replication.live.LiveRig` the recorded streams in time order; VINS-Mono's rule
(:class:`replication.vins_rule.VinsExRotation`) gets exactly the same pairs.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .live import replay
from .online import OnlineCalibrator
from .so3 import angle_between_deg, exp_map
from .stats import proportion_ci
from .vins_rule import VinsExRotation

__all__ = ["coverage_study", "live_run", "ready_table", "remount_study", "update_costs", "REMOUNT_AXIS"]

#: Axis of the synthetic re-mounts (a generic direction, in the sensor frame).
REMOUNT_AXIS = np.array([0.6, 0.0, 0.8])


def coverage_study(settings: dict, *, n_runs: int, n_pairs: int, checkpoints, seed: int, level: float = 0.95):
    """Share of checks where the true error is within the stated radius, per simulation setting.

    ``settings``: ``{label: overrides of replication.simulation.simulate}`` (noise, motions). Each run feeds
    ``n_pairs`` pairs one by one to a fresh :class:`~replication.online.OnlineCalibrator` (change detector off)
    and checks at each of ``checkpoints``.

    Returns
    -------
    pandas.DataFrame
        Index the setting; ``checks``, ``covered`` (share), ``covered low`` / ``covered high`` (its 95 % Wilson
        interval, :func:`replication.stats.proportion_ci`), and the median radius and error at the last checkpoint.
    """
    from .simulation import simulate

    rows = {}
    for k, (label, overrides) in enumerate(settings.items()):
        sim = simulate(seed + k, n_runs, n_motions=n_pairs, **overrides)
        hits, radius, error = [], [], []
        for run in range(n_runs):
            oc = OnlineCalibrator(level=level, cusum_h=1e12)
            for j, state in enumerate(oc.update_many(sim.A[run], sim.B[run]), 1):
                if j in checkpoints:
                    err = float(angle_between_deg(state.R, sim.R0[run]))
                    hits.append(err <= state.radius_deg)
                    if j == max(checkpoints):
                        radius.append(state.radius_deg)
                        error.append(err)
        low, high = proportion_ci(int(np.sum(hits)), len(hits))
        rows[label] = {"checks": len(hits), "covered": float(np.mean(hits)), "covered low": low, "covered high": high,
                       "median radius (deg)": float(np.median(radius)), "median error (deg)": float(np.median(error))}
    out = pd.DataFrame(rows).T
    out.index.name = "setting"
    return out


def live_run(camera, sensor, reference, *, interval: float = 1.0, remount=None, **calibrator_options):
    """One replay as if live, with VINS-Mono's rule fed the same pairs.

    Returns
    -------
    (track, vins) : (pandas.DataFrame, dict)
        ``track``: :func:`replication.live.replay`'s rows with ``t`` since the camera's first sample;
        ``vins``: ``ready_t`` (s since the start, or NaN), ``ready_pairs`` and ``error_at_ready_deg`` (the angle of
        its estimate to the reference when it declared success), ``final_error_deg``.
    """
    vins = VinsExRotation()
    trace = {"ready_t": np.nan, "ready_pairs": np.nan, "error_at_ready_deg": np.nan}

    def feed(t, A, B):
        vins.update(A, B)
        if vins.ready and np.isnan(trace["ready_t"]):
            trace.update(ready_t=t - camera.t[0], ready_pairs=vins.ready_at + 1,
                         error_at_ready_deg=float(angle_between_deg(vins.R, reference)))

    calibrator = OnlineCalibrator(**calibrator_options)
    track = replay(camera, sensor, calibrator, interval=interval, reference=reference, remount=remount, on_pair=feed)
    track["t"] = track["t"] - camera.t[0]
    trace["final_error_deg"] = float(angle_between_deg(vins.R, reference)) if remount is None else np.nan
    return track, trace


def ready_table(runs: dict, targets) -> pd.DataFrame:
    """When each estimator declares itself ready and how far off it is then.

    ``runs``: ``{recording: (track, vins)}`` from :func:`live_run` (with ``target_deg`` the smallest target).
    Ours is ready at a target when its radius first falls below it; VINS-Mono's rule when it first declares
    success (its own rule: 10 pairs and the second-smallest singular value above 0.25).
    """
    rows = []
    for name, (track, vins) in runs.items():
        for target in targets:
            ok = track[(track["n_pairs"] >= 10) & (track["radius_deg"] < target)]
            first = ok.iloc[0] if len(ok) else None
            rows.append({"recording": name, "estimator": f"ours, radius < {target:g} deg",
                         "ready at (s)": np.nan if first is None else first["t"],
                         "pairs": np.nan if first is None else first["n_pairs"],
                         "stated radius (deg)": np.nan if first is None else first["radius_deg"],
                         "error then (deg)": np.nan if first is None else first["error_deg"]})
        rows.append({"recording": name, "estimator": "VINS-Mono rule", "ready at (s)": vins["ready_t"],
                     "pairs": vins["ready_pairs"], "stated radius (deg)": np.nan,
                     "error then (deg)": vins["error_at_ready_deg"]})
        rows.append({"recording": name, "estimator": "ours, at the end", "ready at (s)": track["t"].iloc[-1],
                     "pairs": track["n_pairs"].iloc[-1], "stated radius (deg)": track["radius_deg"].iloc[-1],
                     "error then (deg)": track["error_deg"].iloc[-1]})
    return pd.DataFrame(rows).set_index(["recording", "estimator"])


def remount_study(recordings: dict, *, steps_deg, thresholds, interval: float = 1.0) -> pd.DataFrame:
    """Re-mount detection on the real recordings, per CUSUM threshold ``h``.

    ``recordings``: ``{name: (camera, sensor, reference)}``. For each threshold: the replay as recorded (its
    alarms are false alarms: nothing was re-mounted), and with a synthetic re-mount of each of ``steps_deg``
    about :data:`REMOUNT_AXIS` at mid-recording (detection delay: the first alarm after it).

    Returns
    -------
    pandas.DataFrame
        Index ``(recording, h)``; ``false alarms`` (count), ``false alarms per hour``, and per step
        ``delay <s> deg (s)`` (NaN: not detected) and ``error after <s> deg (deg)`` (at the end, to the re-mounted
        reference).
    """
    rows = []
    for name, (camera, sensor, reference) in recordings.items():
        hours = (camera.t[-1] - camera.t[0]) / 3600.0
        mid = camera.t[0] + 0.5 * (camera.t[-1] - camera.t[0])
        for h in thresholds:
            track, _ = live_run(camera, sensor, reference, interval=interval, cusum_h=h)
            row = {"recording": name, "h": h, "false alarms": int(track["alarm"].sum()),
                   "false alarms per hour": track["alarm"].sum() / hours}
            for step in steps_deg:
                R = exp_map(np.radians(step) * REMOUNT_AXIS)
                track, _ = live_run(camera, sensor, reference, interval=interval, cusum_h=h, remount=(mid, R))
                after = track[(track["alarm"]) & (track["t"] >= mid - camera.t[0])]
                row[f"delay {step:g} deg (s)"] = after["t"].iloc[0] - (mid - camera.t[0]) if len(after) else np.nan
                row[f"error after {step:g} deg (deg)"] = track["error_deg"].iloc[-1]
            rows.append(row)
    return pd.DataFrame(rows).set_index(["recording", "h"])


def update_costs(n_pairs: int = 2000, *, seed: int = 0) -> dict:
    """Per-pair cost of :meth:`~replication.online.OnlineCalibrator.update` on one simulated problem: the median
    and 99th percentile of single updates (µs), and the replay rate of :meth:`update_many` (pairs/s)."""
    import time

    from .simulation import simulate

    sim = simulate(seed, 1, n_motions=n_pairs)
    A, B = sim.A[0], sim.B[0]
    OnlineCalibrator(cusum_h=1e12).update_many(A, B)  # warm-up: every code path once
    oc, times = OnlineCalibrator(cusum_h=1e12), []
    for a, b in zip(A, B):
        start = time.perf_counter()
        oc.update(a, b)
        times.append(time.perf_counter() - start)
    start = time.perf_counter()
    OnlineCalibrator(cusum_h=1e12).update_many(A, B)
    replay_s = time.perf_counter() - start
    times = 1e6 * np.array(times)
    return {"median_us": float(np.median(times)), "p99_us": float(np.percentile(times, 99)),
            "replay_pairs_per_s": n_pairs / replay_s}
