#!/usr/bin/python3
"""Measure a vesph planar die-swell run: the swell ratio of the extrudate against time at
stations beyond the die exit, its steady value and fluctuation, and the velocity and stress
profiles across the die, as CSV, JSON and PNG.

Usage
-----
    /usr/bin/python3 tools/die_swell_measure.py RUN.h5
        [--stations 0.21 0.23 0.25] [--window 1.0] [--filled-window 4] [--die-width 0.01]
        [--die-exit 0.2]
        [--from T] [--until T] [--expect-min R] [--expect-max R]
        [--profile-x 0.185] [--profile-time T] [--xlim 0.15 0.30]
        [--out-dir DIR] [--prefix NAME] [--no-png]

All lengths are in m, times in s, velocities in m/s, stresses in Pa (SI, as in the file).

The geometry
------------
A 2D die (channel) of width W (--die-width, default 0.01 m) along x with walls at y = 0 and
y = W, from the inlet to the die exit at x = --die-exit (default 0.2 m); beyond the exit the
fluid leaves as a free extrudate. Only 2D outputs are accepted. dx is the root attribute dx
(else particles.spacing of the stored scene).

Swell ratio (every frame, fluid particles only: kind 0)
-------------------------------------------------------
At each station x_s (--stations, default 0.21 0.23 0.25 m) the slab
|x - x_s| <= window dx / 2 (--window, in units of dx, default 1: a slab one dx wide) is taken;
the extrudate width is

    width = (max y - min y) + dx

over the fluid particles in the slab: each particle stands for a strip dx wide, so a die
full of 25 particle rows (W = 25 dx) gives a width of 25 dx = W. The swell ratio is
width / W. It is NaN when fewer than 2 fluid particles are in the slab (the extrudate has not
reached the station yet). The average is the mean of the stations' ratios, NaN unless all
stations are defined. Walls (kind 1), dummies (2) and inflow buffer particles (3) are ignored.

Filled width (every frame): the extrudate's volume per unit length
--------------------------------------------------------------------
The width above is the envelope: voids between separated particle lanes count as fluid. The
filled width counts only what the particles hold: over the slab
x_s - F dx/2 <= x < x_s + F dx/2 (--filled-window F, in dx, default 4; half-open, so that a
lattice puts exactly F columns in it)

    filled width = sum over its fluid particles of m_i / rho_i  /  (F dx)

and the filled ratio is filled width / W (NaN with < 2 particles, or when the frames lack
mass or density). For a compact extrudate it equals the envelope ratio (to the counting noise
of the slab's edges); envelope - filled is the share of voids. In a steady extrudate moving
as a plug at U_e it is Q / (U_e W), the swell of volume conservation.

Steady value
------------
Over the frames with time >= --from T whose average is defined (default: the later half of
the frames whose average is defined, i.e. frames n//2 ... n-1 of those n frames), and with
--until T only those with time <= T (to compare windows of two runs over the same times): the mean
of the average ratio, its standard deviation (population, ddof = 0) and its half range
(max - min)/2, and each station's mean and standard deviation over the same frames.
--expect-min R / --expect-max R check that the steady mean lies in [R_min, R_max]; a failed
check (or no frame to check) gives exit status 1.

Profiles across the die
-----------------------
At --profile-x (default 0.185 m, inside the die) the fluid particles with
|x - profile_x| <= dx/2 of the last frame (or of the frame nearest --profile-time T), sorted
by y: y [m], |v| [m/s], and, when the frames have extra_stress (a viscoelastic model),
T_xx, T_yy, T_xy and N1 = T_xx - T_yy [Pa]. Individual particles, not averages.

Checks on the input
-------------------
- A station must lie beyond the die exit (x_s > die exit), else exit status 2: inside the
  die the width is the die's, not the extrudate's. A station whose slab reaches back into the
  die (x_s - window dx/2 < die exit) is measured with a warning.
- --profile-x must lie inside the die (< die exit), else exit status 2; no fluid particle
  within dx/2 of it at the profile frame gives exit status 1.
- A missing file, a file that is not HDF5 or not a vesph output, a 3D output, no frames, or
  frames lacking kind/position give exit status 1 with 'die_swell_measure: error: ...'.

Outputs (in --out-dir, default the directory of the file; PREFIX defaults to the scene name)
-------------------------------------------------------------------------------------------
PREFIX_swell.csv     time_s, ratio_x<station> for each station, ratio_average, then
                     filled_x<station> and filled_average (nan where undefined), one row
                     per frame;
PREFIX_summary.json  stations (x, mean, std, frames defined, filled_mean, filled_std),
                     average (mean, std, half_range, min, max), filled (mean, std), frames_used, time_window [first, last], the
                     settings, and the checks' outcome (NaN written as null);
PREFIX_profiles.csv  y_m, speed_m_s[, Txx_Pa, Tyy_Pa, Txy_Pa, N1_Pa];
PREFIX_swell.png     ratio against time for each station and the average, the steady mean
                     dashed and the steady window shaded;
PREFIX_profiles.png  one panel per quantity against y (|v|, T_xx, T_yy, T_xy, N1);
PREFIX_n1.png        the particles of the profile frame around the die exit (--xlim, default
                     0.15 ... 0.30 m), fluid coloured by N1 (diverging map centred at 0;
                     by |v| without extra_stress), walls grey, equal aspect, the die exit,
                     the stations and the profile x marked.
--no-png writes the CSV and JSON files only.

Exit status: 0 when the run was measured and all requested checks pass; 1 when a check fails
or the file cannot be used; 2 for usage errors (bad options, a station inside the die, a
profile x outside it).
"""

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

