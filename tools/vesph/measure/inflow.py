#!/usr/bin/python3
"""Checks a run with open boundaries (an [inflow] buffer and/or an [outflow] plane,
docs/user-guide.md "Open boundaries") for particle accounting and, optionally, for the
velocity profile of a plane channel against the fully developed Poiseuille parabola.

Accounting (always):
  * every diagnostics row: fluid_particles = initial fluid count + released - removed, with
    released and removed never decreasing;
  * every frame: the number of fluid particles (kind 0) equals the fluid_particles of the last
    diagnostics row at or before the frame time (the changes of a step are made right after it);
  * ids are unique in every frame, and a fluid id that was not in the previous frame is new:
    larger than every id seen in earlier frames (ids are never reused, so a removed particle
    never comes back);
  * every fluid particle carries the same mass (the buffer's rho0 dx^D).

Profile (with --profile-x): over the frames at t >= --from, the fluid particles within one
spacing of x = profile-x are binned into rows of one spacing across the channel
[--wall-lo, --wall-lo + --width]; each row's mean axial velocity is compared with
u(y) = 6 U eta (1 - eta), eta = (y - wall_lo)/width, at the row's mean y. The error is
reported relative to the parabola's maximum 1.5 U; --tolerance is that bound (fraction).
Units: SI (m, s, m/s).

Exit status: 0 all checks pass, 1 a check fails, 2 bad input.
"""
import argparse
import sys

import numpy as np

from vesph.output import Output, ToolError, run_reporting_errors


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("h5", help="the run's .h5 file")
    ap.add_argument("--profile-x", type=float, help="x of the profile check, m (omit: accounting only)")
    ap.add_argument("--mean-velocity", type=float, help="U, the inflow's mean velocity, m/s")
    ap.add_argument("--width", type=float, default=0.01, help="channel width, m (default 0.01)")
    ap.add_argument("--wall-lo", type=float, default=0.0, help="y of the lower wall surface, m (default 0)")
    ap.add_argument("--from", dest="t_from", type=float, default=0.0, help="first time of the profile check, s")
    ap.add_argument("--tolerance", type=float, default=0.03, help="profile bound, fraction of 1.5 U (default 0.03)")
    args = ap.parse_args(argv)
    return run_reporting_errors("inflow_check", run, args)


def run(args):
    if args.profile_x is not None and not (args.mean_velocity and args.mean_velocity > 0):
        raise ToolError("--profile-x needs --mean-velocity U > 0 (m/s)", 2)
    with Output(args.h5) as out:
        dx = out.dx
        f = out.f
        if "diagnostics" not in f or "released" not in f["diagnostics"]:
            raise ToolError(f"{args.h5}: no open-boundary diagnostics (released, removed, fluid_particles): "
                            "the scene has no [inflow] or [outflow]")
        t_rows, released, removed, fluid = out.diagnostics("time", "released", "removed", "fluid_particles")
        kinds0 = out.read(0, ("kind",))["kind"]
        initial = int(np.count_nonzero(kinds0 == 0))
        failures = []

        expected = initial + released - removed
        bad = np.nonzero(fluid != expected)[0]
        if len(bad):
            k = bad[0]
            failures.append(f"row {k} (t = {t_rows[k]:.6g} s): fluid_particles {fluid[k]:.0f} != initial {initial} + "
                            f"released {released[k]:.0f} - removed {removed[k]:.0f}")
        if np.any(np.diff(released) < 0) or np.any(np.diff(removed) < 0):
            failures.append("released or removed decreases")

        seen_max = -1
        prev_ids = None
        mass0 = None
        for k, (name, t) in enumerate(out.frames):
            g = out.read(k, ("kind", "id", "mass"))
            kind = g["kind"]
            ids = g["id"].astype(np.int64)
            nf = int(np.count_nonzero(kind == 0))
            if len(np.unique(ids)) != len(ids):
                failures.append(f"frame {name}: duplicate ids")
            rows = np.nonzero(t_rows <= t * (1 + 1e-12))[0]
            want = initial if len(rows) == 0 else int(fluid[rows[-1]])
            if nf != want:
                failures.append(f"frame {name} (t = {t:.6g} s): {nf} fluid particles, diagnostics say {want}")
            fluid_ids = ids[kind == 0]
            if prev_ids is not None:
                new = np.setdiff1d(fluid_ids, prev_ids)
                if len(new) and new.min() <= seen_max:
                    failures.append(f"frame {name}: fluid id {new.min()} reappears or is reused "
                                    f"(ids up to {seen_max} were seen before)")
            prev_ids = fluid_ids
            seen_max = max(seen_max, int(ids.max()))
            m = g["mass"][kind == 0]
            if mass0 is None and len(m):
                mass0 = m[0]
            if len(m) and np.max(np.abs(m - mass0)) > 1e-12 * mass0:
                failures.append(f"frame {name}: fluid masses differ")

        print(f"inflow_check: {len(out.frames)} frames, {len(t_rows)} steps; fluid particles {initial} -> {int(fluid[-1])}; "
              f"released {int(released[-1])}, removed {int(removed[-1])}")

        if args.profile_x is not None:
            U, W, y0 = args.mean_velocity, args.width, args.wall_lo
            nrows = int(round(W / dx))
            acc = np.zeros(nrows)
            cnt = np.zeros(nrows)
            ysum = np.zeros(nrows)
            used = 0
            for k, (_, t) in enumerate(out.frames):
                if t < args.t_from:
                    continue
                g = out.read(k, ("kind", "position", "velocity"))
                kind, x, v = g["kind"], g["position"], g["velocity"]
                sel = (kind == 0) & (np.abs(x[:, 0] - args.profile_x) <= dx)
                y = x[sel, 1]
                b = np.clip(np.floor((y - y0) / dx).astype(int), 0, nrows - 1)
                np.add.at(acc, b, v[sel, 0])
                np.add.at(cnt, b, 1)
                np.add.at(ysum, b, y)
                used += 1
            if used == 0 or np.any(cnt == 0):
                raise ToolError(f"no fluid in some row at x = {args.profile_x} m after t = {args.t_from} s", 1)
            ym = ysum / cnt
            um = acc / cnt
            eta = (ym - y0) / W
            ua = 6 * U * eta * (1 - eta)
            err = np.abs(um - ua) / (1.5 * U)
            print(f"profile at x = {args.profile_x} m over {used} frames: max error {err.max() * 100:.2f} % of 1.5 U "
                  f"(row {int(err.argmax())}), bound {args.tolerance * 100:.2f} %")
            for r in range(nrows):
                print(f"  y = {ym[r]:.5f} m  u = {um[r]:.5f} m/s  parabola {ua[r]:.5f} m/s  error {err[r] * 100:6.2f} %")
            if err.max() > args.tolerance:
                failures.append(f"profile error {err.max() * 100:.2f} % > {args.tolerance * 100:.2f} %")

    for msg in failures[:20]:
        print(f"FAIL: {msg}")
    if failures:
        return 1
    print("inflow_check: all checks pass")
    return 0


if __name__ == "__main__":
    sys.exit(main())
