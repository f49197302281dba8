"""The studies of ``notebooks/08_online.ipynb``: the online estimator's radius coverage (at every
pair and at the moment it says ready), its ``ready`` on streams that do not determine ``R0`` and on
the usual input mistakes, its events over long simulated streams (false re-mounts per hour, outlier
bursts, noise jumps, detection of re-mounts of each size), live replays of the real recordings
beside VINS-Mono's initialiser rule, and the cost per pair.

Every replay feeds :class:`replication.rig.live.LiveRig` the recorded streams in time order;
VINS-Mono's rule (:class:`replication.study.vins_rule.VinsExRotation`) gets exactly the same pairs.
Simulated pair streams come from :func:`pair_stream`, simulated rigs from
:func:`replication.testing.rig_streams`.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..core.so3 import angle_between_deg, matrix_from_rotation_vector, random_rotations
from ..core.stats import mean_se, poisson_upper, wilson_interval
from ..rig.live import replay
from ..rig.online import MIN_PAIRS, OnlineCalibrator
from ..rig.online_events import EVENT_KINDS
from .vins_rule import VinsExRotation

__all__ = ["coverage_study", "ready_coverage", "pair_stream", "degenerate_streams", "online_mistakes",
           "event_rates", "detection_study", "live_run", "ready_table", "remount_study", "update_costs",
           "REMOUNT_AXIS"]

#: Axis of the synthetic re-mounts (a generic direction, in the sensor frame).
REMOUNT_AXIS = np.array([0.6, 0.0, 0.8])


def pair_stream(rng: np.random.Generator, n: int, R0, *, noise_deg: float = 0.2, motion_deg=(5.0, 60.0), axis=None):
    """``n`` independent motion pairs of a rig with ``camera_from_sensor = R0``: camera motions
    about uniform axes (or ``axis``) with angles uniform in ``motion_deg``, sensor motions ``R0^T A
    R0``, and isotropic Gaussian rotation-vector noise of RMS ``noise_deg / sqrt(2)`` on each side
    (so the pair residual's RMS is ``noise_deg``).

    Returns ``(A, B)``, each ``(n, 3, 3)``.
    """
    w = rng.normal(size=(n, 3)) if axis is None else np.tile(np.asarray(axis, dtype=float), (n, 1))
    w *= (np.radians(rng.uniform(*motion_deg, n)) / np.linalg.norm(w, axis=1))[:, None]
    A = matrix_from_rotation_vector(w)
    B = np.swapaxes(R0, -1, -2) @ A @ R0
    if noise_deg:
        sd = np.radians(noise_deg) / np.sqrt(6.0)
        A = matrix_from_rotation_vector(rng.normal(0.0, sd, (n, 3))) @ A
        B = matrix_from_rotation_vector(rng.normal(0.0, sd, (n, 3))) @ B
    return A, B


def _with_interval(k: int, n: int) -> dict:
    low, high = wilson_interval(k, n)
    return {"share": k / n, "share low": low, "share high": high}


def coverage_study(settings: dict, *, n_runs: int, n_pairs: int, checkpoints, seed: int, level: float = 0.95,
                   **calibrator_options):
    """Share of checks where the true error is within the stated radius, per simulation setting.

    ``settings``: ``{label: overrides of replication.study.simulation.simulate}`` (noise, motions).
    Each run feeds ``n_pairs`` pairs one by one to a fresh
    :class:`~replication.rig.online.OnlineCalibrator` (change detector off) (with
    ``calibrator_options``, e.g. ``forgetting``) and checks at each of ``checkpoints``.

    Returns
    -------
    pandas.DataFrame
        Index the setting; ``checks``, ``covered`` (share), ``covered low`` / ``covered high`` (its
        95 % interval, ``mean +- 1.96 SE`` over the runs: the checks within one run are correlated,
        the runs are independent), and the median radius and error at the last checkpoint.
    """
    from .simulation import simulate

    rows = {}
    for k, (label, overrides) in enumerate(settings.items()):
        sim = simulate(seed + k, n_runs, n_motions=n_pairs, **overrides)
        hits, radius, error = [], [], []
        for run in range(n_runs):
            oc = OnlineCalibrator(level=level, cusum_h=1e12, drift_pairs=10 ** 9, **calibrator_options)
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


def ready_coverage(settings: dict, *, n_runs: int, n_pairs: int, seed: int, target_deg: float = 0.5):
    """Coverage of the radius at the moment the estimator first says ``ready`` (one check per run:
    the runs are independent, so the share has a binomial (Wilson) interval).

    ``settings``: ``{label: keyword arguments of pair_stream}`` (``noise_deg``, ``motion_deg``); a
    random ``R0`` per run. Returns per setting: runs, runs that became ready, the share of those
    whose error was within the stated radius then (with its interval), the median pairs to ready,
    and the median radius and error then.
    """
    rows = {}
    for k, (label, kwargs) in enumerate(settings.items()):
        rng = np.random.default_rng([seed, k])
        ready, covered, pairs, radius, error = 0, 0, [], [], []
        for _ in range(n_runs):
            R0 = random_rotations(rng, ())
            oc = OnlineCalibrator(target_deg=target_deg, cusum_h=1e12, drift_pairs=10 ** 9)
            A, B = pair_stream(rng, n_pairs, R0, **kwargs)
            for start in range(0, n_pairs, 10):  # in chunks, to stop soon after it is ready
                state = next((s for s in oc.update_many(A[start:start + 10], B[start:start + 10]) if s.ready), None)
                if state is not None:
                    err = float(angle_between_deg(state.R, R0))
                    ready += 1
                    covered += err <= state.radius_deg
                    pairs.append(state.n_pairs)
                    radius.append(state.radius_deg)
                    error.append(err)
                    break
        row = {"runs": n_runs, "ready": ready, "covered at ready": covered}
        if ready:
            row.update({f"covered {k}": v for k, v in _with_interval(covered, ready).items()})
            row.update({"median pairs to ready": float(np.median(pairs)),
                        "median radius at ready (deg)": float(np.median(radius)),
                        "median error at ready (deg)": float(np.median(error))})
        rows[label] = row
    out = pd.DataFrame(rows).T
    out.index.name = "setting"
    return out


def _degenerate_cases(rng, R0, n):
    A, B = pair_stream(rng, 2, R0)
    good_A, good_B = pair_stream(rng, 30, R0)
    w = np.radians(30.0) * np.array([0.2, 0.5, 0.8]) / np.linalg.norm([0.2, 0.5, 0.8])
    const = matrix_from_rotation_vector(np.tile(w, (n, 1)))
    noise = lambda: matrix_from_rotation_vector(rng.normal(0.0, np.radians(0.2) / np.sqrt(6.0), (n, 3)))  # noqa: E731
    return {
        "one axis, noise-free": pair_stream(rng, n, R0, noise_deg=0.0, axis=[0.3, 0.4, 0.5]),
        "one axis, noisy": pair_stream(rng, n, R0, axis=[0.3, 0.4, 0.5]),
        "one pair repeated": (np.repeat(A[:1], n, 0), np.repeat(B[:1], n, 0)),
        "two noisy pairs repeated": (np.tile(A, (n // 2, 1, 1)), np.tile(B, (n // 2, 1, 1))),
        "constant speed, noise-free": (const, np.swapaxes(R0, -1, -2) @ const @ R0),
        "constant speed, noisy": (noise() @ const, noise() @ np.swapaxes(R0, -1, -2) @ const @ R0),
        "rig at rest": pair_stream(rng, n, R0, motion_deg=(0.0, 0.05), noise_deg=0.05),
        "30 pairs, then the last repeated": (np.concatenate([good_A, np.repeat(good_A[-1:], n - 30, 0)]),
                                             np.concatenate([good_B, np.repeat(good_B[-1:], n - 30, 0)])),
    }


def degenerate_streams(*, n_runs: int, n_pairs: int = 200, seed: int, target_deg: float = 0.5):
    """``ready`` on streams that do not determine ``R0`` (or determine it from few distinct pairs).

    Each case is run ``n_runs`` times (random ``R0``). A *false ready* is ``ready`` while the
    estimate is farther from ``R0`` than the target, or while the stream cannot determine ``R0``
    (every case but the last, whose 30 distinct pairs do). Returns per case: runs, runs ever ready,
    false-ready runs (with the Wilson interval of the share), the largest error while ready, and
    what :meth:`~replication.rig.online.OnlineCalibrator.status` said at the end of the first run.
    """
    rows = {}
    for run in range(n_runs):
        rng = np.random.default_rng([seed, run])
        R0 = random_rotations(rng, ())
        for case, (A, B) in _degenerate_cases(rng, R0, n_pairs).items():
            determinable = case.startswith("30 pairs")
            oc = OnlineCalibrator(target_deg=target_deg)
            states = oc.update_many(A, B)
            errors = [float(angle_between_deg(s.R, R0)) for s in states if s.ready]
            false = any(e > target_deg for e in errors) or (bool(errors) and not determinable)
            row = rows.setdefault(case, {"runs": 0, "ever ready": 0, "false ready": 0, "largest error when ready (deg)":
                                         0.0, "said at the end (run 1)": "; ".join(oc.status()["not_ready"]) or
                                         "ready"})
            row["runs"] += 1
            row["ever ready"] += bool(errors)
            row["false ready"] += false
            row["largest error when ready (deg)"] = max(row["largest error when ready (deg)"], max(errors, default=0.0))
    for row in rows.values():
        row["false ready high"] = wilson_interval(row["false ready"], row["runs"])[1]
    out = pd.DataFrame(rows).T
    out.index.name = "stream"
    return out


def online_mistakes(*, seed: int, seconds: float = 90.0, target_deg: float = 0.5):
    """The usual input mistakes made on purpose on a synthetic rig (camera at 20 Hz, gyro at 200 Hz,
    small noise), replayed as if live: whether the estimator ever says ``ready``, its final verdict
    and the reasons it names."""
    from ..rig.streams import GyroStream, OrientationStream
    from ..testing import rig_streams

    rng = np.random.default_rng(seed)
    R0, camera, gyro, sensor = rig_streams(seconds, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.05)
    inv = lambda s: OrientationStream(s.t, np.swapaxes(s.world_from_body, -1, -2), s.source)  # noqa: E731
    rest_t = np.arange(0.0, seconds, 0.05)
    rest = OrientationStream(rest_t, matrix_from_rotation_vector(rng.normal(0.0, np.radians(0.02), (len(rest_t), 3))),
                             "camera at rest")
    rest_gyro = GyroStream(gyro.t, rng.normal(0.0, np.radians(0.05), gyro.omega.shape), "gyro at rest")
    cases = {
        "as recorded": (camera, gyro),
        "camera poses inverted (camera_from_world)": (inv(camera), gyro),
        "sensor clock 5 s off": (OrientationStream(camera.t + 5.0, camera.world_from_body, "camera"),
                                 GyroStream(gyro.t + 10.0, gyro.omega, "gyro")),
        "gyro in deg/s read as rad/s": (camera, GyroStream(gyro.t, np.degrees(gyro.omega), "gyro")),
        "sensor orientations inverted (sensor_from_world)": (camera, inv(sensor)),
        "rig at rest": (rest, rest_gyro),
    }
    rows = {}
    for name, (cam, sen) in cases.items():
        track = replay(cam, sen, OnlineCalibrator(target_deg=target_deg), reference=R0)
        summary = track.attrs["summary"]
        fails = [r for r in summary["verdict"]["reasons"] if r["level"] == "fail"]
        named = next((r["message"] for r in fails if r["check"] == "input_mistake"), "")
        rows[name] = {"pairs": len(track), "ever ready": bool(track["ready"].any()),
                      "final error (deg)": float(track["error_deg"].iloc[-1]) if len(track) else np.nan,
                      "verdict": summary["verdict"]["level"],
                      "fail checks": ", ".join(sorted({r["check"] for r in fails})),
                      "input mistake named": named.split(";")[0].replace("likely input mistake: ", "")}
    out = pd.DataFrame(rows).T
    out.index.name = "input"
    return out


def _event_stream(rng, hours, R0, *, noise_deg, motion_deg, burst_every=None, burst_length=(4, 8),
                  jump_every=None, jump_factor=3.0):
    """One long in-control stream (one pair per second) with optional outlier bursts
    (``burst_every`` pairs apart on average, each a run of pairs with random camera motions) and
    noise jumps (the noise level alternates between ``noise_deg`` and ``jump_factor`` times it every
    ``jump_every`` pairs)."""
    n = int(round(hours * 3600))
    if jump_every:
        A, B = [], []
        for k, start in enumerate(range(0, n, jump_every)):
            m = min(jump_every, n - start)
            a, b = pair_stream(rng, m, R0, noise_deg=noise_deg * (jump_factor if k % 2 else 1.0), motion_deg=motion_deg)
            A.append(a)
            B.append(b)
        A, B = np.concatenate(A), np.concatenate(B)
    else:
        A, B = pair_stream(rng, n, R0, noise_deg=noise_deg, motion_deg=motion_deg)
    bursts = 0
    if burst_every:
        starts = np.flatnonzero(rng.random(n) < 1.0 / burst_every)
        for s in starts[starts > 100]:
            length = int(rng.integers(burst_length[0], burst_length[1] + 1))
            A[s:s + length] = random_rotations(rng, len(A[s:s + length]))
            bursts += 1
    return A, B, bursts


def event_rates(settings: dict, *, hours: float, seed: int, **stream):
    """Events per hour over long simulated streams without any re-mount (one pair per second), per
    setting.

    ``settings``: ``{label: {"noise_deg": ..., "motion_deg": (lo, hi)}}``; ``stream``: the class of
    disturbance (``burst_every`` for outlier bursts, ``jump_every`` for noise jumps; see
    :func:`_event_stream`). Every re-mount reported is false. Returns per setting the hours, the
    number of each event kind, false re-mounts per hour with its one-sided 95 % upper bound (exact
    Poisson), and the final error.
    """
    rows = {}
    for k, (label, kwargs) in enumerate(settings.items()):
        rng = np.random.default_rng([seed, k])
        R0 = random_rotations(rng, ())
        A, B, bursts = _event_stream(rng, hours, R0, **kwargs, **stream)
        oc = OnlineCalibrator()
        oc.update_many(A, B)
        kinds = [e.kind for e in oc.events]
        row = {"hours": hours, "pairs": len(A)}
        if stream.get("burst_every"):
            row["bursts"] = bursts
        row.update({kind: kinds.count(kind) for kind in EVENT_KINDS})
        row["false re-mounts per hour"] = kinds.count("remount") / hours
        row["95 % upper bound per hour"] = poisson_upper(kinds.count("remount"), hours)
        row["final error (deg)"] = oc.error_deg(R0)
        rows[label] = row
    out = pd.DataFrame(rows).T
    out.index.name = "setting"
    return out


def detection_study(steps_deg, settings: dict, *, n_placements: int, seed: int, before: int = 200,
                    after: int = 200):
    """Re-mounts of each size in simulated streams: ``before`` in-control pairs, then the sensor
    turned by the step about a random axis, then ``after`` pairs.

    Returns per (setting, step): re-mounts confirmed after the step (count, Wilson interval), the
    median and 90th percentile delay (pairs from the step to the confirming pair), events of other
    kinds, false re-mounts before the step, and the median error to the new mounting at the end.
    """
    rows = []
    for k, (label, kwargs) in enumerate(settings.items()):
        for step in steps_deg:
            rng = np.random.default_rng([seed, k, int(round(100 * step))])
            delays, other, early, errors = [], 0, 0, []
            for _ in range(n_placements):
                R0 = random_rotations(rng, ())
                axis = rng.normal(size=3)
                R1 = R0 @ matrix_from_rotation_vector(np.radians(step) * axis / np.linalg.norm(axis))
                A1, B1 = pair_stream(rng, before, R0, **kwargs)
                A2, B2 = pair_stream(rng, after, R1, **kwargs)
                oc = OnlineCalibrator()
                oc.update_many(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
                found = [e.pair - before + 1 for e in oc.events if e.kind == "remount" and e.pair >= before]
                early += sum(1 for e in oc.events if e.kind == "remount" and e.pair < before)
                other += sum(1 for e in oc.events if e.kind != "remount")
                delays.append(found[0] if found else np.nan)
                errors.append(oc.error_deg(R1))
            d = np.array(delays, dtype=float)
            hit = int(np.isfinite(d).sum())
            low, high = wilson_interval(hit, n_placements)
            rows.append({"setting": label, "re-mount (deg)": step, "detected": hit, "of": n_placements,
                         "detected low": low, "detected high": high,
                         "median delay (pairs)": np.nanmedian(d) if hit else np.nan,
                         "90 % delay (pairs)": np.nanpercentile(d, 90) if hit else np.nan,
                         "other events": other, "re-mounts before the step": early,
                         "median error at the end (deg)": float(np.median(errors))})
    return pd.DataFrame(rows).set_index(["setting", "re-mount (deg)"])


def live_run(camera, sensor, reference, *, interval: float = 1.0, remount=None, vins_rule: bool = True,
             **calibrator_options):
    """One replay as if live, with VINS-Mono's rule fed the same pairs.

    Returns
    -------
    (track, vins) : (pandas.DataFrame, dict)
        ``track``: :func:`replication.rig.live.replay`'s rows with ``t`` and ``t_seen`` since the
        camera's first sample, and ``vins_error_deg`` (the rule's error after the same pairs);
        ``vins``: ``ready_t`` (s since the start, when the pair that made it declare success was
        formed, or NaN), ``ready_pairs`` and ``error_at_ready_deg``.
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
    """When each estimator declares itself ready, how far off it is then, and how far off the other
    one is after the same pairs (the fair comparison: both have seen the same data).

    ``runs``: ``{recording: (track, vins)}`` from :func:`live_run`. Ours is ready at a target when
    it first says ``ready`` with its radius below that target (the motion determines ``R0``, no
    change being confirmed, verdict not ``fail``); VINS-Mono's rule when it first declares success
    (its own rule: 10 pairs and the second-smallest singular value above 0.25). Times are when the
    deciding pair was formed (the first pairs wait for the clock-offset window).
    """
    rows = []
    for name, (track, vins) in runs.items():
        def row(estimator, k, radius=np.nan, own="error_deg", other="vins_error_deg"):
            if k is None:
                return {"recording": name, "estimator": estimator}
            r = track.iloc[k]
            return {"recording": name, "estimator": estimator, "ready at (s)": r["t_seen"], "pairs": k + 1,
                    "stated radius (deg)": radius, "error then (deg)": r[own], "the other's error then (deg)": r[other]}

        determined = track["determined"] & ~track["checking"] & (track["n_pairs"] >= MIN_PAIRS)
        for target in targets:
            ok = np.flatnonzero(determined & (track["radius_deg"] < target))
            k = int(ok[0]) if len(ok) else None
            rows.append(row(f"ours, radius < {target:g} deg", k, np.nan if k is None else track["radius_deg"].iloc[k]))
        k = None if np.isnan(vins["ready_pairs"]) else int(vins["ready_pairs"]) - 1
        rows.append(row("VINS-Mono rule", k, own="vins_error_deg", other="error_deg"))
        rows.append(row("ours, at the end", len(track) - 1, track["radius_deg"].iloc[-1]))
    return pd.DataFrame(rows).set_index(["recording", "estimator"])


