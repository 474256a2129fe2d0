#!/usr/bin/python3
"""Checks of the moving walls (docs/validation.md §15) against analytic solutions.

The tools are vesph.checks.couette, vesph.checks.rotating_box and
vesph.checks.circular_couette (this module holds all three).

Usage
-----
    tools/vesph-post couette_check H5FILE [--times T ...] [--tolerance 0.01]
    tools/vesph-post rotation_check H5FILE [--time T] [--tolerance 0.001]
        [--early-time T0] [--early-minimum 0.3] [--decay T1 T2] [--decay-tolerance 0.1]
    tools/vesph-post circular_couette_check H5FILE [--time T] [--tolerance 0.01] [--bins 10] [--plot PNG]

couette_check: start-up of plane Couette flow (cases/couette_startup.toml). From the resolved
scene: nu = fluid.viscosity / fluid.density; the moving wall is the wall block with a velocity,
U its x component [m/s]; the fluid block spans y0 .. y0 + H (its min[1], max[1]; with image
walls their boundary rows, the floor's max[1] and the ceiling's min[1]), the other wall at rest. The fluid starts at rest and the upper wall at y0 + H moves at U from t = 0:

    u(y, t) = U s/H + (2U/pi) sum_{n>=1} ((-1)^n / n) sin(n pi s/H) exp(-n^2 pi^2 nu t / H^2),
    s = y - y0                                                 (vesph.analytic.couette_startup)

(a lower moving wall: s -> H - s); with the wall's ramp_time T the ramped start by Duhamel's
principle (vesph.analytic.couette_startup). For each checked frame: error = max over fluid particles of
|vx - u(y, t)| / |U| and the largest |vy| / |U|. Pass: error < tolerance (default 1 %) at every
checked time, and the fluid mass unchanged.

rotation_check: spin-up in a rotating closed box (cases/rotating_box.toml). The walls rotate at
omega (the blocks' angular_velocity, 2D) about axis_point c; the fluid spins up toward
solid-body rotation v = omega x (x - c). For each frame: deviation = max over fluid particles of
|v - omega x (x - c)| / (omega L/2), L the fluid block's side. Pass when
  * at --time (default: the last frame) the deviation is below --tolerance (default 0.1 %);
  * at --early-time (default 0.01 s) it is still above --early-minimum (default 30 %): the fluid
    spins up through viscosity, it does not start in solid-body rotation;
  * with --decay T1 T2: the decay rate ln(dev(T1)/dev(T2)) / (T2 - T1) of the deviation agrees
    within --decay-tolerance (relative, default 10 %) with the slowest Stokes mode of the
    square, 52.3447 nu / L^2 (the first eigenvalue of the clamped plate on the unit square).

circular_couette_check: steady circular Couette flow (cases/circular_couette.toml, 2D). The
fluid block is a tube (centre c, inner_diameter 2 R1, outer_diameter 2 R2); the wall blocks
inside R1 and outside R2 turn at omega1 and omega2 about c (angular_velocity, axis_point; a
wall without one is at rest). The steady azimuthal velocity (Newtonian, any Re: the flow is
circular, the pressure takes the centripetal part):

    v(r) = A r + B / r,  A = (omega2 R2^2 - omega1 R1^2) / (R2^2 - R1^2),
                         B = (omega1 - omega2) R1^2 R2^2 / (R2^2 - R1^2)

                                                     (vesph.analytic.circular_couette)

For the frame at --time (default: the last): error = max over fluid particles of
|v_theta - v(r)| / S, S = max(|omega1| R1, |omega2| R2) the faster wall's speed; the radial
velocity max |v_r| / S; a table of the mean v_theta in --bins radial bins against v at the
bin's mean radius. Pass: error < tolerance (default 1 %) and the fluid mass unchanged. --plot
writes the binned profile against v(r) (matplotlib).

Exit status 0 pass, 1 fail, 2 usage.
"""

import argparse
import math
import sys

import numpy as np

from vesph.analytic import circular_couette, couette_startup
from vesph.output import Output, ToolError

MASS_DRIFT_LIMIT = 1e-12
STOKES_SQUARE = 52.344691168  # first eigenvalue of the Stokes (clamped plate) problem, unit square


def _fluid_blocks(scene):
    blocks = [b for b in scene.get("blocks", []) if b.get("kind") == "fluid"]
    if not blocks:
        raise ValueError("scene has no [[blocks]] with kind = \"fluid\"")
    return blocks


