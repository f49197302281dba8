"""The diagnostic figure of a calibration (:meth:`replication.rig.report.CalibrationResult.plot`), like Kalibr's
report: matplotlib, no computation here."""
from __future__ import annotations

import textwrap

import matplotlib.pyplot as plt
import numpy as np

from .quality import THRESHOLDS

__all__ = ["calibration_figure"]

_VERDICT_COLOUR = {"ok": "tab:green", "warning": "tab:orange", "fail": "tab:red"}


def calibration_figure(result):
    """The diagnostic figure of a calibration (:meth:`replication.rig.report.CalibrationResult.plot`), like Kalibr's
    report.

    Streams: (a) angular speed of both streams after the clock alignment; (b) the clock-offset cross-correlation
    with the chosen peak and the search bounds. Static pose sets: (a) each station's median pair residual against
    the outlying-station threshold; (b) the residuals against the station pair. Then (c) per-pair residuals over
    time; (d) their histogram; (e) the bootstrap cloud (estimates as rotation vectors of ``R_boot R^T``, deg) with
    the radius and what it covers; (f) the verdict and its reasons; with ``online`` results, (g) the online
    estimate's radius (and error to a reference) over time, when it became ready and its events.
    """
    d = result.diagnostics
    online = result.online if result.online and d.get("online_track") is not None else None
    fig = plt.figure(figsize=(14, 10.5 if online else 7.5))
    grid = fig.add_gridspec(3 if online else 2, 3)
    a, b, c = (fig.add_subplot(grid[0, k]) for k in range(3))
    h, e, f = (fig.add_subplot(grid[1, k]) for k in range(3))
    t0 = d.get("t0", 0.0)
    speeds = d.get("speeds")
    stations = d.get("pose_residual_median_deg")
    if speeds is not None:
        t, cam, sen = speeds
        a.plot(t - t0, cam, lw=0.7, label="camera")
        a.plot(t - t0, sen, lw=0.7, alpha=0.8, label="sensor, clock aligned")
        a.set_xlabel("time since the camera's first sample (s)")
        a.set_ylabel("angular speed (deg/s)")
        a.legend(fontsize=7)
        a.set_title("(a) angular speed")
    elif stations is not None:
        stations = np.asarray(stations, dtype=float)
        limit = THRESHOLDS["pose_residual_ratio"][0] * np.nanmedian(stations)
        a.bar(np.arange(len(stations)), stations, color=np.where(stations > limit, "tab:red", "tab:blue"))
        a.axhline(limit, color="tab:red", ls=":", lw=0.8, label="outlying-station threshold")
        a.set_xlabel("station (0-based)")
        a.set_ylabel("median residual of its pairs (deg)")
        a.legend(fontsize=7)
        a.set_title("(a) residual by station")
    else:
        a.text(0.5, 0.5, "no streams", ha="center", va="center", transform=a.transAxes)
        a.set_title("(a) angular speed")
    curve = d.get("offset_curve")
    if curve is not None:
        offsets, corr = curve
        b.plot(1e3 * np.asarray(offsets), corr, lw=0.8)
        b.axvline(1e3 * result.time_offset_s, color="k", ls="--", lw=0.8, label="chosen")
        bound = result.parameters.get("max_offset_s")
        if bound:
            for x in (-bound, bound):
                b.axvline(1e3 * x, color="tab:red", ls=":", lw=0.8)
        b.set_xlabel("sensor clock offset (ms)")
        b.set_ylabel("correlation of angular speeds")
        b.legend(fontsize=7)
        b.set_title("(b) clock offset")
    elif d.get("station_pairs") is not None:
        i, j = d["station_pairs"]
        sc = b.scatter(i, j, c=d.get("residuals_deg"), s=3, cmap="viridis")
        fig.colorbar(sc, ax=b, label="residual (deg)")
        b.set_xlabel("station i")
        b.set_ylabel("station j")
        b.set_title("(b) residual of each station pair")
    else:
        b.text(0.5, 0.5, "no clock to align", ha="center", va="center", transform=b.transAxes)
        b.set_title("(b) clock offset")
    res = np.asarray(d.get("residuals_deg", []))
    times = d.get("pair_times")
    c.plot(np.arange(len(res)) if times is None else np.asarray(times) - t0, res, ".", ms=2)
    change = d.get("change")
    if change is not None and change.significant:
        c.axvline(change.split_time, color="tab:red", ls="--", lw=0.8,
                  label=f"R0 changes here? ({change.angle_deg:.2g} deg between the sides)")
        c.legend(fontsize=7)
    c.set_xlabel("pair" if times is None else "pair start, since the camera's first sample (s)")
    c.set_ylabel("residual (deg)")
    c.set_title("(c) per-pair residual")
    h.hist(res, bins=50)
    h.set_xlabel("residual (deg)")
    h.set_title(f"(d) residuals: median {result.residual_deg['median']:.3g} deg")
    cloud = np.asarray(d.get("bootstrap_rotvec_deg", np.empty((0, 3))))
    if len(cloud):
        e.scatter(cloud[:, 0], cloud[:, 1], s=4, c=cloud[:, 2], cmap="coolwarm")
        e.set_aspect("equal", adjustable="datalim")
        e.set_xlabel("x (deg)")
        e.set_ylabel("y (deg); colour: z")
        e.text(0.02, 0.02, textwrap.fill(f"95 % radius {result.bootstrap_ci95_deg:.3g} deg, resampling "
                                         f"{result.bootstrap_resamples}: it covers {result.bootstrap_covers}", 55),
               fontsize=6, transform=e.transAxes, va="bottom")
    else:
        e.text(0.5, 0.5, "no bootstrap", ha="center", va="center", transform=e.transAxes)
    e.set_title("(e) bootstrap estimates about R0")
    f.axis("off")
    colour = _VERDICT_COLOUR[result.verdict.level]
    f.text(0.0, 1.0, f"verdict: {result.verdict.level.upper()}", color=colour, fontsize=14, weight="bold",
           va="top", transform=f.transAxes)
    lines = [r.message for r in result.verdict.reasons] or ["every check passed"]
    body = "\n".join(textwrap.fill(f"- {m}", 60) for m in lines[:8])
    f.text(0.0, 0.88, body, fontsize=7, va="top", transform=f.transAxes)
    f.set_title("(f) verdict")
    if online:
        _online_panel(fig.add_subplot(grid[2, :2]), online, d["online_track"], t0)
        g = fig.add_subplot(grid[2, 2])
        g.axis("off")
        ov = online["verdict"]
        g.text(0.0, 1.0, f"online verdict: {ov['level'].upper()}", color=_VERDICT_COLOUR[ov["level"]], fontsize=11,
               weight="bold", va="top", transform=g.transAxes)
        said = [r["message"] for r in ov["reasons"]] + [f"not ready: {m}" for m in online["not_ready"]]
        g.text(0.0, 0.88, "\n".join(textwrap.fill(f"- {m}", 60) for m in said[:6]) or "every check passed",
               fontsize=7, va="top", transform=g.transAxes)
    fig.suptitle(f"R0 by {result.method}: {result.n_pairs} pairs", color=colour)
    fig.tight_layout()
    return fig


def _online_panel(ax, online, track, t0):
    """The online replay: radius (and error to a reference) over time, when it became ready, its events."""
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
    ax.set_ylabel("deg")
    ax.set_title("(g) online replay (the radius covers the pairs' own noise only)")
    ax.legend(fontsize=7)
