"""Report plots (matplotlib, imported lazily, Agg backend): one function per figure.

Each function takes arrays or result objects, writes a PNG and returns its path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from crowdwalk.errors import invalid


def _pyplot():
    """Import matplotlib's pyplot with a file-only backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, out: str | Path) -> Path:
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120, bbox_inches="tight")
    _pyplot().close(fig)
    return out


# --- viewer / report plots (issue 6) ---------------------------------------------------


def _as_curves(values, n_points: int, owner: str, field: str):
    """(c, m) float array from one curve (m,) or several (c, m)."""
    arr = np.atleast_2d(np.asarray(values, dtype=float))
    if arr.ndim != 2 or arr.shape[1] != n_points:
        raise invalid(owner, field, f"shaped ({n_points},) or (curves, {n_points})", arr.shape)
    return arr


def best_step_length(step_length, efficiency):
    """Step length [m] of the highest efficiency of each curve, shape (c,).

    Parameters
    ----------
    step_length : (m,) float
        Step lengths [m].
    efficiency : (m,) or (c, m) float
        Chen & Li's efficiency ``step length / E`` (Eq. 5) of each step length.
    """
    x = np.asarray(step_length, dtype=float)
    eff = _as_curves(efficiency, len(x), "plot_efficiency_curve", "efficiency")
    return x[np.nanargmax(eff, axis=1)]


def plot_efficiency_curve(
    step_length,
    efficiency,
    out,
    *,
    labels=None,
    unit: str = "m per J/kg",
    reference: tuple[float, float] | None = (0.65, 0.78),
    title: str = "Walking efficiency against step length (Chen & Li, Eq. 5, Fig. 2)",
):
    """The planner's efficiency curve: efficiency against step length, optimum marked.

    Parameters
    ----------
    step_length : (m,) float
        Step lengths [m].
    efficiency : (m,) or (c, m) float
        Efficiency ``step length / E`` of each step length, one row per curve (e.g. per
        walking speed or per energy-model variant), in ``unit``.
    out : path
        PNG file.
    labels : sequence of str, optional
        Curve labels (c,).
    reference : (float, float), optional
        Measured preferred step-length range [m] shaded for comparison (default: 0.65-0.78 m
        at 1.34 m/s, WBDS / Vadere OSM); None for no band.

    Returns
    -------
    pathlib.Path
    """
    x = np.asarray(step_length, dtype=float)
    eff = _as_curves(efficiency, len(x), "plot_efficiency_curve", "efficiency")
    if labels is not None and len(labels) != len(eff):
        raise invalid("plot_efficiency_curve", "labels", f"{len(eff)} labels", len(labels))
    best = best_step_length(x, eff)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    if reference is not None:
        ax.axvspan(*reference, color="0.88", label="measured preferred step length")
    for i, curve in enumerate(eff):
        label = labels[i] if labels is not None else None
        (line,) = ax.plot(x, curve, lw=2, label=label)
        ax.plot(best[i], np.nanmax(curve), "o", color=line.get_color())
        ax.annotate(f"{best[i]:.2f} m", (best[i], np.nanmax(curve)), textcoords="offset points",
                    xytext=(10, -4 - 12 * i), va="top", color=line.get_color(), fontsize=8)
    ax.set_xlabel("step length [m]")
    ax.set_ylabel(f"efficiency [{unit}]")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    if labels is not None or reference is not None:
        ax.legend(fontsize=8)
    return _save(fig, out)