def _nu(scene):
    try:
        rho = float(scene["fluid"]["density"])
        mu = float(scene["fluid"]["viscosity"])
    except (KeyError, TypeError, ValueError):
        raise ValueError("scene has no numeric fluid.density and fluid.viscosity")
    if rho <= 0 or mu <= 0:
        raise ValueError("fluid.density and fluid.viscosity must be > 0")
    return mu / rho


def _select(h5, times, rtol=1e-6):
    frames = list(enumerate(h5.frames))
    if not times:
        return [(k, name, t) for k, (name, t) in frames if t > 0], []
    out, problems = [], []
    ft = np.array([t for _, (_, t) in frames])
    for T in times:
        i = int(np.argmin(np.abs(ft - T)))
        if abs(ft[i] - T) <= rtol * max(abs(T), 1e-300):
            out.append((i, frames[i][1][0], ft[i]))
        else:
            problems.append(f"no frame at t = {T:.9g} s (closest {ft[i]:.9g} s)")
    return out, problems


def _mass(g):
    return float(np.sum(g["mass"][g["kind"] == 0], dtype=np.float64))


def couette(path, times=None, tolerance=0.01, out=sys.stdout, err=sys.stderr):
    try:
        h5 = Output(path)
    except ToolError as e:
        print(f"FAIL: {e}", file=err)
        return 1
    problems = []
    with h5:
        scene = h5.scene
        try:
            nu = _nu(scene)
            fluid = _fluid_blocks(scene)
            y0 = min(float(b["min"][1]) for b in fluid)
            H = max(float(b["max"][1]) for b in fluid) - y0
            # Image walls (as in the Poiseuille check): the surfaces are their boundary rows.
            images = [b for b in scene.get("blocks", []) if b.get("kind") == "wall" and b.get("treatment") == "image"]
            if images:
                top = y0 + H
                floors = [float(b["max"][1]) for b in images if float(b["normal"][1]) > 0]
                ceilings = [float(b["min"][1]) for b in images if float(b["normal"][1]) < 0]
                y0 = max(floors) if floors else y0
                top = min(ceilings) if ceilings else top
                H = top - y0
            moving = [b for b in scene.get("blocks", []) if b.get("kind") == "wall" and "velocity" in b]
            if len(moving) != 1:
                raise ValueError("expected exactly one wall block with a velocity (the moving wall)")
            U = float(moving[0]["velocity"][0])
            ramp = float(moving[0].get("ramp_time", 0.0))
            if U == 0:
                raise ValueError("the moving wall's x velocity is 0")
            upper = float(moving[0]["min"][1]) >= y0 + H - 1e-12 * H
        except ValueError as e:
            print(f"FAIL: {path}: {e}", file=err)
            return 1
        m0 = _mass(h5.read(0, ("kind", "mass")))
        print(f"file: {path}\nnu = {nu:.6g} m^2/s   H = {H:.6g} m   U = {U:.6g} m/s ({'upper' if upper else 'lower'} wall"
              f"{f', ramped over {ramp:g} s' if ramp > 0 else ''})"
              f"   pass if error < {100 * tolerance:g} % of U", file=out)
        print(f"{'frame':>8} {'time [s]':>10} {'error [% U]':>12} {'max|vy| [% U]':>14} {'mass drift':>11}  status",
              file=out)
        selected, problems = _select(h5, times)
        for k, name, t in selected:
            g = h5.read(k, ("kind", "position", "velocity", "mass"))
            fl = g["kind"] == 0
            s = g["position"][fl, 1] - y0
            u = couette_startup(s if upper else H - s, t, U, nu, H, ramp)
            e = float(np.max(np.abs(g["velocity"][fl, 0] - u))) / abs(U)
            vy = float(np.max(np.abs(g["velocity"][fl, 1]))) / abs(U)
            drift = (_mass(g) - m0) / m0
            bad = []
            if not e < tolerance:
                bad.append(f"velocity error {100 * e:.4g} % >= {100 * tolerance:g} %")
            if not abs(drift) < MASS_DRIFT_LIMIT:
                bad.append(f"mass drift {drift:.3e}")
            if bad:
                problems.append(f"frame {name} (t = {t:.6g} s): " + "; ".join(bad))
            print(f"{name:>8} {t:10.6g} {100 * e:12.5f} {100 * vy:14.5f} {drift:11.2e}  {'FAIL' if bad else 'ok'}",
                  file=out)
        if not selected and not problems:
            problems.append("no frame to check")
    for p in problems:
        print(f"FAIL: {p}", file=err)
    print("RESULT: " + ("FAIL" if problems else "PASS"), file=out)
    return 1 if problems else 0


