#!/usr/bin/python3
"""Where a planar die-swell run decides its swell: the flow at the die's lip, averaged over the
last frames, as a table (printed and CSV) and a PNG. Written to compare WCSPH and ISPH runs of
the same scene (docs/studies.md §5, "WSPH against ISPH").

Usage
-----
    /usr/bin/python3 tools/die_swell_lip.py RUN.h5 [RUN.h5 ...] [--frames N]
        [--die-width 0.01] [--die-exit 0.2] [--csv FILE] [--png FILE]

SI units throughout (m, s, m/s, Pa). Only 2D outputs; the die runs along x with walls at
y = 0 and y = W (--die-width), its exit at x = --die-exit. The frames used are the last N
(--frames, default 8); every quantity is averaged over them.

Per run
-------
- The die's pressure gradient: a least-squares line through the fluid particles' pressures
  over exit - 4 W <= x <= exit - W/2 (where the flow is developed and the exit's influence
  small), against plane Poiseuille flow dp/dx = -12 mu U / W^2 with mu = fluid.viscosity and
  U = inflow.mean_velocity of the stored scene (omitted when the scene lacks either).
- Bands across the flow, 4 dx long, from one dx before the exit to 2 W beyond it: the mean u_x
  of the centre particles (|y - W/2| < W/5) and of the outer rows (within 1.2 dx of the band's
  outermost |y - W/2|, both sides); the median pressure of each; the median T_yy of the outer
  rows (extra_stress, when the frames have it) and the normal stress balance there,
  -p + T_yy (zero on a free surface whose normal is y, thesis §4.1); and the band's particle
  count per unit length over the die's (counted from exit - 4 W over the whole number of
  spacings nearest 3.5 W): the swell of volume conservation at lattice spacing, honest where
  the envelope counts voids or the particles crowd. Then the outer rows' mean outward velocity
  sign(y - W/2) u_y (> 0: moving away from the centreline, the jet widening there) and their
  median T_xx (the stress along the flow that the exit releases). Last, the band's momentum
  flux along x per unit depth, J = sum_i V_i (rho_i u_i^2 + p_i - T_xx,i) / L (N/m; V_i =
  m_i/rho_i, L the band's length; T = 0 where the output has no extra_stress, i.e. without
  the viscous normal stress of a Newtonian run) and its momentum width Q^2 / (rho0 J) / W,
  Q = sum_i m_i u_i / L the mass flux: in a free jet J and Q are conserved, and a plug at
  rest pressure with flux Q and momentum flux J is Q^2 / (rho0 J) wide, so the bands past the
  lip give the width the jet will settle to, and where J falls between the die and the jet
  shows where the fluid is held back. rho0 is fluid.density of the stored scene. A line per
  run gives the jet's mean momentum flux and width over the bands from exit + W on.

Exit status: 0; 1 for an unreadable file, a frame without pressure, or a 3D output; 2 for bad
arguments.
"""
import argparse
import csv
import os
import sys
import warnings

import numpy as np

from vesph.measure import die_swell as dsm
from vesph.output import ToolError

COLUMNS = ["run", "x0_m", "x1_m", "u_centre_m_s", "u_outer_m_s", "p_centre_Pa", "p_outer_Pa",
           "T_yy_outer_Pa", "balance_outer_Pa", "count_ratio", "v_outward_outer_m_s",
           "T_xx_outer_Pa", "momentum_flux_N_m", "momentum_width"]


def frames_of(run, n):
    """The last n frames' fluid particles: position, velocity, pressure and, with a stress
    field, T_xx and T_yy (the output reader checks the shapes)."""
    out = []
    for k in range(max(0, len(run.frames) - n), len(run.frames)):
        nm = run.frames[k][0]
        g = run.group(k)
        if "pressure" not in g:
            raise ToolError(f"{run.path}: frame {nm} has no pressure")
        for key in ("mass", "density"):
            if key not in g:
                raise ToolError(f"{run.path}: frame {nm} has no {key}")
        fr = run.read(k, ("kind", "position", "velocity", "pressure", "mass", "density"),
                      optional=("extra_stress",))
        fluid = fr["kind"] == 0
        d = {key: fr[key][fluid] for key in ("position", "velocity", "pressure", "mass", "density")}
        if "extra_stress" in fr:
            d["T_xx"] = fr["extra_stress"][fluid, 0]  # stored xx, xy, yy
            d["T_yy"] = fr["extra_stress"][fluid, 2]
        out.append(d)
    return out


