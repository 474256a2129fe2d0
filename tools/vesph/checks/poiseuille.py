#!/usr/bin/python3
"""Check a vesph plane-Poiseuille (body-force driven channel) run against the
analytic transient solution.

Usage
-----
    /usr/bin/python3 tools/poiseuille_check.py H5FILE [--times T ...]
        [--tolerance 0.02] [--time-rtol 1e-6] [--png OUT.png] [--csv OUT.csv]

Arguments
---------
H5FILE        vesph output file in format "vesph-1" (DIR/<name>.h5).
--times T ..  output times [s] to check.  For each T the frame whose time
              attribute is closest to T is used, provided
              |t_frame - T| <= time_rtol * max(|T|, 1e-300); a requested time
              with no such frame is an error.  Default: every frame with
              time > 0.
--tolerance   pass threshold for the velocity error, as a fraction of the
              steady centreline velocity (default 0.02, i.e. 2 %).
--time-rtol   relative tolerance used to match frame times to --times
              (default 1e-6).
--png FILE    write a plot: simulated vx of the fluid particles (dots) and the
              analytic profiles (lines) for each checked time;
              x axis vx [m/s], y axis y [m].
--csv FILE    write the per-frame table as CSV (same columns as printed).

What it computes
----------------
All physical inputs come from the resolved scene TOML stored in the root
attribute ``scene``:
    rho  = fluid.density                          [kg/m^3]
    mu   = fluid.viscosity (dynamic)              [Pa s]
    nu   = mu / rho (kinematic)                   [m^2/s]
    F    = effects.body_force.acceleration[0]     [m/s^2]
    y0   = min over [[blocks]] with kind "fluid" of min[1]        [m]
    H    = max over those blocks of max[1]  -  y0                  [m]
    (walls with treatment = "image": y0 and y0 + H are their surfaces, the rows of
    boundary particles: the floor's max[1] and the ceiling's min[1])
    (a wall with slip = "free" on one side, above the fluid or below it: the channel
    is half of one of height 2 H whose middle is that wall, the free-slip wall a plane
    of symmetry: y0 and H are those of the whole channel, the steady velocity at the
    free-slip wall F (2H)^2/(8 nu))
The analytic start-up velocity (fluid at rest at t = 0, no-slip walls at
y = y0 and y = y0 + H) is

    v(y,t) = F/(2 nu) s (H - s)
             - sum_{n>=0} 4 F H^2 / (nu pi^3 (2n+1)^3) sin((2n+1) pi s / H)
                          exp(-(2n+1)^2 pi^2 nu t / H^2)        with s = y - y0

in [m/s].  For every checked frame the tool reports
    error        = max over fluid particles (kind == 0) of |vx - v(y,t)|
                   divided by the steady centreline velocity F H^2 / (8 nu)
                   (printed in %),
    density dev. = max over fluid particles of |rho - rho0| / rho0  (-),
    fluid mass   = sum of the fluid particles' mass  [kg; kg/m per unit
                   depth in 2D],
    mass drift   = (mass - mass of frame 0) / mass of frame 0   (-), where
                   frame 0 is the first frame stored in the file.

Exit status: 0 when every checked frame has error < tolerance,
|mass drift| < 1e-12 and, when the scene set the sound speed by the rule of
thesis eq. (3.38), a max density deviation within its delta; 1 otherwise (each failing frame is named on stderr);
2 for usage errors (argparse).

The analytic solution is importable:
    from poiseuille_check import analytic_velocity
"""

import argparse
import csv
import sys

import numpy as np

from vesph.analytic import analytic_velocity  # noqa: F401 (the tool's reference, also imported from here)
from vesph.output import Output, ToolError

MASS_DRIFT_LIMIT = 1e-12