def plot_planner_comparison(metrics, out, *, units=None, title="Planned against unplanned walkers"):
    """Planned vs unplanned (or any planners): one panel per metric, a box per planner with
    every agent's value on top, the median printed.

    Parameters
    ----------
    metrics : mapping of metric name -> mapping of planner -> (n_agents,) float
        e.g. ``{"energy per metre": {"best_first": e1, "fixed": e2}, "travel time": ...}``
        from the runs' ``summary.json``.
    out : path
        PNG file.
    units : mapping of metric name -> unit string, optional
        Shown on each y axis.

    Returns
    -------
    pathlib.Path
    """
    if not metrics:
        raise invalid("plot_planner_comparison", "metrics", "a non-empty mapping", metrics)
    units = units or {}
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(metrics), figsize=(3.2 * len(metrics), 3.6), squeeze=False)
    rng = np.random.default_rng(0)  # jitter of the dots only
    for ax, (metric, groups) in zip(axes[0], metrics.items(), strict=True):
        names = list(groups)
        data = [np.asarray(groups[n], dtype=float) for n in names]
        data = [d[np.isfinite(d)] for d in data]
        if any(d.size == 0 for d in data):
            raise invalid("plot_planner_comparison", metric, "finite values for every planner",
                          {n: d.size for n, d in zip(names, data, strict=True)})
        ax.boxplot(data, widths=0.5, showfliers=False)
        ax.set_xticks(range(1, len(names) + 1), names)
        for i, d in enumerate(data, start=1):
            ax.plot(i + rng.uniform(-0.15, 0.15, d.size), d, ".", alpha=0.5, ms=4)
            ax.annotate(f"{np.median(d):.3g}", (i, np.median(d)), xytext=(18, 0),
                        textcoords="offset points", va="center", fontsize=8)
        unit = units.get(metric)
        ax.set_ylabel(f"{metric} [{unit}]" if unit else metric)
        ax.grid(alpha=0.3, axis="y")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out)


def plot_gait_curves(stride, generated, measured, out, *, measured_stride=None,
                     title="Generated elevation angles against measured data"):
    """Generated gait curves vs measured data: one panel per segment, elevation angle
    against the normalised stride, generated curve(s) over the measured mean ± 1 SD band.

    Parameters
    ----------
    stride : (F,) float
        Normalised stride t ∈ [0, 1) of the generated curves (t = 0 at heel strike).
    generated : mapping of segment -> (F,) or (c, F) float
        Generated elevation angles [rad] (e.g. ``{"thigh": ..., "shank": ..., "foot": ...}``).
    measured : mapping of segment -> (mean (M,), sd (M,)) float
        Measured mean and standard deviation [rad] of the same segments.
    out : path
        PNG file.
    measured_stride : (M,) float, optional
        Stride samples of the measured curves; ``stride`` when omitted.

    Returns
    -------
    pathlib.Path
    """
    t = np.asarray(stride, dtype=float)
    tm = t if measured_stride is None else np.asarray(measured_stride, dtype=float)
    if not generated:
        raise invalid("plot_gait_curves", "generated", "a non-empty mapping", generated)
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(generated), figsize=(3.4 * len(generated), 3.2),
                             squeeze=False)
    for ax, (segment, curves) in zip(axes[0], generated.items(), strict=True):
        curves = _as_curves(curves, len(t), "plot_gait_curves", f"generated[{segment!r}]")
        if segment in measured:
            mean, sd = (np.asarray(a, dtype=float) for a in measured[segment])
            if mean.shape != tm.shape or sd.shape != tm.shape:
                raise invalid("plot_gait_curves", f"measured[{segment!r}]",
                              f"(mean, sd) each shaped {tm.shape} [rad]", (mean.shape, sd.shape))
            ax.fill_between(100 * tm, np.degrees(mean - sd), np.degrees(mean + sd),
                            color="0.85", label="measured ± 1 SD")
            ax.plot(100 * tm, np.degrees(mean), color="0.4", lw=1, ls="--",
                    label="measured mean")
        for i, curve in enumerate(curves):
            ax.plot(100 * t, np.degrees(curve), lw=1.5, color="C0", alpha=1.0 if i == 0 else 0.5,
                    label="generated" if i == 0 else None)
        ax.set_title(segment, fontsize=10)
        ax.set_xlabel("stride [%]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("elevation angle [deg]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out)


