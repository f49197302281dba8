"""The diagnostic figure of a calibration (:meth:`replication.rig.report.CalibrationResult.plot`),
like Kalibr's report: matplotlib, no computation here beyond the conventions' conversions of the
reference."""
from __future__ import annotations

import math
import textwrap

import matplotlib.pyplot as plt
import numpy as np

from ..core.so3 import quaternion_from_matrix, yaw_pitch_roll_deg_from_matrix
from .quality import THRESHOLDS

__all__ = ["calibration_figure", "headline", "offset_zoom_ms"]

_VERDICT_COLOUR = {"ok": "tab:green", "warning": "tab:orange", "fail": "tab:red"}
_ROW_IN = 3.4  # height of a row of panels (inches)
_HEAD_IN = 0.9  # height of the text band that states R0 (five lines; taller for more)


def _rotation_text(quaternion_wxyz, yaw_pitch_roll) -> str:
    q = ", ".join(f"{v:+.6f}" for v in quaternion_wxyz)
    return (f"quaternion (w, x, y, z) = ({q}); yaw / pitch / roll (intrinsic z-y'-x'') = "
            + " / ".join(f"{v:.3f}" for v in yaw_pitch_roll) + " deg")


def headline(result, *, name: str | None = None, reference_name: str | None = None) -> tuple[str, list[str]]:
    """The figure's title and the lines that state ``R0``: the recording, the method and the pairs;
    ``R0`` as a quaternion and as yaw / pitch / roll (conventions: ``docs/conventions.md``); the
    bootstrap radius and what it covers; the reference, when one was given, and the angle to it.

    Returns
    -------
    (title, lines) : (str, list of str)
    """
    pairs = (f"{result.n_pairs} pairs {result.interval_s:g} s apart" if math.isfinite(result.interval_s)
             else f"{result.n_pairs} pairs of static poses")
    title = f"{name or 'calibration'}: R0 (camera_from_sensor) by {result.method}, {pairs}"
    lines = ["R0: " + _rotation_text(result.quaternion_wxyz, result.euler_zyx_deg)]
    if math.isfinite(result.bootstrap_ci95_deg):
        lines.append(f"95 % bootstrap radius {result.bootstrap_ci95_deg:.3g} deg (resampling "
                     f"{result.bootstrap_resamples}); it covers {result.bootstrap_covers}")
    else:
        lines.append("95 % bootstrap radius: not available (no bootstrap, or too few independent blocks for one to "
                     "mean anything)")
    if result.reference_error_deg is None:
        lines.append("reference: none given")
    elif result.reference_errors_deg is not None:  # two references: each error, the floor, the reading
        names = reference_name.split(" and ") if reference_name and reference_name.count(" and ") == 1 else [None] * 2
        for k, (key, error) in enumerate(zip(("reference_camera_from_sensor", "second_reference_camera_from_sensor"),
                                             result.reference_errors_deg)):
            lines.append(_reference_line(f"reference {k + 1}" + (f" ({names[k]})" if names[k] else ""),
                                         result.inputs.get(key), error))
        lines.append(f"reading: {result.reference_reading}")
    else:
        said = f"reference ({reference_name})" if reference_name else "reference"
        lines.append(_reference_line(said, result.inputs.get("reference_camera_from_sensor"),
                                     result.reference_error_deg))
    if result.sensor_model is not None:  # a gyro: its bias and the clock's drift, as the summary states them
        lines += [x for x in result.summary().splitlines() if x.startswith(("gyro bias", "clock drift"))]
    return title, lines


def _reference_line(said: str, ref, error_deg: float) -> str:
    if ref is not None:
        ref = np.asarray(ref, dtype=float)
        said += ": " + _rotation_text(quaternion_from_matrix(ref), yaw_pitch_roll_deg_from_matrix(ref))
    return f"{said}; angle between R0 and it: {error_deg:.3f} deg"