def scene_parameters(scene):
    """Extract (rho [kg/m^3], mu [Pa s], F [m/s^2], y0 [m], H [m]) from the
    parsed scene dictionary; raises ValueError with a clear message."""
    try:
        rho = float(scene["fluid"]["density"])
    except (KeyError, TypeError):
        raise ValueError("scene has no fluid.density")
    try:
        mu = float(scene["fluid"]["viscosity"])
    except (KeyError, TypeError, ValueError):
        raise ValueError("scene has no numeric fluid.viscosity "
                         "(this check is for a Newtonian fluid)")
    try:
        F = float(scene["effects"]["body_force"]["acceleration"][0])
    except (KeyError, TypeError, IndexError):
        raise ValueError("scene has no effects.body_force.acceleration")
    fluid_blocks = [b for b in scene.get("blocks", []) if b.get("kind") == "fluid"]
    if not fluid_blocks:
        raise ValueError("scene has no [[blocks]] with kind = \"fluid\"")
    y0 = min(float(b["min"][1]) for b in fluid_blocks)
    H = max(float(b["max"][1]) for b in fluid_blocks) - y0
    # Image walls (Fang et al. 2006 §3.3): the wall surfaces are their boundary particles'
    # rows, one spacing from the fluid (the fluid block's edges are half a spacing off).
    images = [b for b in scene.get("blocks", [])
              if b.get("kind") == "wall" and b.get("treatment") == "image"]
    if images:
        top = y0 + H
        floors = [float(b["max"][1]) for b in images if float(b["normal"][1]) > 0]
        ceilings = [float(b["min"][1]) for b in images if float(b["normal"][1]) < 0]
        if floors:
            y0 = max(floors)
        if ceilings:
            top = min(ceilings)
        H = top - y0
    if H <= 0:
        raise ValueError(f"fluid blocks have non-positive height H = {H}")
    # A free-slip wall (slip = "free", docs/theory.md §6.4) is a plane of symmetry: the fluid
    # is one half of a channel of height 2 H between no-slip walls.
    free = [b for b in scene.get("blocks", [])
            if b.get("kind") == "wall" and b.get("slip") == "free"]
    above = [b for b in free if "min" in b and float(b["min"][1]) >= y0 + H - 1e-9 * H]
    below = [b for b in free if "max" in b and float(b["max"][1]) <= y0 + 1e-9 * H]
    if len(free) != len(above) + len(below) or (above and below):
        raise ValueError("slip = \"free\" walls: this check takes one free-slip wall, a box above "
                         "the fluid or below it (the channel's plane of symmetry)")
    if below:
        y0 -= H
    if free:
        H *= 2.0
    if rho <= 0 or mu <= 0:
        raise ValueError("fluid.density and fluid.viscosity must be > 0")
    return rho, mu, F, y0, H


def select_frames(frames, times, time_rtol):
    """Frames to check: closest frame per requested time (within time_rtol),
    or all frames with time > 0.  Returns (selected, problems)."""
    if not times:
        return [f for f in frames if f[1] > 0.0], []
    selected, problems = [], []
    ftimes = np.array([f[1] for f in frames])
    for T in times:
        i = int(np.argmin(np.abs(ftimes - T)))
        if abs(ftimes[i] - T) <= time_rtol * max(abs(T), 1e-300):
            if frames[i] not in selected:
                selected.append(frames[i])
        else:
            problems.append(f"no frame at requested time {T:.9g} s "
                            f"(closest frame {frames[i][0]} has t = {ftimes[i]:.9g} s)")
    selected.sort(key=lambda f: f[0])
    return selected, problems


def fluid_mass(fr):
    """The total mass of the fluid particles of a frame (dict with kind and mass), kg."""
    return float(np.sum(fr["mass"][fr["kind"] == 0], dtype=np.float64))


COLUMNS = ["frame", "time_s", "step", "n_fluid", "error_percent",
           "max_density_deviation", "fluid_mass", "mass_drift", "status"]