from vesph import output as vesph_output
from vesph.output import Output, ToolError

PROG = "die_swell_measure"
STRESS_COLS = ("Txx_Pa", "Tyy_Pa", "Txy_Pa", "N1_Pa")


class Run(Output):
    """The header and frame list of one vesph output (a run still writing it may be measured:
    the file is opened without locking, a half-written last frame skipped)."""

    def __init__(self, path):
        super().__init__(path, live=True, partial_last_frame=True)
        self.has_stress = self.has(len(self.frames) - 1, "extra_stress")

    def _check_scene(self):
        path = self.path
        if self.dim != 2:
            raise ToolError(f"{path}: a {self.dim}D output; die_swell_measure measures 2D "
                            "(planar) die swell only")
        if not (self.dx > 0):
            raise ToolError(f"{path}: particle spacing dx = {self.dx:g}, expected > 0")

    def read_frame(self, k, full=False):
        """Frame k: dict with kind [n], position [n, 2] and (when mass and density are there)
        volume [n]; with full also velocity [n, 2] and (when present) extra_stress [n, 3]
        (xx, xy, yy). None for an unreadable last frame of a file still being written."""
        need = ("kind", "position") + (("velocity",) if full else ())
        d = self.read_or_skip(k, need, optional=("mass", "density") + (("extra_stress",) if full else ()))
        if d is None:
            return None
        m, rho = d.pop("mass", None), d.pop("density", None)
        if m is not None and rho is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                d["volume"] = m / rho
        return d


# -------------------------------------------------------------------------- measures
def slab(x, centre, half):
    """Mask of |x - centre| <= half (inclusive up to rounding)."""
    return np.abs(x - centre) <= half * (1.0 + 1e-9)


def swell_ratio(pos, station, half, dx, W):
    """(ratio, particles in the slab): ((max y - min y) + dx) / W; nan with < 2 particles."""
    m = slab(pos[:, 0], station, half)
    n = int(np.count_nonzero(m))
    if n < 2:
        return float("nan"), n
    y = pos[m, 1]
    return float((y.max() - y.min() + dx) / W), n


def filled_ratio(pos, vol, station, half, W):
    """Sum of the particle volumes in station - half <= x < station + half over 2 half W;
    nan with < 2 particles or without volumes."""
    if vol is None:
        return float("nan")
    m = (pos[:, 0] >= station - half * (1.0 + 1e-9)) & (pos[:, 0] < station + half * (1.0 - 1e-9))
    if np.count_nonzero(m) < 2:
        return float("nan")
    return float(vol[m].sum() / (2.0 * half) / W)


def mean_if_all(values):
    return float(np.mean(values)) if all(math.isfinite(r) for r in values) else float("nan")