def rotation(path, time=None, tolerance=0.001, early_time=0.01, early_minimum=0.3, decay=None,
             decay_tolerance=0.1, out=sys.stdout, err=sys.stderr):
    try:
        h5 = Output(path)
    except ToolError as e:
        print(f"FAIL: {e}", file=err)
        return 1
    problems = []
    with h5:
        scene = h5.scene
        try:
            if int(scene.get("dimension", 2)) != 2:
                raise ValueError("rotation_check is for 2D scenes")
            nu = _nu(scene)
            fluid = _fluid_blocks(scene)
            L = max(float(b["max"][0]) for b in fluid) - min(float(b["min"][0]) for b in fluid)
            walls = [b for b in scene.get("blocks", []) if b.get("kind") == "wall"]
            rot = {(float(b["angular_velocity"]), tuple(float(c) for c in b["axis_point"]))
                   for b in walls if "angular_velocity" in b}
            if len(rot) != 1 or len([b for b in walls if "angular_velocity" in b]) != len(walls):
                raise ValueError("expected every wall block to rotate with the same angular_velocity and axis_point")
            (omega, centre), = rot
        except (ValueError, KeyError, TypeError) as e:
            print(f"FAIL: {path}: {e}", file=err)
            return 1
        scale = abs(omega) * L / 2
        m0 = _mass(h5.read(0, ("kind", "mass")))
        dev = {}
        print(f"file: {path}\nnu = {nu:.6g} m^2/s   L = {L:.6g} m   omega = {omega:.6g} rad/s about {centre}"
              f"   omega L/2 = {scale:.6g} m/s", file=out)
        print(f"{'frame':>8} {'time [s]':>10} {'max dev [%]':>12} {'rms dev [%]':>12} {'mass drift':>11}", file=out)
        for k, (name, t) in enumerate(h5.frames):
            g = h5.read(k, ("kind", "position", "velocity", "mass"))
            fl = g["kind"] == 0
            r = g["position"][fl] - np.array(centre)
            solid = omega * np.stack([-r[:, 1], r[:, 0]], axis=1)
            d = np.linalg.norm(g["velocity"][fl] - solid, axis=1) / scale
            drift = (_mass(g) - m0) / m0
            if not abs(drift) < MASS_DRIFT_LIMIT:
                problems.append(f"frame {name}: mass drift {drift:.3e}")
            dev[t] = float(d.max())
            print(f"{name:>8} {t:10.6g} {100 * d.max():12.5f} {100 * math.sqrt(float(np.mean(d * d))):12.5f}"
                  f" {drift:11.2e}", file=out)
        times = sorted(dev)

        def at(T):
            best = min(times, key=lambda s: abs(s - T))
            if abs(best - T) > 1e-6 * max(T, 1e-300):
                problems.append(f"no frame at t = {T:.9g} s")
                return None
            return dev[best]

        T = time if time is not None else times[-1]
        final = at(T)
        if final is not None:
            ok = final < tolerance
            print(f"t = {T:g} s: deviation from solid-body rotation {100 * final:.4g} % of omega L/2 "
                  f"(pass below {100 * tolerance:g} %): {'ok' if ok else 'FAIL'}", file=out)
            if not ok:
                problems.append(f"t = {T:g} s: deviation {100 * final:.4g} % >= {100 * tolerance:g} %")
        if early_time is not None:
            early = at(early_time)
            if early is not None:
                ok = early > early_minimum
                print(f"t = {early_time:g} s: deviation {100 * early:.4g} % (still spinning up: above "
                      f"{100 * early_minimum:g} %): {'ok' if ok else 'FAIL'}", file=out)
                if not ok:
                    problems.append(f"t = {early_time:g} s: deviation {100 * early:.4g} % <= {100 * early_minimum:g} %"
                                    " (the fluid should still be spinning up)")
        if decay:
            a, b = at(decay[0]), at(decay[1])
            if a is not None and b is not None:
                rate = math.log(a / b) / (decay[1] - decay[0])
                expected = STOKES_SQUARE * nu / (L * L)
                rel = abs(rate / expected - 1)
                ok = rel < decay_tolerance
                print(f"decay rate between t = {decay[0]:g} and {decay[1]:g} s: {rate:.4g} 1/s, slowest Stokes mode "
                      f"52.345 nu/L^2 = {expected:.4g} 1/s ({100 * rel:.3g} % off, pass below "
                      f"{100 * decay_tolerance:g} %): {'ok' if ok else 'FAIL'}", file=out)
                if not ok:
                    problems.append(f"decay rate {rate:.4g} 1/s is {100 * rel:.3g} % off {expected:.4g} 1/s")
    for p in problems:
        print(f"FAIL: {p}", file=err)
    print("RESULT: " + ("FAIL" if problems else "PASS"), file=out)
    return 1 if problems else 0