def check(path, times=None, tolerance=0.02, time_rtol=1e-6, png=None, csv_path=None,
          out=sys.stdout, err=sys.stderr):
    """Run the check; returns the exit status (0 pass, 1 fail)."""
    try:
        h5 = Output(path)
    except ToolError as e:
        print(f"FAIL: {e}", file=err)
        return 1
    with h5:
        scene = h5.scene
        try:
            rho0, mu, F, y0, H = scene_parameters(scene)
        except ValueError as e:
            print(f"FAIL: {path}: {e}", file=err)
            return 1
        # (name, time, step, index) of each frame, in time order
        frames = [(name, t, step, k) for k, ((name, t), step) in enumerate(zip(h5.frames, h5.steps))]
        nu = mu / rho0
        u_centre = F * H * H / (8.0 * nu)
        if u_centre == 0.0:
            print("FAIL: body force is zero, nothing to compare", file=err)
            return 1
        selected, problems = select_frames(frames, times or [], time_rtol)
        if not selected and not problems:
            problems.append("no frame with time > 0 to check")

        # The density criterion: the relative density variation delta that set the sound
        # speed by thesis eq. (3.38), when the scene used that rule.
        ss = scene.get("effects", {}).get("equation_of_state", {}).get("sound_speed")
        delta = float(ss["delta"]) if isinstance(ss, dict) and "delta" in ss else None

        m_ref = fluid_mass(h5.read(0, ("kind", "mass")))
        print(f"file: {path}", file=out)
        print(f"scene: {scene.get('name', '?')}   rho0 = {rho0:.6g} kg/m^3   "
              f"mu = {mu:.6g} Pa s   nu = {nu:.6g} m^2/s", file=out)
        print(f"F = {F:.6g} m/s^2   y0 = {y0:.6g} m   H = {H:.6g} m   "
              f"steady centreline velocity F H^2/(8 nu) = {u_centre:.6g} m/s", file=out)
        print(f"reference fluid mass (frame {frames[0][0]}, t = {frames[0][1]:.6g} s)"
              f" = {m_ref:.12g}", file=out)
        print(f"pass if error < {100 * tolerance:g} % and |mass drift| < "
              f"{MASS_DRIFT_LIMIT:g}"
              + (f" and max density deviation <= delta = {delta:g} (eq. 3.38)" if delta else ""),
              file=out)

        rows, curves = [], []
        for name, t, step, k in selected:
            g = h5.read(k, ("kind", "position", "velocity", "density", "mass"))
            fl = g["kind"] == 0
            nfl = int(np.count_nonzero(fl))
            if nfl == 0:
                problems.append(f"frame {name} (t = {t:.6g} s): no fluid particles")
                continue
            pos = g["position"][fl]
            vx = g["velocity"][fl, 0]
            rho = g["density"][fl]
            y = pos[:, 1]
            v_exact = analytic_velocity(y, t, F, nu, H, y0)
            error = float(np.max(np.abs(vx - v_exact))) / abs(u_centre)
            dens_dev = float(np.max(np.abs(rho - rho0))) / rho0
            mass = fluid_mass(g)
            drift = (mass - m_ref) / m_ref if m_ref != 0 else float("nan")
            reasons = []
            if not error < tolerance:
                reasons.append(f"velocity error {100 * error:.4g} % >= {100 * tolerance:g} %")
            if not abs(drift) < MASS_DRIFT_LIMIT:
                reasons.append(f"mass drift {drift:.3e} exceeds {MASS_DRIFT_LIMIT:g}")
            if delta is not None and not dens_dev <= delta:
                reasons.append(f"density deviation {dens_dev:.3e} exceeds delta = {delta:g}")
            if reasons:
                problems.append(f"frame {name} (t = {t:.6g} s): " + "; ".join(reasons))
            rows.append({"frame": name, "time_s": t, "step": step, "n_fluid": nfl,
                         "error_percent": 100.0 * error,
                         "max_density_deviation": dens_dev, "fluid_mass": mass,
                         "mass_drift": drift, "status": "FAIL" if reasons else "ok"})
            curves.append((t, vx, y))

        header = (f"{'frame':>8} {'time [s]':>12} {'step':>9} {'N_fluid':>8} "
                  f"{'error [%]':>11} {'max|drho|/rho0':>15} {'fluid mass':>18} "
                  f"{'mass drift':>11}  status")
        print(header, file=out)
        for r in rows:
            print(f"{r['frame']:>8} {r['time_s']:12.6g} {r['step']:9d} {r['n_fluid']:8d} "
                  f"{r['error_percent']:11.5f} {r['max_density_deviation']:15.4e} "
                  f"{r['fluid_mass']:18.12g} {r['mass_drift']:11.2e}  {r['status']}",
                  file=out)

        if csv_path:
            with open(csv_path, "w", newline="") as fh:
                w = csv.DictWriter(fh, fieldnames=COLUMNS)
                w.writeheader()
                for r in rows:
                    w.writerow({k: (repr(v) if isinstance(v, float) else v)
                                for k, v in r.items()})
            print(f"wrote {csv_path}", file=out)
        if png:
            _plot(png, curves, F, nu, H, y0, scene.get("name", ""))
            print(f"wrote {png}", file=out)

    if problems:
        for p in problems:
            print(f"FAIL: {p}", file=err)
        print(f"RESULT: FAIL ({len(problems)} problem(s))", file=out)
        return 1
    print(f"RESULT: PASS ({len(rows)} frame(s) checked)", file=out)
    return 0


def _plot(png, curves, F, nu, H, y0, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    yy = np.linspace(y0, y0 + H, 201)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (t, vx, y) in enumerate(curves):
        c = colors[i % len(colors)]
        ax.plot(vx, y, ".", color=c, markersize=3, alpha=0.6)
        ax.plot(analytic_velocity(yy, t, F, nu, H, y0), yy, "-", color=c,
                label=f"t = {t:.4g} s")
    ax.plot([], [], "k.", label="SPH (fluid particles)")
    ax.plot([], [], "k-", label="analytic")
    ax.set_xlabel("vx [m/s]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"Poiseuille flow {title}".strip())
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(
        description="Compare a vesph Poiseuille run with the analytic transient solution.")
    ap.add_argument("h5file", metavar="H5FILE", help="vesph-1 output file (.h5)")
    ap.add_argument("--times", type=float, nargs="+", metavar="T",
                    help="times [s] to check (default: every frame with t > 0)")
    ap.add_argument("--tolerance", type=float, default=0.02,
                    help="max velocity error as a fraction of the steady centreline "
                         "velocity (default 0.02)")
    ap.add_argument("--time-rtol", type=float, default=1e-6,
                    help="relative tolerance for matching --times to frame times "
                         "(default 1e-6)")
    ap.add_argument("--png", metavar="OUT.png", help="write a profile plot")
    ap.add_argument("--csv", metavar="OUT.csv", help="write the table as CSV")
    a = ap.parse_args(argv)
    return check(a.h5file, a.times, a.tolerance, a.time_rtol, a.png, a.csv)


if __name__ == "__main__":
    sys.exit(main())