def measure_swell(run, a):
    """Rows: dicts time, ratios [per station], average, filled [per station], filled_average."""
    rows = []
    half = 0.5 * a.window * run.dx
    half_filled = 0.5 * a.filled_window * run.dx
    for k, (nm, t) in enumerate(run.frames):
        fr = run.read_frame(k)
        if fr is None:
            break
        fluid = fr["kind"] == 0
        pos = fr["position"][fluid]
        vol = fr["volume"][fluid] if "volume" in fr else None
        ratios = [swell_ratio(pos, xs, half, run.dx, a.die_width)[0] for xs in a.stations]
        filled = [filled_ratio(pos, vol, xs, half_filled, a.die_width) for xs in a.stations]
        rows.append({"frame": nm, "time": t, "ratios": ratios, "average": mean_if_all(ratios),
                     "filled": filled, "filled_average": mean_if_all(filled)})
    return rows


def steady(rows, a):
    """Statistics over the steady window (see the module docstring)."""
    defined = [r for r in rows if math.isfinite(r["average"])]
    if a.from_time is not None:
        win = [r for r in defined if r["time"] >= a.from_time - 1e-12 * max(1.0, abs(a.from_time))]
        rule = f"--from {a.from_time:g} s"
    else:
        win = defined[len(defined) // 2:]
        rule = "the later half of the frames with a defined average"
    if a.until_time is not None:
        # an upper end: windows of one run compared with another run's over the same times
        win = [r for r in win if r["time"] <= a.until_time + 1e-12 * max(1.0, abs(a.until_time))]
        rule += f", --until {a.until_time:g} s"
    nan = float("nan")
    res = {"rule": rule, "frames_used": len(win),
           "time_window": [win[0]["time"], win[-1]["time"]] if win else [nan, nan],
           "mean": nan, "std": nan, "half_range": nan, "min": nan, "max": nan,
           "filled": {"mean": nan, "std": nan}, "stations": []}
    if win:
        v = np.array([r["average"] for r in win])
        res.update(mean=float(v.mean()), std=float(v.std()),
                   half_range=float(0.5 * (v.max() - v.min())),
                   min=float(v.min()), max=float(v.max()))
        f = np.array([r["filled_average"] for r in win])
        res["filled"] = {"mean": float(f.mean()), "std": float(f.std())}
    for j, xs in enumerate(a.stations):
        v = np.array([r["ratios"][j] for r in win])
        f = np.array([r["filled"][j] for r in win])
        res["stations"].append({
            "x_m": xs, "mean": float(v.mean()) if len(v) else nan,
            "std": float(v.std()) if len(v) else nan,
            "frames_defined": int(sum(math.isfinite(r["ratios"][j]) for r in rows)),
            "filled_mean": float(f.mean()) if len(f) else nan,
            "filled_std": float(f.std()) if len(f) else nan})
    return res


def profile_frame(run, a):
    """Index of the profile frame: the last, or the one nearest --profile-time."""
    if a.profile_time is None:
        return len(run.frames) - 1
    times = np.array([t for _, t in run.frames])
    return int(np.argmin(np.abs(times - a.profile_time)))


def profiles(run, fr, a):
    """Rows (dicts) of the fluid particles within dx/2 of profile_x, sorted by y."""
    kind, pos, vel = fr["kind"], fr["position"], fr["velocity"]
    m = (kind == 0) & slab(pos[:, 0], a.profile_x, 0.5 * run.dx)
    if not np.any(m):
        fl = pos[kind == 0, 0]
        rng = (f"fluid x from {fl.min():g} to {fl.max():g} m" if len(fl)
               else "no fluid particles at all")
        raise ToolError(f"{run.path}: no fluid particle within dx/2 = {0.5 * run.dx:g} m of "
                        f"--profile-x {a.profile_x:g} m at t = {a.prof_t:g} s ({rng})")
    idx = np.nonzero(m)[0]
    idx = idx[np.argsort(pos[idx, 1], kind="stable")]
    out = []
    T = fr.get("extra_stress")
    for i in idx:
        r = {"y_m": float(pos[i, 1]), "speed_m_s": float(np.hypot(*vel[i]))}
        if T is not None:
            txx, txy, tyy = (float(c) for c in T[i])
            r.update(Txx_Pa=txx, Tyy_Pa=tyy, Txy_Pa=txy, N1_Pa=txx - tyy)
        out.append(r)
    return out


# ------------------------------------------------------------------------------ output
def fmt(v):
    return repr(float(v)) if isinstance(v, (float, np.floating)) else v


def station_header(xs):
    return f"ratio_x{xs:g}"


def write_swell_csv(path, rows, a):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s"] + [station_header(x) for x in a.stations] + ["ratio_average"]
                   + [f"filled_x{x:g}" for x in a.stations] + ["filled_average"])
        for r in rows:
            w.writerow([fmt(r["time"])] + [fmt(v) for v in r["ratios"]] + [fmt(r["average"])]
                       + [fmt(v) for v in r["filled"]] + [fmt(r["filled_average"])])