def die_gradient(frames, exit_x, W):
    """Least-squares dp/dx over exit - 4W <= x <= exit - W/2, all frames pooled."""
    xs, ps = [], []
    for fr in frames:
        x = fr["position"][:, 0]
        m = (x >= exit_x - 4 * W) & (x <= exit_x - 0.5 * W)
        xs.append(x[m])
        ps.append(fr["pressure"][m])
    x, p = np.concatenate(xs), np.concatenate(ps)
    if len(x) < 2:
        return float("nan")
    return float(np.polyfit(x, p, 1)[0])


def lip_rows(frames, dx, exit_x, W, rho0):
    # the die's particles per unit length over a whole number of spacings (a lattice puts the
    # same number of columns in every such window)
    length = max(1, round(3.5 * W / dx)) * dx
    die_per_m = []
    for fr in frames:
        x = fr["position"][:, 0]
        die_per_m.append(np.count_nonzero((x >= exit_x - 4 * W) & (x < exit_x - 4 * W + length)) / length)
    die_density = float(np.mean(die_per_m))
    rows = []
    x0 = exit_x - dx
    while x0 < exit_x + 2 * W - 1e-12:
        x1 = x0 + 4 * dx
        acc = []
        for fr in frames:
            pos = fr["position"]
            m = (pos[:, 0] >= x0) & (pos[:, 0] < x1)
            if np.count_nonzero(m) < 2:
                continue
            off = pos[m, 1] - 0.5 * W   # from the centreline
            d = np.abs(off)
            centre = d < W / 5
            outer = d > d.max() - 1.2 * dx
            u, p = fr["velocity"][m, 0], fr["pressure"][m]
            tyy = np.median(fr["T_yy"][m][outer]) if "T_yy" in fr else np.nan
            txx = np.median(fr["T_xx"][m][outer]) if "T_xx" in fr else np.nan
            p_out = np.median(p[outer])
            outward = np.sign(off) * fr["velocity"][m, 1]
            mass = fr["mass"][m]
            t_xx = fr["T_xx"][m] if "T_xx" in fr else 0.0
            flux_q = np.sum(mass * u) / (x1 - x0)
            # V_i (rho_i u_i^2 + p_i - T_xx,i) with V_i rho_i = m_i
            flux_j = np.sum(mass * u * u + mass / fr["density"][m] * (p - t_xx)) / (x1 - x0)
            acc.append((u[centre].mean() if centre.any() else np.nan, u[outer].mean(),
                        np.median(p[centre]) if centre.any() else np.nan, p_out, tyy, -p_out + tyy,
                        np.count_nonzero(m) / (x1 - x0) / die_density, outward[outer].mean(), txx,
                        flux_j, flux_q * flux_q / (rho0 * flux_j) / W if flux_j > 0 else np.nan))
        if acc:
            with warnings.catch_warnings():  # a column without values (T_yy, Newtonian) stays nan
                warnings.simplefilter("ignore", RuntimeWarning)
                mean = np.nanmean(np.array(acc, dtype=float), axis=0)
            rows.append([x0, x1] + list(mean))
        x0 = x1
    return rows


def run_labels(paths):
    """A label per run: its directory and file name (without .h5), with as many directories
    above as it takes to tell the runs apart (the studies give runs of the same name in
    different study directories); a file given twice is numbered."""
    parts = [os.path.splitext(os.path.abspath(p))[0].split(os.sep) for p in paths]
    depth = 2
    while depth < max(len(q) for q in parts) and len({"/".join(q[-depth:]) for q in parts}) < len(parts):
        depth += 1
    labels, seen = [], {}
    for q in parts:
        label = "/".join(q[-depth:])
        seen[label] = seen.get(label, 0) + 1
        labels.append(label if seen[label] == 1 else f"{label}#{seen[label]}")
    return labels