def plot_footstep_map(x, y, values, out, *, walkable_area=None, label="step energy",
                      title="Footholds seen from above"):
    """Every foothold seen from above, coloured by a per-step value (e.g. energy).

    Parameters
    ----------
    x, y : (n,) float
        Foothold positions [m].
    values : (n,) float
        Colour value per foothold (unit in ``label``).
    out : path
        PNG file.
    walkable_area : shapely geometry, optional
        Outline drawn underneath [m].

    Returns
    -------
    pathlib.Path
    """
    import shapely

    x, y, values = (np.asarray(a, dtype=float) for a in (x, y, values))
    if not (x.shape == y.shape == values.shape) or x.ndim != 1:
        raise invalid("plot_footstep_map", "x", "1-D and as long as y and values",
                      (x.shape, y.shape, values.shape))
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    if walkable_area is not None:
        for ring in shapely.get_parts(shapely.boundary(walkable_area)):
            for line in shapely.get_parts(ring):
                xy = np.asarray(line.coords)
                ax.plot(xy[:, 0], xy[:, 1], color="#1971c2", lw=1)
    points = ax.scatter(x, y, c=values, s=4, cmap="plasma")
    fig.colorbar(points, ax=ax, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    return _save(fig, out)


# --- gait data plots (issue 4: datasets, ElevInterp) ------------------------------------


def plot_elevation_datasets(datasets, out, *, title="Sagittal elevation angles"):
    """Foot, shank, thigh and pelvis elevation angles of datasets over the stride.

    Parameters
    ----------
    datasets : sequence of crowdwalk.gait.datasets.ElevationDataset
        Curves (N, 4) [rad] on t = k / N; drawn in degrees against % stride.
    out : str or Path
        PNG file to write.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for ax, k, name in zip(axes.flat, range(4), ("foot", "shank", "thigh", "pelvis"),
                           strict=True):
        for d in datasets:
            n = d.angles.shape[0]
            pct = np.arange(n + 1) * 100.0 / n
            curve = np.rad2deg(np.append(d.angles[:, k], d.angles[0, k]))
            ax.plot(pct, curve, label=d.name, lw=1.4 if d.kind == "level" else 1.0,
                    ls="-" if d.kind == "level" else "--")
        ax.set_title(name)
        ax.set_ylabel("elevation [deg]")
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("stride [%] (0 = heel strike)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title)
    return _save(fig, out)


def plot_elevinterp_region(interp, leg, out, *, requests=None, title=None):
    """ElevInterp's Height/Length space for one body: legal region, datasets, requests.

    Parameters
    ----------
    interp : crowdwalk.gait.elevinterp.ElevInterp
    leg : LegLike
        One body's leg dimensions [m] (floats).
    requests : (k, 2) array, optional
        Requested (step length, step height) [m]; drawn with the steps produced for them.
    out : str or Path
        PNG file to write.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    region = interp.legal_region(leg)
    closed = np.vstack([region, region[:1]])
    ax.fill(closed[:, 0], closed[:, 1], alpha=0.15, label="legal region (hull)")
    steps = interp.source_steps(leg)
    ax.plot(steps[:, 0], steps[:, 1], "ko")
    for (x, y), d in zip(steps, interp.datasets, strict=True):
        ax.annotate(d.name, (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
    if requests is not None:
        req = np.asarray(requests, dtype=float).reshape(-1, 2)
        dims = {k: np.full(len(req), float(np.ravel(getattr(leg, k))[0]))
                for k in ("thigh", "shank", "ankle_height", "heel_offset", "toe_offset")}
        if getattr(leg, "ball_offset", None) is not None:
            dims["ball_offset"] = np.full(len(req), float(np.ravel(leg.ball_offset)[0]))
        from crowdwalk.gait.elevinterp import SagittalLeg

        res = interp.request(SagittalLeg(**dims), req[:, 0], req[:, 1])
        ax.plot(req[:, 0], req[:, 1], "x", color="tab:red", label="requested")
        ax.plot(res.step_length, res.step_height, ".", color="tab:green", label="produced")
    ax.set_xlabel("step length [m]")
    ax.set_ylabel("step height [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "ElevInterp Height/Length space (Eq. 10)")
    return _save(fig, out)


def plot_gait_validation(generated, reference, metrics, out,
                         *, title="Generated joint flexion against Winter (1991), natural cadence"):
    """Generated hip, knee and ankle flexion over a level stride against measured means
    (issue 4 validation, as Sun & Metaxas 2001 Fig. 15).

    Parameters
    ----------
    generated : mapping
        ``t`` (F,) stride fraction [1] and ``Hip``/``Knee``/``Ankle`` (F,) flexion [deg].
    reference : mapping
        ``t`` (M,) and per joint the mean (M,) and ``<joint> sd`` (M,) [deg].
    metrics : mapping of joint -> {"rms", "correlation", ...}
        Shown in the panel titles (RMS [deg], Pearson r).
    out : path
        PNG file.

    Returns
    -------
    pathlib.Path
    """
    plt = _pyplot()
    joints = ("Hip", "Knee", "Ankle")
    fig, axes = plt.subplots(1, 3, figsize=(10.5, 3.2))
    for ax, joint in zip(axes, joints, strict=True):
        t_ref = 100 * np.asarray(reference["t"], dtype=float)
        mean = np.asarray(reference[joint], dtype=float)
        sd = np.asarray(reference[f"{joint} sd"], dtype=float)
        ax.fill_between(t_ref, mean - sd, mean + sd, color="0.85", label="Winter ± 1 SD")
        ax.plot(t_ref, mean, color="0.4", lw=1, ls="--", label="Winter mean")
        ax.plot(100 * np.asarray(generated["t"]), generated[joint], color="C0", lw=1.5,
                label="generated")
        m = metrics.get(joint, {})
        ax.set_title(f"{joint}: RMS {m.get('rms', np.nan):.1f}°, r = "
                     f"{m.get('correlation', np.nan):.3f}", fontsize=9)
        ax.set_xlabel("stride [%]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("flexion (+) [deg]")
    axes[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, out)


# --- planning plots (issue 3) -----------------------------------------------------------


def plot_plan(profile, plans, out, *, labels=None, title: str | None = None):
    """A footstep plan on its ground profile: profile, footholds and swing-ankle curves.

    Parameters
    ----------
    profile : planners.GroundProfile
        Ground along the path [m].
    plans : planners.Plan or sequence of Plan
        One plan, or several to compare on the same profile (e.g. Fig. 11: ``fixed``
        against ``best_first``), drawn with vertical offsets so they do not overlap.
    out : path
        PNG file.
    labels : sequence of str, optional
        One label per plan (default: the planner names and energy per metre).
    title : str, optional

    Returns
    -------
    pathlib.Path
    """
    from planners import Plan
    from planners.swing import bezier_points

    plans = [plans] if isinstance(plans, Plan) else list(plans)
    plt = _pyplot()
    fig, axes = plt.subplots(len(plans), 1, figsize=(8, 2.6 * len(plans)), squeeze=False,
                             sharex=True)
    lo = min(min(p.footholds_s.min(), p.trailing_s) for p in plans) - 0.4
    hi = max(p.footholds_s.max() for p in plans) + 0.5
    s = np.concatenate([[lo], profile.s[(profile.s > lo) & (profile.s < hi)], [hi]])
    z = profile.height(s)
    inside = (profile.s > lo) & (profile.s < hi)
    s, z = np.concatenate([[lo], profile.s[inside], [hi]]), np.concatenate(
        [[profile.height(lo)], profile.z[inside], [profile.height(hi)]])
    for i, (ax, p) in enumerate(zip(axes[:, 0], plans, strict=True)):
        ax.fill_between(s, z, z.min() - 0.1, color="0.85", step=None)
        ax.plot(s, z, color="0.3", lw=1.2)
        for k, ctrl in enumerate(p.swing_controls):
            pts = bezier_points(ctrl, 40)
            ax.plot(pts[:, 0], pts[:, 1], color="tab:blue", lw=1.0, alpha=0.8,
                    label="swing ankle" if k == 0 else None)
            ax.plot(ctrl[:, 0], ctrl[:, 1], ":", color="tab:blue", lw=0.6, alpha=0.5)
        ax.plot(p.footholds_s, p.footholds_z, "v", color="tab:red", ms=7, label="footholds")
        ax.plot([p.trailing_s], [profile.height(p.trailing_s)], "v", color="0.5", ms=6,
                label="trailing foot")
        for k, (fs, fz) in enumerate(zip(p.footholds_s[1:], p.footholds_z[1:], strict=True)):
            ax.annotate(f"{p.step_lengths[k]:.2f}", (fs, fz), textcoords="offset points",
                        xytext=(0, -14), ha="center", fontsize=7, color="tab:red")
        label = labels[i] if labels is not None else (
            f"{p.planner}: {p.energy_per_metre:.2f} J/(kg m)" if p.ok
            else f"{p.planner}: {p.status}")
        ax.set_title(label, fontsize=9, loc="left")
        ax.set_ylabel("z [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("s along the path [m]")
    if title:
        fig.suptitle(title, fontsize=10)
    return _save(fig, out)


# --- planner comparison by terrain type (issue 5: crowdwalk compare) -------------------


def plot_by_terrain(values, out, *, ylabel: str, title: str, errors=None):
    """Grouped bars: one group per terrain type, one bar per planner.

    Parameters
    ----------
    values : mapping of planner -> mapping of terrain type name -> float
        e.g. energy per metre [J/(kg m)] of each planner on each terrain type; a missing
        or non-finite value leaves its bar out.
    out : path
        PNG file.
    ylabel : str
        Y axis label with its unit.
    errors : mapping of planner -> mapping of terrain type name -> (low, high), optional
        An interval per bar (e.g. a 95 % confidence interval), drawn as an error bar.

    Returns
    -------
    pathlib.Path
    """
    if not values:
        raise invalid("plot_by_terrain", "values", "a non-empty mapping", values)
    planners = list(values)
    kinds = sorted({k for v in values.values() for k in v})
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(max(4.0, 1.3 * len(kinds) * len(planners) ** 0.5), 3.6))
    width = 0.8 / len(planners)
    x = np.arange(len(kinds))
    for i, name in enumerate(planners):
        ys = np.array([values[name].get(k, np.nan) for k in kinds], dtype=float)
        bars = ax.bar(x + (i - (len(planners) - 1) / 2) * width, np.nan_to_num(ys), width,
                      label=name)
        if errors is not None and name in errors:
            lo, hi = (np.array([errors[name].get(k, (np.nan, np.nan))[j] for k in kinds],
                               dtype=float) for j in (0, 1))
            ok = np.isfinite(ys) & np.isfinite(lo) & np.isfinite(hi)
            if ok.any():
                ax.errorbar((x + (i - (len(planners) - 1) / 2) * width)[ok], ys[ok],
                            yerr=[np.maximum(ys[ok] - lo[ok], 0), np.maximum(hi[ok] - ys[ok], 0)],
                            fmt="none", ecolor="black", elinewidth=0.8, capsize=2)
        for bar, y in zip(bars, ys, strict=True):
            if np.isfinite(y):
                ax.annotate(f"{y:.3g}", (bar.get_x() + bar.get_width() / 2, y),
                            xytext=(0, 2), textcoords="offset points", ha="center",
                            fontsize=7)
    ax.set_xticks(x, kinds)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return _save(fig, out)