def write_profiles_csv(path, prof, has_stress):
    cols = ["y_m", "speed_m_s"] + (list(STRESS_COLS) if has_stress else [])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in prof:
            w.writerow([fmt(r[c]) for c in cols])


def json_clean(v):
    """NaN and inf as None (JSON has no NaN)."""
    if isinstance(v, dict):
        return {k: json_clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [json_clean(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


def plot_swell(png, rows, st, a, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    t = [r["time"] for r in rows]
    for j, xs in enumerate(a.stations):
        ax.plot(t, [r["ratios"][j] for r in rows], ".-", ms=3, lw=1, label=f"x = {xs:g} m")
    ax.plot(t, [r["average"] for r in rows], "k-", lw=2, label="average")
    ax.plot(t, [r["filled_average"] for r in rows], "-", color="tab:purple", lw=2,
            label="filled (void-free) average")
    if st["frames_used"]:
        ax.axhline(st["mean"], color="k", ls="--", lw=1,
                   label=f"steady mean {st['mean']:.4g} (std {st['std']:.2g})")
        t0, t1 = st["time_window"]
        ax.axvspan(t0, t1, color="0.85", alpha=0.5, lw=0, label="steady window")
    ax.axhline(1.0, color="0.5", ls=":", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("swell ratio  width / W")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title, fontsize="medium")
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


def plot_profiles(png, prof, has_stress, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("speed_m_s", "|v| [m/s]")]
    if has_stress:
        panels += [("Txx_Pa", "T_xx [Pa]"), ("Tyy_Pa", "T_yy [Pa]"), ("Txy_Pa", "T_xy [Pa]"),
                   ("N1_Pa", "N1 = T_xx - T_yy [Pa]")]
    n = len(panels)
    ncol = min(n, 3)
    nrow = math.ceil(n / ncol)
    fig, axs = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.8 * nrow), squeeze=False)
    y = [r["y_m"] for r in prof]
    for ax, (k, lab) in zip(axs.ravel(), panels):
        ax.plot(y, [r[k] for r in prof], "o-", ms=3, lw=1)
        ax.set_xlabel("y [m]")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    for ax in axs.ravel()[n:]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize="medium")
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


def plot_particles(png, fr, dx, a, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    kind, pos = fr["kind"], fr["position"]
    x0, x1 = a.xlim
    inx = (pos[:, 0] >= x0 - dx) & (pos[:, 0] <= x1 + dx)
    fl = inx & (kind == 0)
    wl = inx & (kind != 0)
    T = fr.get("extra_stress")
    if T is not None:
        c = T[fl, 0] - T[fl, 2]
        m = float(np.max(np.abs(c))) if c.size else 0.0
        m = m if m > 0 else 1.0
        cmap, norm, clab = "RdBu_r", Normalize(-m, m), "N1 = T_xx - T_yy [Pa]"
    else:
        c = np.hypot(fr["velocity"][fl, 0], fr["velocity"][fl, 1])
        hi = float(c.max()) if c.size and c.max() > 0 else 1.0
        cmap, norm, clab = "viridis", Normalize(0.0, hi), "|v| [m/s]"
    ys = pos[inx, 1]
    y0, y1 = (float(ys.min()) - 2 * dx, float(ys.max()) + 2 * dx) if ys.size else (0.0, 1.0)
    fig, ax = plt.subplots(figsize=(12, 5))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.apply_aspect()
    bb = ax.get_window_extent()
    pts = bb.width / (x1 - x0) * dx * 72.0 / fig.dpi     # points per dx
    s = max(0.5, (0.9 * pts) ** 2)
    ax.scatter(pos[wl, 0], pos[wl, 1], s=s, c="0.6", marker="s", lw=0, rasterized=True)
    sc = ax.scatter(pos[fl, 0], pos[fl, 1], s=s, c=c, cmap=cmap, norm=norm, marker="o",
                    lw=0, rasterized=True)
    fig.colorbar(sc, ax=ax, label=clab, shrink=0.8)
    ax.axvline(a.die_exit, color="k", ls="--", lw=0.8, label=f"die exit {a.die_exit:g} m")
    for xs in a.stations:
        ax.axvline(xs, color="tab:green", ls=":", lw=0.8)
    ax.axvline(a.profile_x, color="tab:purple", ls="-.", lw=0.8,
               label=f"profile x {a.profile_x:g} m")
    ax.plot([], [], color="tab:green", ls=":", lw=0.8, label="stations")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="x-small", loc="upper right")
    ax.set_title(title, fontsize="medium")
    fig.savefig(png, dpi=110, bbox_inches="tight")
    plt.close(fig)


# -------------------------------------------------------------------------------- main
def run(a, out=sys.stdout):
    p = lambda *s: print(*s, file=out)  # noqa: E731
    for xs in a.stations:
        if not (xs > a.die_exit):
            raise ToolError(f"station x = {xs:g} m is not beyond the die exit at "
                            f"{a.die_exit:g} m: inside the die the width is the die's; give "
                            "stations x > --die-exit", 2)
    if not (a.profile_x < a.die_exit):
        raise ToolError(f"--profile-x {a.profile_x:g} m is not inside the die (die exit at "
                        f"{a.die_exit:g} m): give a profile x < --die-exit", 2)
    r = Run(a.path)
    try:
        dx, W = r.dx, a.die_width
        half = 0.5 * a.window * dx
        p(f"== {r.name}: {r.path}")
        p(f"   dx = {dx:g} m, die width W = {W:g} m (W/dx = {W / dx:.4g}), die exit x = "
          f"{a.die_exit:g} m, slab |x - x_s| <= {half:g} m ({a.window:g} dx), "
          f"{len(r.frames)} frames, t = {r.frames[0][1]:g} ... {r.frames[-1][1]:g} s")
        for xs in a.stations:
            if xs - half < a.die_exit:
                r.notes.append(f"warning: the slab of station {xs:g} m reaches into the die "
                               f"(x_s - {half:g} m < die exit {a.die_exit:g} m)")
        if a.profile_x + 0.5 * dx > a.die_exit:
            r.notes.append(f"warning: the profile slab at {a.profile_x:g} m reaches beyond "
                           "the die exit")
        rows = measure_swell(r, a)
        k = profile_frame(r, a)
        if k >= len(rows):            # the last frame was unreadable (being written)
            k = len(rows) - 1
        a.prof_t = r.frames[k][1]
        fr = r.read_frame(k, full=True)
        if fr is None:
            raise ToolError(f"{r.path}: the profile frame cannot be read")
        has_stress = "extra_stress" in fr
        prof = profiles(r, fr, a)
        for n in r.notes:
            p("note: " + n)
        st = steady(rows, a)

        # --- report
        step = max(1, math.ceil(len(rows) / 16))
        show = sorted(set(range(0, len(rows), step)) | {len(rows) - 1})
        p("   " + f"{'t [s]':>10}" + "".join(f"{f'x={x:g}':>10}" for x in a.stations)
          + f"{'average':>10}")
        for j in show:
            q = rows[j]
            p("   " + f"{q['time']:10.4g}" + "".join(f"{v:10.4f}" for v in q["ratios"])
              + f"{q['average']:10.4f}")
        if step > 1:
            p(f"   (every {step} frames and the last; all frames in the CSV)")
        for s in st["stations"]:
            p(f"   station x = {s['x_m']:g} m: defined in {s['frames_defined']} of {len(rows)}"
              f" frames; steady mean {s['mean']:.5g}, std {s['std']:.3g}")
        if st["frames_used"]:
            t0, t1 = st["time_window"]
            p(f"   steady swell ratio ({st['rule']}: {st['frames_used']} frames, "
              f"t = {t0:g} ... {t1:g} s): mean {st['mean']:.5g}, std {st['std']:.3g}, "
              f"(max - min)/2 {st['half_range']:.3g}; filled (void-free) ratio: mean "
              f"{st['filled']['mean']:.5g}, std {st['filled']['std']:.3g}")
        else:
            p(f"   steady swell ratio: no frame with a defined average ({st['rule']})")
        p(f"   profile at x = {a.profile_x:g} m, frame t = {a.prof_t:g} s: {len(prof)} "
          f"particles, y = {prof[0]['y_m']:.4g} ... {prof[-1]['y_m']:.4g} m, max |v| "
          f"{max(q['speed_m_s'] for q in prof):.4g} m/s"
          + (f", max N1 {max(q['N1_Pa'] for q in prof):.4g} Pa" if has_stress else
             "; no extra_stress (Newtonian run): velocity only"))

        # --- checks
        ok = True
        checks = []
        if a.expect_min is not None or a.expect_max is not None:
            lo = a.expect_min if a.expect_min is not None else -math.inf
            hi = a.expect_max if a.expect_max is not None else math.inf
            m = st["mean"]
            if not st["frames_used"]:
                ok = False
                msg = "FAIL: no frame with a defined average swell ratio in the steady window"
            else:
                ok = lo <= m <= hi
                msg = (f"steady mean swell ratio {m:.5g} "
                       + ("within" if ok else "OUTSIDE") + f" [{lo:g}, {hi:g}]: "
                       + ("PASS" if ok else "FAIL"))
            checks.append({"expect_min": a.expect_min, "expect_max": a.expect_max,
                           "pass": bool(ok), "message": msg})
            p("   check " + msg)

        # --- files
        od = a.out_dir if a.out_dir is not None else os.path.dirname(os.path.abspath(r.path))
        os.makedirs(od, exist_ok=True)
        pre = a.prefix or r.name
        written = []
        fn = os.path.join(od, pre + "_swell.csv")
        write_swell_csv(fn, rows, a)
        written.append(fn)
        summary = {
            "file": os.path.abspath(r.path), "scene": r.name, "dx_m": dx,
            "die_width_m": W, "die_exit_m": a.die_exit, "window_dx": a.window,
            "frames": len(rows),
            "stations": st["stations"],
            "average": {k2: st[k2] for k2 in ("mean", "std", "half_range", "min", "max")},
            "filled": st["filled"], "filled_window_dx": a.filled_window,
            "frames_used": st["frames_used"], "time_window_s": st["time_window"],
            "from_s": a.from_time, "until_s": a.until_time, "window_rule": st["rule"],
            "profile": {"x_m": a.profile_x, "time_s": a.prof_t, "particles": len(prof),
                        "extra_stress": has_stress},
            "checks": checks, "notes": r.notes,
        }
        fn = os.path.join(od, pre + "_summary.json")
        with open(fn, "w") as fh:
            json.dump(json_clean(summary), fh, indent=2)
            fh.write("\n")
        written.append(fn)
        fn = os.path.join(od, pre + "_profiles.csv")
        write_profiles_csv(fn, prof, has_stress)
        written.append(fn)
        if not a.no_png:
            fn = os.path.join(od, pre + "_swell.png")
            plot_swell(fn, rows, st, a, f"die swell: {r.name}  (W = {W:g} m, slab "
                                        f"{a.window:g} dx)")
            written.append(fn)
            fn = os.path.join(od, pre + "_profiles.png")
            plot_profiles(fn, prof, has_stress, f"{r.name}: profiles at x = {a.profile_x:g} m,"
                                                f" t = {a.prof_t:g} s")
            written.append(fn)
            fn = os.path.join(od, pre + "_n1.png")
            plot_particles(fn, fr, dx, a, f"{r.name}: t = {a.prof_t:g} s, "
                           + ("N1" if has_stress else "|v| (no extra_stress)"))
            written.append(fn)
    finally:
        r.close()
    for w in written:
        p(f"wrote {w}")
    if checks:
        p("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="die_swell_measure.py",
        description="Swell ratio of a vesph planar die-swell run (2D) against time at "
                    "stations beyond the die exit, its steady mean and fluctuation, and the "
                    "velocity/stress profiles across the die, as CSV, JSON and PNG. Units: "
                    "m, s, m/s, Pa.",
        epilog="Width at a station = (max y - min y) + dx of the fluid particles within "
               "window*dx/2 of it; ratio = width / W (NaN with fewer than 2 particles). "
               "Stations must lie beyond the die exit and the profile x inside the die "
               "(exit status 2 otherwise). Exit status 1 when --expect-min/--expect-max "
               "fails or the file cannot be used.")
    ap.add_argument("path", metavar="RUN.h5", help="vesph output file (.h5)")
    ap.add_argument("--stations", type=float, nargs="+", default=[0.21, 0.23, 0.25],
                    metavar="X", help="station x positions [m] beyond the die exit "
                                      "(default 0.21 0.23 0.25)")
    ap.add_argument("--window", type=float, default=1.0, metavar="N",
                    help="slab width at a station in units of dx: particles with "
                         "|x - x_s| <= N dx/2 (default 1)")
    ap.add_argument("--filled-window", type=float, default=4.0, metavar="F",
                    help="slab width of the filled (void-free) width in units of dx: "
                         "x_s - F dx/2 <= x < x_s + F dx/2 (default 4)")
    ap.add_argument("--die-width", type=float, default=0.01, metavar="W",
                    help="die width W [m] (default 0.01)")
    ap.add_argument("--die-exit", type=float, default=0.2, metavar="X",
                    help="x of the die exit [m] (default 0.2)")
    ap.add_argument("--from", dest="from_time", type=float, metavar="T",
                    help="steady window: frames with time >= T [s] (default: the later half "
                         "of the frames whose average is defined)")
    ap.add_argument("--until", dest="until_time", type=float, metavar="T",
                    help="steady window: only frames with time <= T [s] as well (default: to "
                         "the last frame)")
    ap.add_argument("--expect-min", type=float, metavar="R",
                    help="check: steady mean swell ratio >= R (exit 1 otherwise)")
    ap.add_argument("--expect-max", type=float, metavar="R",
                    help="check: steady mean swell ratio <= R (exit 1 otherwise)")
    ap.add_argument("--profile-x", type=float, default=0.185, metavar="X",
                    help="x of the profiles across the die [m], inside it (default 0.185)")
    ap.add_argument("--profile-time", type=float, metavar="T",
                    help="profiles and particle picture at the frame nearest T [s] "
                         "(default: the last frame)")
    ap.add_argument("--xlim", type=float, nargs=2, default=[0.15, 0.30], metavar=("X0", "X1"),
                    help="x range of the particle picture [m] (default 0.15 0.30)")
    ap.add_argument("--out-dir", metavar="DIR",
                    help="directory for the outputs (default: that of the file)")
    ap.add_argument("--prefix", metavar="NAME",
                    help="file name prefix (default: the scene name)")
    ap.add_argument("--no-png", action="store_true", help="write the CSV and JSON files only")
    a = ap.parse_args(argv)
    for nm, v in (("--window", a.window), ("--filled-window", a.filled_window),
                  ("--die-width", a.die_width)):
        if not (math.isfinite(v) and v > 0):
            ap.error(f"{nm} must be a positive number, got {v:g}")
    for nm, v in [("--die-exit", a.die_exit), ("--profile-x", a.profile_x)] + [
            ("--stations", x) for x in a.stations] + [
            (n2, v2) for n2, v2 in (("--from", a.from_time), ("--until", a.until_time),
                                    ("--profile-time", a.profile_time),
                                    ("--expect-min", a.expect_min),
                                    ("--expect-max", a.expect_max)) if v2 is not None]:
        if not math.isfinite(v):
            ap.error(f"{nm} must be a finite number, got {v:g}")
    if not (a.xlim[0] < a.xlim[1]):
        ap.error(f"--xlim needs X0 < X1, got {a.xlim[0]:g} {a.xlim[1]:g}")
    if (a.expect_min is not None and a.expect_max is not None
            and a.expect_min > a.expect_max):
        ap.error(f"--expect-min {a.expect_min:g} is above --expect-max {a.expect_max:g}")
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
