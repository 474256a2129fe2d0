#!/usr/bin/python3
"""A plane section of a 3D vesph run: the particles within one spacing of a plane, plotted in
the plane's own coordinates with a chosen field as colour.

Usage
-----
    tools/vesph-post section H5FILE [--point X,Y,Z] [--normal NX,NY,NZ] [--field NAME]
        [--time T] [--half-width W] [--png OUT.png] [--csv OUT.csv] [--fluid-only]

The plane passes through --point (default: the centre of the scene's domain) with the unit
normal --normal (default 0,0,1; any non-zero vector, normalised). A particle at x is in the
section when its signed distance d = (x - point) . n satisfies |d| < W, W = --half-width
(default dx, the particle spacing: "within one spacing of the plane"; on a lattice with the
plane through a particle layer that is the layer alone: distances within 1e-9 W of W count as
W, so the round-off of the positions cannot take in the layers one spacing away). Distances are measured without
periodic images.

In-plane coordinates: u = (x - point) . e1, v = (x - point) . e2, where e1 and e2 are the two
coordinate axes least aligned with n (in axis order), projected onto the plane and
orthonormalised: normal z gives (u, v) = (x, y), normal y gives (x, z), normal x gives (y, z),
each relative to the point.

Fields (--field, default speed): speed = |v|; velocity_x, velocity_y, velocity_z; density,
pressure, mass, kind, free_surface, id; extra_stress_xx, _xy, _xz, _yy, _yz, _zz (the dataset
extra_stress, stored xx xy xz yy yz zz); a frame without the dataset is an error.

The frame is the one nearest --time (default the last). Fluid particles are coloured by the
field; wall and other fixed particles (kind != 0) are drawn as small grey dots unless
--fluid-only (then they are left out of the plot and the CSV). Points nearer the plane are
drawn on top.

Outputs: the PNG (default <h5 dir>/<scene name>_section_<field>.png), the CSV when asked
(columns u, v, d [m], x, y, z [m], id, kind, value [the field's SI unit]), and a summary on
stdout: frame time, plane, the particle count and the field's range over the section's fluid
particles.

Exit status: 0 on success; 1 when the file cannot be used (not a vesph output, a frame
without the field, no particle in the section); 2 for usage errors (a 2D run, a zero normal,
an unknown field).
"""
import argparse
import math
import os
import sys

import numpy as np

from vesph import output as vesph_output
from vesph.output import Output, ToolError

PROG = "section"

STRESS_COMPONENTS = ("xx", "xy", "xz", "yy", "yz", "zz")  # the 3D extra_stress columns
FIELDS = (["speed", "velocity_x", "velocity_y", "velocity_z", "density", "pressure", "mass",
           "kind", "free_surface", "id"] + [f"extra_stress_{c}" for c in STRESS_COMPONENTS])
UNITS = {"speed": "m/s", "velocity_x": "m/s", "velocity_y": "m/s", "velocity_z": "m/s",
         "density": "kg/m^3", "pressure": "Pa", "mass": "kg", "kind": "", "free_surface": "",
         "id": ""}


def parse_vector(text, what):
    try:
        vals = [float(s) for s in text.split(",")]
    except ValueError:
        raise ToolError(f"{what} must be three numbers X,Y,Z, got {text!r}", 2)
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise ToolError(f"{what} must be three finite numbers X,Y,Z, got {text!r}", 2)
    return np.array(vals)


def plane_basis(normal):
    """Unit normal n and in-plane unit vectors e1, e2: the coordinate axes least aligned with n
    (stable in axis order), projected onto the plane and orthonormalised (Gram-Schmidt)."""
    n = normal / np.linalg.norm(normal)
    axes = sorted(sorted(range(3), key=lambda a: (round(abs(n[a]), 12), a))[:2])
    basis = []
    for a in axes:
        e = np.eye(3)[a] - n[a] * n
        for b in basis:
            e -= e.dot(b) * b
        basis.append(e / np.linalg.norm(e))
    return n, basis[0], basis[1]


def field_values(data, field):
    if field == "speed":
        return np.linalg.norm(data["velocity"], axis=1)
    if field.startswith("velocity_"):
        return data["velocity"][:, "xyz".index(field[-1])]
    if field.startswith("extra_stress_"):
        return data["extra_stress"][:, STRESS_COMPONENTS.index(field[len("extra_stress_"):])]
    return data[field].astype(float)


def dataset_of(field):
    if field == "speed" or field.startswith("velocity_"):
        return "velocity"
    if field.startswith("extra_stress_"):
        return "extra_stress"
    return field