def _circular_setup(scene):
    if int(scene.get("dimension", 2)) != 2:
        raise ValueError("circular_couette_check is for 2D scenes")
    fluid = _fluid_blocks(scene)
    if len(fluid) != 1 or fluid[0].get("shape") != "tube":
        raise ValueError("expected one fluid block of shape = \"tube\" (the gap)")
    centre = np.array([float(c) for c in fluid[0]["centre"]])
    R1 = 0.5 * float(fluid[0]["inner_diameter"])
    R2 = 0.5 * float(fluid[0]["outer_diameter"])
    omega1 = omega2 = 0.0
    for b in scene.get("blocks", []):
        if b.get("kind") != "wall" or "angular_velocity" not in b:
            continue
        if "velocity" in b or float(b.get("ramp_time", 0.0)) > 0:
            raise ValueError(f"{b.get('shape', 'box')} wall: no translation or ramp in the steady check")
        if np.abs(np.array([float(c) for c in b["axis_point"]]) - centre).max() > 1e-9 * R2:
            raise ValueError("a wall turns about a point other than the gap's centre")
        # Which cylinder: a wall block reaching inside R1 is the inner one.
        if b.get("shape") in ("cylinder", "disk"):
            inner = 0.5 * float(b["diameter"]) <= R1 * (1 + 1e-9)
        elif b.get("shape") == "tube":
            inner = 0.5 * float(b["outer_diameter"]) <= R1 * (1 + 1e-9)
        else:
            raise ValueError("rotating walls must be disks, cylinders or tubes about the gap's centre")
        if inner:
            omega1 = float(b["angular_velocity"])
        else:
            omega2 = float(b["angular_velocity"])
    if omega1 == 0 and omega2 == 0:
        raise ValueError("no rotating wall (angular_velocity) about the gap")
    return centre, R1, R2, omega1, omega2


def circular(path, time=None, tolerance=0.01, bins=10, plot=None, out=sys.stdout, err=sys.stderr):
    try:
        h5 = Output(path)
    except ToolError as e:
        print(f"FAIL: {e}", file=err)
        return 1
    problems = []
    with h5:
        try:
            centre, R1, R2, omega1, omega2 = _circular_setup(h5.scene)
        except (ValueError, KeyError, TypeError) as e:
            print(f"FAIL: {path}: {e}", file=err)
            return 1
        frames = list(h5.frames)
        times = np.array([t for _, t in frames])
        k = len(frames) - 1 if time is None else int(np.argmin(np.abs(times - time)))
        if time is not None and abs(times[k] - time) > 1e-6 * max(abs(time), 1e-300):
            print(f"FAIL: no frame at t = {time:.9g} s (closest {times[k]:.9g} s)", file=err)
            return 1
        name, t = frames[k]
        m0 = _mass(h5.read(0, ("kind", "mass")))
        g = h5.read(k, ("kind", "position", "velocity", "mass"))
        fl = g["kind"] == 0
        d = g["position"][fl] - centre
        r = np.hypot(d[:, 0], d[:, 1])
        er, et = d / r[:, None], np.stack([-d[:, 1], d[:, 0]], axis=1) / r[:, None]
        v = g["velocity"][fl]
        vt, vr = np.sum(v * et, axis=1), np.sum(v * er, axis=1)
        exact = circular_couette(r, R1, R2, omega1, omega2)
        S = max(abs(omega1) * R1, abs(omega2) * R2)
        e = float(np.max(np.abs(vt - exact))) / S
        radial = float(np.max(np.abs(vr))) / S
        drift = (_mass(g) - m0) / m0
        print(f"file: {path}\nR1 = {R1:.6g} m  R2 = {R2:.6g} m  omega1 = {omega1:.6g} rad/s  omega2 = {omega2:.6g} rad/s"
              f"  wall speed S = {S:.6g} m/s  frame {name} (t = {t:.6g} s), {int(fl.sum())} fluid particles", file=out)
        edges = np.linspace(R1, R2, bins + 1)
        which = np.clip(np.searchsorted(edges, r) - 1, 0, bins - 1)
        print(f"{'r [m]':>12} {'n':>6} {'mean v_theta':>14} {'A r + B/r':>12} {'diff [% S]':>11}", file=out)
        rows = []
        for b in range(bins):
            sel = which == b
            if not sel.any():
                continue
            rb = float(r[sel].mean())
            mean = float(vt[sel].mean())
            ref = float(circular_couette(rb, R1, R2, omega1, omega2))
            rows.append((rb, mean, ref))
            print(f"{rb:12.6g} {int(sel.sum()):6d} {mean:14.6g} {ref:12.6g} {100 * (mean - ref) / S:11.4f}", file=out)
        print(f"max |v_theta - (A r + B/r)| = {100 * e:.4g} % of S (pass below {100 * tolerance:g} %); "
              f"max |v_r| = {100 * radial:.4g} % of S; mass drift {drift:.2e}", file=out)
        if not e < tolerance:
            problems.append(f"azimuthal velocity error {100 * e:.4g} % >= {100 * tolerance:g} % of the wall speed")
        if not abs(drift) < MASS_DRIFT_LIMIT:
            problems.append(f"mass drift {drift:.3e}")
        if plot:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
            rr = np.linspace(R1, R2, 200)
            ax.plot(rr / R1, circular_couette(rr, R1, R2, omega1, omega2) / S, "k-", label="A r + B/r")
            ax.plot(r / R1, vt / S, ".", ms=1.5, alpha=0.3, color="tab:blue", label="particles")
            ax.plot([q[0] / R1 for q in rows], [q[1] / S for q in rows], "o", mfc="none", color="tab:red",
                    label=f"mean in {bins} bins")
            ax.set_xlabel("r / R1")
            ax.set_ylabel("v_theta / S")
            ax.set_title(f"circular Couette, t = {t:g} s")
            ax.legend()
            bx.axhspan(-100 * tolerance, 100 * tolerance, color="0.9", label=f"tolerance {100 * tolerance:g} %")
            bx.plot(r / R1, 100 * (vt - exact) / S, ".", ms=1.5, alpha=0.4, color="tab:blue", label="particles")
            bx.plot([q[0] / R1 for q in rows], [100 * (q[1] - q[2]) / S for q in rows], "o-", mfc="none",
                    color="tab:red", label="bin means")
            bx.set_xlabel("r / R1")
            bx.set_ylabel("(v_theta - (A r + B/r)) / S  [%]")
            bx.set_title(f"error: max {100 * e:.2g} % of S")
            bx.legend()
            fig.tight_layout()
            fig.savefig(plot, dpi=120)
            print(f"plot: {plot}", file=out)
    for p in problems:
        print(f"FAIL: {p}", file=err)
    print("RESULT: " + ("FAIL" if problems else "PASS"), file=out)
    return 1 if problems else 0


