#!/usr/bin/python3
"""Check a vesph hydrostatic-tank run (cases/hydrostatic_tank_isph.toml) against the
hydrostatic pressure and for spurious motion.

Usage
-----
    /usr/bin/python3 tools/hydrostatic_check.py H5FILE [--tolerance 0.02] [--layers 3]
        [--max-speed 1e-3] [--from T] [--until T] [--csv OUT.csv]

For every frame (with time in [--from, --until], default every frame after t = 0):
    g       = |effects.body_force.acceleration|, rho = fluid.density (from the stored scene)
    y_s     = mean height of the fluid particles flagged `free_surface` (the discrete free
              surface: the pressure is zero there); without the flag, the top of the highest
              fluid block
    depth   = y_s - y,  H = y_s - (bottom of the fluid blocks)
    error   = max |p - rho g depth| / (rho g H) over the fluid particles deeper than
              --layers particle spacings (below the first particle layers)
    speed   = max |v| over the fluid / sqrt(g H)
A frame passes when error <= --tolerance and speed <= --max-speed. Prints a table and
'RESULT: PASS' or 'RESULT: FAIL'; exit status 0 or 1 (2 for unusable input).
"""
import argparse
import math
import sys

import numpy as np

from vesph import output as vesph_output
from vesph.output import Output, ToolError

PROG = "hydrostatic_check.py"


def run(a):
    with Output(a.h5file) as out:
        scene, dim, dx = out.scene, out.dim, out.dx
        try:
            g = float(np.linalg.norm(scene["effects"]["body_force"]["acceleration"]))
            rho0 = float(scene["fluid"]["density"])
        except (KeyError, TypeError):
            raise ToolError(f"{a.h5file}: the scene has no effects.body_force.acceleration or fluid.density", 2)
        fluid_blocks = [b for b in scene.get("blocks", []) if b.get("kind") == "fluid" and "min" in b]
        if not fluid_blocks:
            raise ToolError(f"{a.h5file}: no box-shaped fluid block in the scene", 2)
        bottom = min(b["min"][dim - 1] for b in fluid_blocks)
        top = max(b["max"][dim - 1] for b in fluid_blocks)
        rows, ok = [], True
        print(f"{'time [s]':>10} {'y_s [m]':>10} {'p error/(rho g H)':>18} {'max|v|/sqrt(gH)':>16}  status")
        for k, (name, t) in enumerate(out.frames):
            if t <= 0 or (a.time_from is not None and t < a.time_from) or (a.until is not None and t > a.until):
                continue
            if not out.has(k, "pressure"):
                raise ToolError(f"{a.h5file}: frame {name} has no pressure", 2)
            fr = out.read(k, ("kind", "position", "pressure", "velocity"), optional=("free_surface",))
            fluid = fr["kind"] == 0
            x = fr["position"][fluid]
            p = fr["pressure"][fluid]
            v = fr["velocity"][fluid]
            y = x[:, dim - 1]
            if "free_surface" in fr and fr["free_surface"][fluid].any():
                ys = float(y[fr["free_surface"][fluid] > 0].mean())
            else:
                ys = top
            H = ys - bottom
            depth = ys - y
            deep = depth > a.layers * dx
            if not deep.any():
                raise ToolError(f"{a.h5file}: no fluid particle deeper than {a.layers} spacings", 2)
            err = float(np.max(np.abs(p[deep] - rho0 * g * depth[deep])) / (rho0 * g * H))
            speed = float(np.max(np.linalg.norm(v, axis=1)) / math.sqrt(g * H))
            good = err <= a.tolerance and speed <= a.max_speed
            ok = ok and good
            rows.append((t, ys, err, speed, good))
            print(f"{t:10.4g} {ys:10.5g} {err:18.4e} {speed:16.4e}  {'ok' if good else 'FAIL'}")
        if not rows:
            raise ToolError(f"{a.h5file}: no frame in the requested time range", 2)
        if a.csv:
            with open(a.csv, "w") as csv_file:
                csv_file.write("time,surface_height,pressure_error,max_speed_over_sqrt_gH,pass\n")
                for r in rows:
                    csv_file.write(f"{r[0]:.9g},{r[1]:.9g},{r[2]:.6e},{r[3]:.6e},{int(r[4])}\n")
    print(f"tolerances: pressure {a.tolerance:g} of rho g H below {a.layers:g} layers, speed {a.max_speed:g} sqrt(gH)")
    print("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description="hydrostatic pressure and spurious motion of a tank run")
    ap.add_argument("h5file", metavar="H5FILE")
    ap.add_argument("--tolerance", type=float, default=0.02, help="pressure error / (rho g H) (default 0.02)")
    ap.add_argument("--layers", type=float, default=3.0, help="skip particles within this many spacings of the surface (default 3)")
    ap.add_argument("--max-speed", type=float, default=1e-3, help="max |v| / sqrt(g H) (default 1e-3)")
    ap.add_argument("--from", dest="time_from", type=float, metavar="T", help="first time checked [s]")
    ap.add_argument("--until", type=float, metavar="T", help="last time checked [s]")
    ap.add_argument("--csv", metavar="FILE")
    a = ap.parse_args(argv)
    for nm, v in (("--tolerance", a.tolerance), ("--layers", a.layers), ("--max-speed", a.max_speed)):
        if not (math.isfinite(v) and v >= 0):
            ap.error(f"{nm} must be a non-negative number, got {v:g}")
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