def main(argv=None):
    ap = argparse.ArgumentParser(prog="die_swell_lip.py", description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="+", metavar="RUN.h5")
    ap.add_argument("--frames", type=int, default=8, metavar="N")
    ap.add_argument("--die-width", type=float, default=0.01, metavar="W")
    ap.add_argument("--die-exit", type=float, default=0.2, metavar="X")
    ap.add_argument("--csv", metavar="FILE")
    ap.add_argument("--png", metavar="FILE")
    a = ap.parse_args(argv)
    if a.frames < 1:
        ap.error("--frames must be >= 1")
    if not (a.die_width > 0):
        ap.error("--die-width must be > 0")
    W, exit_x = a.die_width, a.die_exit
    table, curves = [], {}
    try:
        for path, label in zip(a.paths, run_labels(a.paths)):
            r = dsm.Run(path)
            try:
                frames = frames_of(r, a.frames)
                g = die_gradient(frames, exit_x, W)
                mu = (r.scene.get("fluid") or {}).get("viscosity")
                rho0 = (r.scene.get("fluid") or {}).get("density")
                if not rho0 or not rho0 > 0:
                    raise ToolError(f"{path}: the stored scene has no fluid.density")
                U = (r.scene.get("inflow") or {}).get("mean_velocity")
                line = f"{label}: die dp/dx {g:.4g} Pa/m"
                if mu and U:
                    pois = -12.0 * mu * U / W ** 2
                    line += f" (plane Poiseuille {pois:.4g}: {100 * (g / pois - 1):+.0f} %)"
                print(line)
                print(f"   {'x0':>7} {'x1':>7} {'u_c':>6} {'u_out':>6} {'p_c':>9} {'p_out':>9} "
                      f"{'Tyy_out':>9} {'-p+Tyy':>9} {'count':>6} {'v_out':>6} {'Txx_out':>9} "
                      f"{'J':>7} {'W_J':>6}")
                rows = lip_rows(frames, r.dx, exit_x, W, rho0)
                for row in rows:
                    print(f"   {row[0]:7.4f} {row[1]:7.4f} {row[2]:6.2f} {row[3]:6.2f} {row[4]:9.0f} "
                          f"{row[5]:9.0f} {row[6]:9.0f} {row[7]:9.0f} {row[8]:6.3f} {row[9]:6.2f} "
                          f"{row[10]:9.0f} {row[11]:7.1f} {row[12]:6.3f}")
                    table.append([label] + row)
                jet = [row for row in rows if row[0] >= exit_x + W - 1e-12 and np.isfinite(row[12])]
                if jet:
                    print(f"   jet (bands from x = {exit_x + W:g} m): momentum flux "
                          f"{np.mean([row[11] for row in jet]):.1f} N/m, momentum width "
                          f"{np.mean([row[12] for row in jet]):.3f} W over {len(jet)} bands")
                curves[label] = np.array(rows)
            finally:
                r.close()
    except ToolError as e:
        print(f"die_swell_lip: error: {e}", file=sys.stderr)
        return 1
    if a.csv:
        with open(a.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(COLUMNS)
            for row in table:
                w.writerow([row[0]] + [f"{v:.6g}" for v in row[1:]])
        print(f"wrote {a.csv}")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        # One colour per run (the legend below the panels); the line style tells the
        # quantity (the panels' titles).
        fig, ax = plt.subplots(1, 3, figsize=(13, 3.6 + 0.22 * len(curves)))
        for k, (label, c) in enumerate(curves.items()):
            xm = 0.5 * (c[:, 0] + c[:, 1])
            col = f"C{k}"
            ax[0].plot(xm, c[:, 2], "-", color=col, label=label)
            ax[0].plot(xm, c[:, 3], "--", color=col)
            ax[1].plot(xm, c[:, 4] / 1e3, "-", color=col)
            ax[1].plot(xm, c[:, 5] / 1e3, "--", color=col)
            ax[1].plot(xm, c[:, 6] / 1e3, ":", color=col)
            ax[2].plot(xm, c[:, 8], "-", color=col)
            ax[2].plot(xm, c[:, 12], "--", color=col)
        titles = ("u_x: centre (solid), outer rows (dashed)",
                  "p: centre (solid), outer rows (dashed);\nT_yy of the outer rows (dotted)",
                  "count per length / die's (solid);\nmomentum width Q²/(ρ0 J) / W (dashed)")
        for axis, yl, title in zip(ax, ("u_x [m/s]", "p, T_yy [kPa]", "width / W"), titles):
            axis.axvline(exit_x, color="k", lw=0.8)
            axis.set_xlabel("x [m]")
            axis.set_ylabel(yl)
            axis.set_title(title, fontsize=8)
            axis.grid(alpha=0.3)
        fig.suptitle(f"the flow at the die's lip (mean of the last {a.frames} frames)", fontsize=10)
        handles, names = ax[0].get_legend_handles_labels()
        fig.legend(handles, names, loc="lower center", ncol=1, fontsize=7, frameon=False)
        fig.tight_layout(rect=(0, 0.06 * len(curves), 1, 1))
        fig.savefig(a.png, dpi=110)
        print(f"wrote {a.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
