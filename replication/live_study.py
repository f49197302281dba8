"""The studies of ``notebooks/08_online.ipynb``: the online estimator's radius coverage in simulation, live replays
of the real recordings beside VINS-Mono's initialiser rule, and re-mount detection.

Every replay feeds :class:`replication.live.LiveRig` the recorded streams in time order; VINS-Mono's rule
(:class:`replication.vins_rule.VinsExRotation`) gets exactly the same pairs.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .live import replay
from .online import MIN_PAIRS, OnlineCalibrator
from .so3 import angle_between_deg, exp_map
from .stats import mean_se
from .vins_rule import VinsExRotation

__all__ = ["coverage_study", "live_run", "ready_table", "remount_study", "update_costs", "REMOUNT_AXIS"]

#: Axis of the synthetic re-mounts (a generic direction, in the sensor frame).
REMOUNT_AXIS = np.array([0.6, 0.0, 0.8])


def coverage_study(settings: dict, *, n_runs: int, n_pairs: int, checkpoints, seed: int, level: float = 0.95,
                   **calibrator_options):
    """Share of checks where the true error is within the stated radius, per simulation setting.

    ``settings``: ``{label: overrides of replication.simulation.simulate}`` (noise, motions). Each run feeds
    ``n_pairs`` pairs one by one to a fresh :class:`~replication.online.OnlineCalibrator` (change detector off)
    (with ``calibrator_options``, e.g. ``forgetting``) and checks at each of ``checkpoints``.

    Returns
    -------
    pandas.DataFrame
        Index the setting; ``checks``, ``covered`` (share), ``covered low`` / ``covered high`` (its 95 % interval,
        ``mean +- 1.96 SE`` over the runs: the checks within one run are correlated, the runs are independent), and
        the median radius and error at the last checkpoint.
    """
    from .simulation import simulate

    rows = {}
    for k, (label, overrides) in enumerate(settings.items()):
        sim = simulate(seed + k, n_runs, n_motions=n_pairs, **overrides)
        hits, radius, error = [], [], []
        for run in range(n_runs):
            oc = OnlineCalibrator(level=level, cusum_h=1e12, **calibrator_options)
            hits.append([])
            for j, state in enumerate(oc.update_many(sim.A[run], sim.B[run]), 1):
                if j in checkpoints:
                    err = float(angle_between_deg(state.R, sim.R0[run]))
                    hits[-1].append(err <= state.radius_deg)
                    if j == max(checkpoints):
                        radius.append(state.radius_deg)
                        error.append(err)
        share, se = mean_se(np.mean(hits, axis=1))
        rows[label] = {"checks": int(np.size(hits)), "covered": share, "covered low": share - 1.96 * se,
                       "covered high": share + 1.96 * se,
                       "median radius (deg)": float(np.median(radius)), "median error (deg)": float(np.median(error))}
    out = pd.DataFrame(rows).T
    out.index.name = "setting"
    return out


def live_run(camera, sensor, reference, *, interval: float = 1.0, remount=None, vins_rule: bool = True,
             **calibrator_options):
    """One replay as if live, with VINS-Mono's rule fed the same pairs.

    Returns
    -------
    (track, vins) : (pandas.DataFrame, dict)
        ``track``: :func:`replication.live.replay`'s rows with ``t`` and ``t_seen`` since the camera's first sample,
        and ``vins_error_deg`` (the rule's error after the same pairs);
        ``vins``: ``ready_t`` (s since the start, when the pair that made it declare success was formed, or NaN),
        ``ready_pairs`` and ``error_at_ready_deg``.
    """
    vins = VinsExRotation()
    errors = []

    def feed(t, A, B):
        vins.update(A, B)
        errors.append(float(angle_between_deg(vins.R, reference)))

    track = replay(camera, sensor, OnlineCalibrator(**calibrator_options), interval=interval, reference=reference,
                   remount=remount, on_pair=feed if vins_rule else None)
    track["t"] = track["t"] - camera.t[0]
    track["t_seen"] = track["t_seen"] - camera.t[0]
    trace = {"ready_t": np.nan, "ready_pairs": np.nan, "error_at_ready_deg": np.nan}
    if vins_rule:
        track["vins_error_deg"] = errors
        if vins.ready:
            trace.update(ready_t=track["t_seen"].iloc[vins.ready_at], ready_pairs=vins.ready_at + 1,
                         error_at_ready_deg=errors[vins.ready_at])
    return track, trace


def ready_table(runs: dict, targets) -> pd.DataFrame:
    """When each estimator declares itself ready, how far off it is then, and how far off the other one is after
    the same pairs (the fair comparison: both have seen the same data).

    ``runs``: ``{recording: (track, vins)}`` from :func:`live_run`. Ours is ready at a target when its radius
    first falls below it (from :data:`~replication.online.MIN_PAIRS` pairs on); VINS-Mono's rule when it first
    declares success (its own rule: 10 pairs and the second-smallest singular value above 0.25). Times are when
    the deciding pair was formed (the first pairs wait for the clock-offset window).
    """
    rows = []
    for name, (track, vins) in runs.items():
        def row(estimator, k, radius=np.nan, own="error_deg", other="vins_error_deg"):
            if k is None:
                return {"recording": name, "estimator": estimator}
            r = track.iloc[k]
            return {"recording": name, "estimator": estimator, "ready at (s)": r["t_seen"], "pairs": k + 1,
                    "stated radius (deg)": radius, "error then (deg)": r[own], "the other's error then (deg)": r[other]}

        for target in targets:
            ok = np.flatnonzero((track["n_pairs"] >= MIN_PAIRS) & (track["radius_deg"] < target))
            k = int(ok[0]) if len(ok) else None
            rows.append(row(f"ours, radius < {target:g} deg", k, np.nan if k is None else track["radius_deg"].iloc[k]))
        k = None if np.isnan(vins["ready_pairs"]) else int(vins["ready_pairs"]) - 1
        rows.append(row("VINS-Mono rule", k, own="vins_error_deg", other="error_deg"))
        rows.append(row("ours, at the end", len(track) - 1, track["radius_deg"].iloc[-1]))
    return pd.DataFrame(rows).set_index(["recording", "estimator"])


def remount_study(recordings: dict, *, steps_deg, when=(1 / 3, 1 / 2, 2 / 3), axes=None, threshold: float = 30.0,
                  interval: float = 1.0, wrong_deg: float = 1.0) -> pd.DataFrame:
    """Re-mount detection on the real recordings: synthetic re-mounts of each size, at several times and about
    several axes, and the recording as recorded (any alarm there is false: nothing was re-mounted).

    Returns
    -------
    pandas.DataFrame
        Index ``(recording, re-mount (deg))``; ``detected`` (count of the re-mounts caught), ``of``, ``median
        delay (s)`` and ``max delay (s)`` over those caught (from the re-mount to the pair that raised the alarm),
        ``ready but wrong at the end`` (replays that end ``ready`` more than ``wrong_deg`` from the re-mounted
        reference: a missed re-mount the radius cannot see), ``alarms before the re-mount`` (false, summed over the
        replays), and ``false alarms as recorded`` and per hour (the replay without a re-mount; a property of the
        recording, repeated on its rows).
    """
    axes = [REMOUNT_AXIS, np.array([0.0, 0.0, 1.0])] if axes is None else axes
    rows = []
    for name, (camera, sensor, reference) in recordings.items():
        span = camera.t[-1] - camera.t[0]
        track, _ = live_run(camera, sensor, reference, interval=interval, vins_rule=False, cusum_h=threshold)
        false = int(track["alarm"].sum())
        for step in steps_deg:
            delays, wrong, early = [], 0, 0
            for share in when:
                for axis in axes:
                    t_re = share * span
                    R = exp_map(np.radians(step) * np.asarray(axis) / np.linalg.norm(axis))
                    tr, _ = live_run(camera, sensor, reference, interval=interval, vins_rule=False, cusum_h=threshold,
                                     remount=(camera.t[0] + t_re, R))
                    alarms = tr.loc[tr["alarm"], "t_seen"]
                    early += int((alarms < t_re).sum())
                    after = alarms[alarms >= t_re]
                    delays.append(after.iloc[0] - t_re if len(after) else np.nan)
                    wrong += bool(tr["ready"].iloc[-1] and tr["error_deg"].iloc[-1] > wrong_deg)
            d = np.array(delays)
            rows.append({"recording": name, "re-mount (deg)": step, "detected": int(np.isfinite(d).sum()), "of": len(d),
                         "median delay (s)": np.nanmedian(d) if np.isfinite(d).any() else np.nan,
                         "max delay (s)": np.nanmax(d) if np.isfinite(d).any() else np.nan,
                         "ready but wrong at the end": wrong, "alarms before the re-mount": early,
                         "false alarms as recorded": false, "false alarms per hour as recorded": false / span * 3600.0})
    return pd.DataFrame(rows).set_index(["recording", "re-mount (deg)"])


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