def circular_main(argv=None):
    ap = argparse.ArgumentParser(prog="circular_couette_check",
                                 description="Steady circular Couette flow against v = A r + B/r.")
    ap.add_argument("h5file", metavar="H5FILE")
    ap.add_argument("--time", type=float, help="time of the checked frame, s (default: the last frame)")
    ap.add_argument("--tolerance", type=float, default=0.01, help="fraction of the wall speed (default 0.01)")
    ap.add_argument("--bins", type=int, default=10, help="radial bins of the printed profile (default 10)")
    ap.add_argument("--plot", metavar="PNG", help="write the profile against the analytic one")
    a = ap.parse_args(argv)
    if a.bins < 1:
        ap.error("--bins must be at least 1")
    return circular(a.h5file, a.time, a.tolerance, a.bins, a.plot)


def couette_main(argv=None):
    ap = argparse.ArgumentParser(prog="couette_check", description="Start-up of plane Couette flow against the series.")
    ap.add_argument("h5file", metavar="H5FILE")
    ap.add_argument("--times", type=float, nargs="+", metavar="T")
    ap.add_argument("--tolerance", type=float, default=0.01, help="fraction of the wall speed (default 0.01)")
    a = ap.parse_args(argv)
    return couette(a.h5file, a.times, a.tolerance)


def rotation_main(argv=None):
    ap = argparse.ArgumentParser(prog="rotation_check", description="Spin-up in a rotating box toward solid-body rotation.")
    ap.add_argument("h5file", metavar="H5FILE")
    ap.add_argument("--time", type=float, help="time of the final check, s (default: the last frame)")
    ap.add_argument("--tolerance", type=float, default=0.001, help="fraction of omega L/2 (default 0.001)")
    ap.add_argument("--early-time", type=float, default=0.01)
    ap.add_argument("--early-minimum", type=float, default=0.3)
    ap.add_argument("--decay", type=float, nargs=2, metavar=("T1", "T2"))
    ap.add_argument("--decay-tolerance", type=float, default=0.1)
    a = ap.parse_args(argv)
    return rotation(a.h5file, a.time, a.tolerance, a.early_time, a.early_minimum, a.decay, a.decay_tolerance)