def calibration_figure(result, *, name: str | None = None, reference_name: str | None = None):
    """The diagnostic figure of a calibration
    (:meth:`replication.rig.report.CalibrationResult.plot`), like Kalibr's report.

    A title naming the recording (``name``), the method and the pairs, and a band of text stating
    ``R0`` (:func:`headline`: quaternion, yaw / pitch / roll, the bootstrap radius and what it
    covers, the reference (``reference_name`` says where it came from) and the angle to it). Then
    the panels that have data, lettered in order. Streams: angular speed of both streams after the
    clock alignment; the clock-offset cross-correlation with the chosen peak and the search bounds.
    Static pose sets: each station's median pair residual against the outlying-station threshold;
    the residuals against the station pair. Then the per-pair residuals over time, their histogram,
    the bootstrap cloud (estimates as rotation vectors of ``R_boot R^T``, deg; left out without a
    bootstrap), the verdict and its reasons; with ``online`` results, the online estimate's radius
    (and error to a reference) over time, when it became ready and its events, and the online
    verdict.
    """
    d = result.diagnostics
    online = result.online if result.online and d.get("online_track") is not None else None
    t0 = d.get("t0", 0.0)
    res = np.asarray(d.get("residuals_deg", []), dtype=float)
    cloud = np.asarray(d.get("bootstrap_rotvec_deg", np.empty((0, 3))), dtype=float).reshape(-1, 3)
    panels = []  # the panels with data, in order
    if d.get("speeds") is not None:
        panels.append(lambda ax, k: _speeds_panel(ax, k, d["speeds"], t0))
    elif d.get("pose_residual_median_deg") is not None:
        panels.append(lambda ax, k: _stations_panel(ax, k, d["pose_residual_median_deg"]))
    if d.get("offset_curve") is not None:
        panels.append(lambda ax, k: _offset_panel(ax, k, result))
    elif d.get("station_pairs") is not None:
        panels.append(lambda ax, k: _station_pairs_panel(ax, k, d["station_pairs"], d.get("residuals_deg")))
    if len(res):
        panels.append(lambda ax, k: _residual_panel(ax, k, res, d.get("pair_times"), t0, d.get("change")))
        panels.append(lambda ax, k: _histogram_panel(ax, k, res, result))
    if len(cloud):
        panels.append(lambda ax, k: _cloud_panel(ax, k, cloud, result))
    panels.append(lambda ax, k: _verdict_panel(ax, k, result))
    nrows = -(-len(panels) // 3) + (1 if online else 0)
    title, lines = headline(result, name=name, reference_name=reference_name)
    text = "\n".join(textwrap.fill(line, 150, subsequent_indent="    ") for line in lines)
    head_in = _HEAD_IN * max(1.0, (text.count("\n") + 1) / 5)  # 5 lines fit the band
    fig = plt.figure(figsize=(14, head_in + _ROW_IN * nrows))
    grid = fig.add_gridspec(1 + nrows, 3, height_ratios=[head_in] + [_ROW_IN] * nrows)
    colour = _VERDICT_COLOUR[result.verdict.level]
    head = fig.add_subplot(grid[0, :])
    head.axis("off")
    head.text(0.0, 1.0, text, fontsize=8, va="top", family="monospace", transform=head.transAxes)
    for k, draw in enumerate(panels):
        draw(fig.add_subplot(grid[1 + k // 3, k % 3]), chr(97 + k))
    if online:
        k = len(panels)
        _online_panel(fig.add_subplot(grid[nrows, :2]), chr(97 + k), online, d["online_track"], t0)
        _online_verdict_panel(fig.add_subplot(grid[nrows, 2]), chr(98 + k), online)
    fig.suptitle(title, color=colour)
    fig.tight_layout()
    return fig


def _speeds_panel(ax, k, speeds, t0):
    t, cam, sen = speeds
    ax.plot(t - t0, cam, lw=0.7, label="camera")
    ax.plot(t - t0, sen, lw=0.7, alpha=0.8, label="sensor, clock aligned")
    ax.set_xlabel("time since the camera's first sample (s)")
    ax.set_ylabel("angular speed (deg/s)")
    ax.legend(fontsize=7)
    ax.set_title(f"({k}) angular speed")


def _stations_panel(ax, k, stations):
    stations = np.asarray(stations, dtype=float)
    limit = THRESHOLDS["pose_residual_ratio"][0] * np.nanmedian(stations)
    ax.bar(np.arange(len(stations)), stations, color=np.where(stations > limit, "tab:red", "tab:blue"))
    ax.axhline(limit, color="tab:red", ls=":", lw=0.8, label="outlying-station threshold")
    ax.set_xlabel("station (0-based)")
    ax.set_ylabel("median residual of its pairs (deg)")
    ax.legend(fontsize=7)
    ax.set_title(f"({k}) residual by station")


#: Least width (ms) of the offset panel's zoom about the interval (a few fine-grid steps).
_ZOOM_MIN_MS = 0.5


def offset_zoom_ms(result):
    """The offset panel's x range (ms): the 95 % interval with half its width either side (at least
    :data:`_ZOOM_MIN_MS` wide), or None where the interval is not finite (the full search is
    shown)."""
    lo, hi = (1e3 * float(v) for v in result.time_offset_ci95_s)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return None
    pad = max(0.5 * (hi - lo), 0.5 * (_ZOOM_MIN_MS - (hi - lo)))
    return lo - pad, hi + pad


def _offset_panel(ax, k, result):
    """Zoomed to the offset's 95 % interval (shaded, with 0 marked), the full search in an inset."""
    offsets, corr = result.diagnostics["offset_curve"]
    x, corr = 1e3 * np.asarray(offsets, dtype=float), np.asarray(corr, dtype=float)
    chosen = 1e3 * result.time_offset_s
    zoom = offset_zoom_ms(result)
    ax.plot(x, corr, ".-" if zoom else "-", lw=0.8, ms=3)
    ax.axvline(chosen, color="k", ls="--", lw=0.8, label=f"chosen: {chosen:+.2f} ms")
    bound = result.parameters.get("max_offset_s")
    if zoom is None:
        if bound:
            for b in (-bound, bound):
                ax.axvline(1e3 * b, color="tab:red", ls=":", lw=0.8, label="search bound" if b < 0 else None)
        ax.set_title(f"({k}) clock offset (no finite interval: the full search)")
    else:
        lo, hi = (1e3 * float(v) for v in result.time_offset_ci95_s)
        ax.axvspan(lo, hi, color="tab:blue", alpha=0.15, label=f"95 % interval [{lo:+.2f}, {hi:+.2f}] ms")
        ax.axvline(0.0, color="grey", lw=0.8, label="0 (clocks agree)" + (": inside the interval" if lo <= 0 <= hi
                                                                         else ""))
        ax.set_xlim(*zoom)
        inside = (x >= zoom[0]) & (x <= zoom[1])
        if inside.any():
            span = np.ptp(corr[inside])
            ax.set_ylim(corr[inside].min() - 0.1 * span - 1e-6, corr[inside].max() + 0.1 * span + 1e-6)
        inset = ax.inset_axes([0.32, 0.05, 0.36, 0.32])
        inset.plot(x, corr, lw=0.6)
        inset.axvspan(*zoom, color="tab:orange", alpha=0.4)
        inset.tick_params(labelsize=5)
        inset.text(0.02, 0.96, "full search" + (f" +-{1e3 * bound:g} ms" if bound else ""), fontsize=5, va="top",
                   transform=inset.transAxes)
        ax.set_title(f"({k}) clock offset, zoomed to its 95 % interval")
    ax.set_xlabel("sensor clock offset d (ms; d > 0: the sensor clock reads ahead)")
    ax.set_ylabel("correlation of angular speeds")
    ax.legend(fontsize=6, loc="upper right")


def _station_pairs_panel(ax, k, station_pairs, residuals):
    i, j = station_pairs
    sc = ax.scatter(i, j, c=residuals, s=3, cmap="viridis")
    ax.figure.colorbar(sc, ax=ax, label="residual (deg)")
    ax.set_xlabel("station i")
    ax.set_ylabel("station j")
    ax.set_title(f"({k}) residual of each station pair")


def _residual_panel(ax, k, res, times, t0, change):
    ax.plot(np.arange(len(res)) if times is None else np.asarray(times) - t0, res, ".", ms=2)
    if change is not None and change.significant:
        ax.axvline(change.split_time, color="tab:red", ls="--", lw=0.8,
                   label=f"R0 changes here? ({change.angle_deg:.2g} deg between the sides)")
        ax.legend(fontsize=7)
    ax.set_xlabel("pair" if times is None else "pair start, since the camera's first sample (s)")
    ax.set_ylabel("residual (deg)")
    ax.set_title(f"({k}) per-pair residual")


def _histogram_panel(ax, k, res, result):
    ax.hist(res, bins=50)
    ax.set_xlabel("residual (deg)")
    ax.set_ylabel("pairs")
    ax.set_title(f"({k}) residuals: median {result.residual_deg['median']:.3g} deg")


def _cloud_panel(ax, k, cloud, result):
    sc = ax.scatter(cloud[:, 0], cloud[:, 1], s=4, c=cloud[:, 2], cmap="coolwarm")
    ax.figure.colorbar(sc, ax=ax, label="z (deg)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (deg)")
    ax.set_ylabel("y (deg)")
    radius = (f"95 % radius {result.bootstrap_ci95_deg:.3g} deg" if math.isfinite(result.bootstrap_ci95_deg)
              else "95 % radius not available")
    ax.text(0.02, 0.02, f"{radius}; {len(cloud)} resamples", fontsize=7, transform=ax.transAxes, va="bottom")
    ax.set_title(f"({k}) bootstrap estimates about R0")


def _verdict_panel(ax, k, result):
    ax.axis("off")
    ax.text(0.0, 1.0, f"verdict: {result.verdict.level.upper()}", color=_VERDICT_COLOUR[result.verdict.level],
            fontsize=14, weight="bold", va="top", transform=ax.transAxes)
    lines = [r.message for r in result.verdict.reasons] or ["every check passed"]
    body = "\n".join(textwrap.fill(f"- {m}", 60) for m in lines[:8])
    ax.text(0.0, 0.88, body, fontsize=7, va="top", transform=ax.transAxes)
    ax.set_title(f"({k}) verdict")


def _online_verdict_panel(ax, k, online):
    ax.axis("off")
    ov = online["verdict"]
    ax.text(0.0, 1.0, f"online verdict: {ov['level'].upper()}", color=_VERDICT_COLOUR[ov["level"]], fontsize=11,
            weight="bold", va="top", transform=ax.transAxes)
    said = [r["message"] for r in ov["reasons"]] + [f"not ready: {m}" for m in online["not_ready"]]
    ax.text(0.0, 0.88, "\n".join(textwrap.fill(f"- {m}", 60) for m in said[:6]) or "every check passed",
            fontsize=7, va="top", transform=ax.transAxes)
    ax.set_title(f"({k}) online verdict")


def _online_panel(ax, k, online, track, t0):
    """The online replay: radius (and error to a reference) over time, when it became ready, its
    events."""
    t = np.asarray(track["t_seen"]) - t0
    ax.semilogy(t, track["radius_deg"], "--", label=f"stated {100 * online['radius_level']:g} % radius")
    if "error_deg" in track:
        ax.semilogy(t, track["error_deg"], label="error to the reference")
    ax.axhline(online["target_deg"], color="grey", lw=0.6, ls=":", label=f"target {online['target_deg']:g} deg")
    if online["ready_at_s"] is not None:
        ax.axvline(online["ready_at_s"], color="tab:green", lw=0.8, label=f"ready at {online['ready_at_s']:.1f} s")
    for ev in online["events"]:
        ax.axvline(ev["t_s"], color="tab:red" if ev["kind"] == "remount" else "tab:orange", lw=0.8, ls="-.")
        ax.text(ev["t_s"], 0.98, ev["kind"], rotation=90, fontsize=6, va="top", transform=ax.get_xaxis_transform())
    ax.set_xlabel("when the pair was formed, since the camera's first sample (s)")
    ax.set_ylabel("angle (deg)")
    ax.set_title(f"({k}) online replay (the radius covers the pairs' own noise only)")
    ax.legend(fontsize=7)
