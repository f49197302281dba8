"""Plot helpers shared by the notebooks (matplotlib; no computation here)."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["METHOD_STYLE", "convergence_figure", "SWEEP_LABELS", "sweep_figure", "FIG7_STYLE", "fig6_figure", "fig7_figure",
           "calibration_figure", "live_figure"]

#: One colour/line style per method, reused in every figure.
METHOD_STYLE = {
    "ours_right": {"color": "tab:cyan", "label": "ours, $R^r$"},
    "ours_left": {"color": "tab:purple", "label": "ours, $R^l$"},
    "optimization": {"color": "tab:blue", "label": "SQP (SLSQP)"},
    "optimization_projected": {"color": "tab:blue", "ls": "--", "label": "SQP, iterate projected"},
    "optimization (analytic)": {"color": "tab:blue", "label": "SQP, analytic gradients"},
    "optimization (finite-difference)": {"color": "tab:orange", "ls": "--", "label": "SQP, finite differences"},
    "optimization (capped)": {"color": "tab:red", "ls": ":", "label": "SQP, capped (30 it., ftol 1e-6)"},
    "optimization (per-pair cost)": {"color": "tab:brown", "ls": "-.", "label": "SQP, cost (8) / 2J"},
}


def convergence_figure(curves: dict, *, ylabel: str, title: str, logy: bool = True, ax=None):
    """One line per method: ``curves[name]`` is a 1-D array over iterations 1..N (on ``ax`` if given)."""
    fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
    for name, values in curves.items():
        values = np.asarray(values)
        ax.plot(np.arange(1, len(values) + 1), values, marker=".", **METHOD_STYLE.get(name, {"label": name}))
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


#: Axis labels of the sweeps in :mod:`replication.baselines`.
SWEEP_LABELS = {
    "noise_deg": "noise bound on each rotation (deg)",
    "n_motions": "number of motion pairs J",
    "motion_amplitude_deg": "largest motion angle (deg)",
    "outlier_fraction": "fraction of outlier pairs",
}


def sweep_figure(sweeps, *, metric: str = "mean_deg", ylabel: str = "mean error to $R_0$ (deg)"):
    """One panel per sweep parameter, one line per solver; ``sweeps`` is :func:`replication.baselines.sweep` output."""
    params = list(dict.fromkeys(sweeps["parameter"]))
    ncols = 2
    nrows = -(-len(params) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(11, 3.6 * nrows), squeeze=False)
    methods = list(dict.fromkeys(sweeps["method"]))
    cmap = plt.get_cmap("tab20")
    for ax, param in zip(axes.flat, params):
        part = sweeps[sweeps["parameter"] == param]
        for i, method in enumerate(methods):
            line = part[part["method"] == method]
            style = {"ls": "-", "lw": 2.2} if method.startswith("two_step") else {"ls": "--", "lw": 1.2}
            ax.plot(line["value"], line[metric], marker=".", color=cmap(i), label=method, **style)
        ax.set_xlabel(SWEEP_LABELS.get(param, param))
        ax.set_ylabel(ylabel)
        ax.set_yscale("log")
    for ax in list(axes.flat)[len(params):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


#: Fig. 7's colours as the paper describes them: camera red, sensor frame black,
#: projections cyan / magenta / blue.
FIG7_STYLE = {
    "camera": {"color": "tab:red", "label": "camera (PnP)", "lw": 1.6},
    "sensor_frame": {"color": "black", "label": "sensor frame (uncalibrated)", "lw": 1.0},
    "ours_right": {"color": "c", "label": "projected, ours $R^r$", "lw": 1.0},
    "ours_left": {"color": "m", "label": "projected, ours $R^l$", "lw": 1.0, "ls": "--"},
    "optimization": {"color": "b", "label": "projected, SQP", "lw": 1.0, "ls": ":"},
}
ANGLES = ("roll", "pitch", "yaw")


def fig6_figure(per_set, *, reference: str = "the true $R_0$"):
    """Fig. 6: each method's ``R0`` estimate over the data sets, as its deviation from a reference.

    ``per_set`` is :attr:`replication.lab.LabResult.per_set`: the rotation vector of
    ``R_est R_ref^T`` about the camera's x, y, z axes (deg). (Euler angles would be
    unreadable here: the mounting puts ``R0`` near pitch -90 deg, gimbal lock.)
    """
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharey=True)
    for ax, axis in zip(axes, "xyz"):
        for method, part in per_set.groupby("method", sort=False):
            style = {"color": FIG7_STYLE[method]["color"], "ls": FIG7_STYLE[method].get("ls", "-")}
            ax.plot(part["set"] + 1, part[f"dev_{axis}_deg"], marker="o", ms=4, label=METHOD_STYLE[method]["label"], **style)
        ax.axhline(0.0, color="grey", ls="--", lw=1)
        ax.set_xlabel("data set")
        ax.set_title(f"about camera {axis}")
    axes[0].set_ylabel(f"deviation from {reference} (deg)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def fig7_figure(traces):
    """Fig. 7: (a) relative roll / pitch / yaw traces; (b) their differences to the camera's.

    ``traces`` is :attr:`replication.lab.LabResult.traces`.
    """
    sources = [k for k in FIG7_STYLE if f"{k}_roll" in traces]
    fig, axes = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    t = traces["t"]
    for j, angle in enumerate(ANGLES):
        for src in sources:
            axes[0, j].plot(t, traces[f"{src}_{angle}"], **FIG7_STYLE[src])
            if src != "camera":
                diff = (traces[f"{src}_{angle}"] - traces[f"camera_{angle}"] + 180.0) % 360.0 - 180.0
                axes[1, j].plot(t, diff, **FIG7_STYLE[src])
        axes[0, j].set_title(f"(a) {angle}")
        axes[1, j].set_title(f"(b) {angle}: minus camera")
        axes[1, j].set_xlabel("time (s)")
    axes[0, 0].set_ylabel("relative attitude (deg)")
    axes[1, 0].set_ylabel("difference (deg)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


_VERDICT_COLOUR = {"ok": "tab:green", "warning": "tab:orange", "fail": "tab:red"}


def calibration_figure(result):
    """The diagnostic figure of a calibration (:meth:`replication.report.CalibrationResult.plot`), like Kalibr's report.

    Streams: (a) angular speed of both streams after the clock alignment; (b) the clock-offset cross-correlation
    with the chosen peak and the search bounds. Static pose sets: (a) each station's median pair residual against
    the outlying-station threshold; (b) the residuals against the station pair. Then (c) per-pair residuals over
    time; (d) their histogram; (e) the bootstrap cloud (estimates as rotation vectors of ``R_boot R^T``, deg) with
    the radius and what it covers; (f) the verdict and its reasons; with ``online`` results, (g) the online
    estimate's radius (and error to a reference) over time, when it became ready and its events.
    """
    import textwrap

    from .quality import THRESHOLDS

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


def live_figure(runs: dict, targets=(0.5, 0.2)):
    """Notebook 08: the online estimate's error to the reference and its stated radius over time, per recording,
    with the moment VINS-Mono's rule declares success (``runs``: :func:`replication.live_study.live_run` results)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(6.5 * len(runs), 4.2), squeeze=False)
    for ax, (name, (track, vins)) in zip(axes[0], runs.items()):
        ok = track["n_pairs"] >= 10
        ax.semilogy(track["t"][ok], track["error_deg"][ok], label="error to the reference")
        ax.semilogy(track["t"][ok], track["radius_deg"][ok], "--", label="stated 95 % radius")
        for target in targets:
            ax.axhline(target, color="grey", lw=0.6, ls=":")
        if np.isfinite(vins["ready_t"]):
            ax.axvline(vins["ready_t"], color="tab:red", lw=0.8)
            ax.annotate(f"VINS-Mono rule: done,\n{vins['error_at_ready_deg']:.2f} deg off", (vins["ready_t"], 0.9),
                        xycoords=("data", "axes fraction"), fontsize=7, color="tab:red", va="top")
        ax.set_title(name)
        ax.set_xlabel("time since the first camera pose (s)")
        ax.set_ylabel("deg")
        ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    return fig