def remount_study(recordings: dict, *, steps_deg, when=(1 / 3, 1 / 2, 2 / 3), axes=None, interval: float = 1.0,
                  wrong_deg: float = 1.0) -> pd.DataFrame:
    """Re-mount detection on the real recordings: synthetic re-mounts of each size, at several times
    and about several axes, and the recording as recorded (any re-mount reported there is false:
    nothing was re-mounted).

    Returns
    -------
    pandas.DataFrame
        Index ``(recording, re-mount (deg))``; ``detected`` (re-mounts confirmed after the step),
        ``of``, ``median delay (s)`` and ``max delay (s)`` over those caught (from the re-mount to
        the pair that confirmed it), ``ready but wrong at the end`` (replays that end ``ready`` more
        than ``wrong_deg`` from the re-mounted reference), ``other events`` (of other kinds, summed
        over the replays), ``re-mounts before the step`` (false), and the replay without a re-mount:
        its events by kind (a property of the recording, repeated on its rows).
    """
    axes = [REMOUNT_AXIS, np.array([0.0, 0.0, 1.0])] if axes is None else axes
    rows = []
    for name, (camera, sensor, reference) in recordings.items():
        span = camera.t[-1] - camera.t[0]
        track, _ = live_run(camera, sensor, reference, interval=interval, vins_rule=False)
        as_recorded = track.loc[track["event"] != "", "event"].tolist()
        for step in steps_deg:
            delays, wrong, early, other = [], 0, 0, 0
            for share in when:
                for axis in axes:
                    t_re = share * span
                    R = matrix_from_rotation_vector(np.radians(step) * np.asarray(axis) / np.linalg.norm(axis))
                    tr, _ = live_run(camera, sensor, reference, interval=interval, vins_rule=False,
                                     remount=(camera.t[0] + t_re, R))
                    remounts = tr.loc[tr["event"] == "remount", "t_seen"]
                    other += int(((tr["event"] != "") & (tr["event"] != "remount")).sum())
                    early += int((remounts < t_re).sum())
                    after = remounts[remounts >= t_re]
                    delays.append(after.iloc[0] - t_re if len(after) else np.nan)
                    wrong += bool(tr["ready"].iloc[-1] and tr["error_deg"].iloc[-1] > wrong_deg)
            d = np.array(delays)
            rows.append({"recording": name, "re-mount (deg)": step, "detected": int(np.isfinite(d).sum()),
                         "of": len(d), "median delay (s)": np.nanmedian(d) if np.isfinite(d).any() else np.nan,
                         "max delay (s)": np.nanmax(d) if np.isfinite(d).any() else np.nan,
                         "ready but wrong at the end": wrong, "other events": other,
                         "re-mounts before the step": early,
                         "events as recorded": ", ".join(as_recorded) or "none"})
    return pd.DataFrame(rows).set_index(["recording", "re-mount (deg)"])


def update_costs(n_pairs: int = 2000, *, seed: int = 0) -> dict:
    """Per-pair cost of :meth:`~replication.rig.online.OnlineCalibrator.update` on one simulated
    problem: the median, mean and 99th percentile of single updates (µs), and the replay rate of
    :meth:`update_many` (pairs/s)."""
    import time

    from .simulation import simulate

    sim = simulate(seed, 1, n_motions=n_pairs)
    A, B = sim.A[0], sim.B[0]
    OnlineCalibrator().update_many(A, B)  # warm-up: every code path once
    oc, times = OnlineCalibrator(), []
    for a, b in zip(A, B):
        start = time.perf_counter()
        oc.update(a, b)
        times.append(time.perf_counter() - start)
    start = time.perf_counter()
    OnlineCalibrator().update_many(A, B)
    replay_s = time.perf_counter() - start
    times = 1e6 * np.array(times)
    return {"median_us": float(np.median(times)), "mean_us": float(np.mean(times)),
            "p99_us": float(np.percentile(times, 99)), "replay_pairs_per_s": n_pairs / replay_s}