def run(a):
    with Output(a.h5file) as out:
        if out.dim != 3:
            raise ToolError(f"{a.h5file} is a {out.dim}D run; a section needs a 3D run "
                            "(plot a 2D run's particles directly)", 2)
        normal = parse_vector(a.normal, "--normal")
        if np.linalg.norm(normal) == 0:
            raise ToolError("--normal must not be the zero vector", 2)
        if a.point is not None:
            point = parse_vector(a.point, "--point")
        else:
            try:
                dom = out.scene["domain"]
                point = 0.5 * (np.array(dom["min"], float) + np.array(dom["max"], float))
            except (KeyError, TypeError, ValueError):
                raise ToolError(f"{a.h5file}: the scene has no domain min/max; give --point")
        half = out.dx if a.half_width is None else a.half_width
        k = len(out.frames) - 1 if a.time is None else int(np.argmin(np.abs(out.times - a.time)))
        name, t = out.frames[k]
        ds = dataset_of(a.field)
        data = out.read(k, ["position", "kind"] + ([ds] if ds not in ("position", "kind") else []),
                        optional=("id",))
        if ds == "id" and "id" not in data:
            raise ToolError(f"{a.h5file}: frame {name} has no dataset 'id'")
    n, e1, e2 = plane_basis(normal)
    rel = data["position"] - point
    d = rel @ n
    # strictly inside, less round-off: a lattice layer exactly W from the plane stays out
    keep = np.abs(d) < half * (1 - 1e-9)
    fluid = data["kind"] == 0
    if a.fluid_only:
        keep &= fluid
    if not keep.any():
        raise ToolError(f"no particle within {half:g} m of the plane through {point.tolist()} "
                        f"with normal {n.tolist()} at t = {t:g} s")
    u, v = rel @ e1, rel @ e2
    values = field_values(data, a.field)
    sel_fluid = keep & fluid
    unit = UNITS.get(a.field, "Pa")
    print(f"{PROG}: frame {name}, t = {t:.6g} s; plane through ({', '.join(f'{c:.6g}' for c in point)}) m, "
          f"normal ({', '.join(f'{c:.4g}' for c in n)}), half-width {half:.4g} m")
    print(f"  in-plane axes e1 = ({', '.join(f'{c:.4g}' for c in e1)}), e2 = ({', '.join(f'{c:.4g}' for c in e2)})")
    print(f"  particles: {int(keep.sum())} in the section ({int(sel_fluid.sum())} fluid)")
    if sel_fluid.any():
        print(f"  {a.field}: min {values[sel_fluid].min():.6g}, max {values[sel_fluid].max():.6g}, "
              f"mean {values[sel_fluid].mean():.6g} {unit}".rstrip())
    if a.csv:
        idx = np.flatnonzero(keep)
        ids = data["id"][idx] if "id" in data else idx
        with open(a.csv, "w") as fh:
            fh.write("u,v,d,x,y,z,id,kind,value\n")
            for i, pid in zip(idx, ids):
                x = data["position"][i]
                fh.write(f"{u[i]:.17g},{v[i]:.17g},{d[i]:.17g},{x[0]:.17g},{x[1]:.17g},{x[2]:.17g},"
                         f"{int(pid)},{int(data['kind'][i])},{values[i]:.17g}\n")
        print(f"  wrote {a.csv}")
    png = a.png or os.path.join(os.path.dirname(os.path.abspath(a.h5file)),
                                f"{out.name}_section_{a.field}.png")
    plot(png, u, v, d, values, keep, fluid, a.field, unit, t, point, n, half)
    print(f"  wrote {png}")
    return 0


def plot(png, u, v, d, values, keep, fluid, field, unit, t, point, n, half):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 5.6))
    walls = np.flatnonzero(keep & ~fluid)
    if walls.size:
        ax.scatter(u[walls], v[walls], s=3, c="0.7", lw=0, label="walls")
    idx = np.flatnonzero(keep & fluid)
    if idx.size:
        idx = idx[np.argsort(-np.abs(d[idx]))]  # nearest to the plane drawn last, on top
        size = float(np.clip(2.0e4 / idx.size, 2.0, 40.0))  # marker area: fewer points, larger
        sc = ax.scatter(u[idx], v[idx], c=values[idx], s=size, lw=0, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=f"{field}" + (f" [{unit}]" if unit else ""))
    ax.set_aspect("equal")
    ax.set_xlabel("u [m]")
    ax.set_ylabel("v [m]")
    ax.set_title(f"section at t = {t:.4g} s, |d| < {half:.3g} m\npoint ({', '.join(f'{c:.3g}' for c in point)}) m, "
                 f"normal ({', '.join(f'{c:.2g}' for c in n)})", fontsize=9)
    if walls.size:
        ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description="plot the particles of a 3D run within one spacing of a plane")
    ap.add_argument("h5file", metavar="H5FILE")
    ap.add_argument("--point", metavar="X,Y,Z", help="a point of the plane [m] (default: the domain centre)")
    ap.add_argument("--normal", metavar="NX,NY,NZ", default="0,0,1", help="the plane's normal (default 0,0,1)")
    ap.add_argument("--field", default="speed", choices=FIELDS, help="colour (default speed)")
    ap.add_argument("--time", type=float, metavar="T", help="the frame nearest T [s] (default the last)")
    ap.add_argument("--half-width", type=float, metavar="W", help="|distance| < W [m] (default dx)")
    ap.add_argument("--png", metavar="OUT.png")
    ap.add_argument("--csv", metavar="OUT.csv")
    ap.add_argument("--fluid-only", action="store_true", help="leave wall particles out")
    a = ap.parse_args(argv)
    if a.half_width is not None and not (math.isfinite(a.half_width) and a.half_width > 0):
        ap.error(f"--half-width must be a positive number, got {a.half_width:g}")
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
