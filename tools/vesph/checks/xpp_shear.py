#!/usr/bin/python3
"""Steady homogeneous simple shear of the single-equation XPP model (Verbeeten, Peters &
Baaijens, J. Rheol. 45 (2001) 823), solved independently of vesph, and a check of a vesph
start-up channel flow of an XPP fluid against it.

Usage
-----
    /usr/bin/python3 tools/xpp_steady_shear.py solve --rate GDOT --modulus G
        --lambda-b L0B --ratio R --arms Q --anisotropy ALPHA [--solvent ETA_S] [--ode]
    /usr/bin/python3 tools/xpp_steady_shear.py check H5FILE [--tolerance 0.03]
        [--interior H_FRACTION] [--n1d CELLS] [--csv OUT.csv] [--png OUT.png]
        [--transient] [--bound 2] [--roughness 0.01]
        [--transient-png OUT.png] [--transient-csv OUT.csv]

Model (SI units; tau the polymer stress, a 3x3 tensor; G the modulus, lambda_0b the backbone
orientation relaxation time, r = lambda_0b/lambda_0s, nu = 2/q, alpha the anisotropy):

    tau^nabla + (1/lambda_0b) [ (alpha/G) tau.tau + F tau + G (F - 1) I ] = 2 G D
    F = 2 r e^{nu (Lambda - 1)} (1 - 1/Lambda) + (1/Lambda^2) [1 - alpha tr(tau.tau)/(3 G^2)]
    Lambda = sqrt(1 + tr(tau)/(3 G))

In steady simple shear v_x = gdot y the unknowns are tau_xx, tau_xy, tau_yy, tau_zz
(tau_xz = tau_yz = 0) and the upper-convected derivative reduces to
(-2 gdot tau_xy, -gdot tau_yy, 0, 0), so the steady equations are four algebraic equations
(`shear_residual`). `steady_shear` solves them by Newton's method (scipy fsolve) with
continuation in gdot from the linear (UCM) solution; `steady_shear_ode` integrates the
homogeneous ODE dtau/dt = kappa tau + tau kappa^T - ... + G (kappa + kappa^T) from rest to
steady state instead (the check of the algebraic route). The total shear stress adds the
solvent: T_xy = eta_s gdot + tau_xy.

check: a steady, fully developed channel flow (periodic along x, walls at the y-limits of the
fluid blocks, driven by the body force F) has, whatever the fluid, the shear stress
T_xy(y) = -rho F (y - y_c) (momentum balance), and every material point sits in steady simple
shear at its local rate (D/Dt = 0 in fully developed flow). The reference at a particle is
therefore the homogeneous steady shear at the local shear STRESS: the rate gdot(y) solves
eta_s gdot + tau_xy(gdot) = -rho F (y - y_c) (the flow curve, tabulated with continuation,
is inverted; the SPH velocity gradient is not used: the reference takes nothing from the
simulation but the particle positions), and the reference velocity is v(y) = integral of
gdot from the wall (no slip at the y-limits of the fluid blocks). The normal stresses follow
from gdot(y). At the last frame, over the interior particles (farther than --interior times
the channel height from the walls, default 0.1):

    T_xy (extra_stress[:,1], total)         vs -rho F (y - y_c)
    tau_xy = T_xy - eta_s dv/dy             vs tau_xy(gdot(y)); dv/dy from a quadratic
                                               least-squares fit of the particle velocities
                                               within 2.5 dx in y (only the solvent part)
    T_xx = tau_xx, T_yy = tau_yy            vs tau_xx, tau_yy  (planar steady shear: D_xx = D_yy = 0)
    N1 = T_xx - T_yy                        vs tau_xx - tau_yy
    T_zz = tau_zz (extra_stress_zz)         vs tau_zz          (when the file has it; N2 reported)
    v_x                                     vs v(y)

each error divided by the largest reference magnitude of that quantity over the channel,
below --tolerance (default 3 %).

Is the last frame steady? The start-up of the fully developed flow is exactly
one-dimensional for an incompressible fluid (`startup_1d`: rho dv/dt = rho F + dT_xy/dy,
tau by the homogeneous XPP equations at the local rate; method of lines, --n1d cells,
default 64). The check requires this 1-D start-up, at the time of the last frame, to be
within tolerance/6 of the steady state (centreline velocity and the stresses at the wall);
otherwise it fails with "not steady".

--transient also checks the start-up history at every frame: every velocity and stress
finite; the centreline velocity (mean of the two particle rows next to the centreline) and
the largest |T_xy| and T_xx over the interior particles, each divided by its steady value
(the velocity's at the centre, the stresses' at the edge of the interior band), at most
--bound (default 2); each within --tolerance of the same quantity of the 1-D start-up
(evaluated at the same particle positions) at every frame; and the frame-to-frame second
difference of that deviation below --roughness (default 0.01): an oscillation from frame to
frame that the 1-D start-up does not have (an instability) fails it, while the physical
overshoot and undershoot do not. --transient-csv/--transient-png write the histories.

Exit status 0 when every check passes, 1 otherwise (2 for bad input).
"""
import argparse
import sys

import numpy as np

from vesph.analytic import Xpp, channel_reference, startup_1d, steady_shear, steady_shear_ode
from vesph.output import Output, ToolError


def scene_parameters(scene):
    """Xpp, rho, F, y0, y1 from the resolved scene of a vesph file."""
    eff = scene["effects"]
    if "xpp" not in eff:
        raise ValueError("the scene has no [effects.xpp]")
    m = eff["xpp"]
    lam_b = float(m["backbone_relaxation_time"])
    G = float(m["modulus"]) if "modulus" in m else float(m["polymer_viscosity"]) / lam_b
    r = float(m["relaxation_ratio"]) if "relaxation_ratio" in m else lam_b / float(m["stretch_relaxation_time"])
    eta_s = float(scene["fluid"]["viscosity"]) if "viscosity" in eff else 0.0
    p = Xpp(G, lam_b, r, float(m["arms"]), float(m["anisotropy"]), eta_s)
    blocks = [b for b in scene["blocks"] if b["kind"] == "fluid"]
    y0 = min(b["min"][1] for b in blocks)
    y1 = max(b["max"][1] for b in blocks)
    rho = float(scene["fluid"]["density"])
    F = float(eff["body_force"]["acceleration"][0])
    return p, rho, F, y0, y1


def local_slope(y, v, width):
    """dv/dy at each particle: quadratic least squares over particles within `width` in y."""
    order = np.argsort(y)
    ys, vs = y[order], v[order]
    out = np.empty_like(y)
    lo = np.searchsorted(ys, ys - width, "left")
    hi = np.searchsorted(ys, ys + width, "right")
    for k in range(len(ys)):
        yy = ys[lo[k]:hi[k]] - ys[k]
        c = np.polyfit(yy, vs[lo[k]:hi[k]], 2)
        out[order[k]] = c[1]
    return out


def read_frames(path):
    """(scene, dx, frames): per frame its time and the fluid's y, v_x and, when stored, the
    extra stress T (xx, xy, yy) and T_zz."""
    with Output(path) as out:
        frames = []
        for k, (_, t) in enumerate(out.frames):
            g = out.read(k, ("kind", "position", "velocity"), optional=("extra_stress", "extra_stress_zz"))
            fl = g["kind"] == 0
            fr = {"time": t, "y": g["position"][fl, 1], "vx": g["velocity"][fl, 0]}
            if "extra_stress" in g:
                fr["T"] = g["extra_stress"][fl]
            if "extra_stress_zz" in g:
                fr["Tzz"] = g["extra_stress_zz"][fl]
            frames.append(fr)
        return out.scene, out.dx, frames


def central_rows(y, yc, half):
    dist = np.abs(y - yc)
    return dist <= dist.min() * (1 + 1e-6) + 1e-12 * half


def check(a, scene, dx, frames):
    """The steady-state checks at the last frame; returns (ok, context for transient)."""
    p, rho, F, y0, y1 = scene_parameters(scene)
    print(p.describe())
    last = frames[-1]
    ref_all = channel_reference(np.linspace(y0, y1, 201), p, rho, F, y0, y1)
    curve = ref_all["curve"]
    half, yc = ref_all["half"], ref_all["yc"]
    gw = abs(ref_all["gdot"][0])
    wi = p.lam_b * gw
    Tw = rho * abs(F) * half
    vc = float(np.max(np.abs(ref_all["v"])))
    eta0 = p.eta_s + p.eta_p
    print(f"steady reference: wall shear stress {Tw:.5g} Pa, wall rate {gw:.5g} 1/s, "
          f"Wi = lambda_0b gdot_w = {wi:.4g}, viscosity at the wall {Tw/gw:.5g} Pa s "
          f"({100*(1-Tw/gw/eta0):.1f} % below eta0 = {eta0:.5g} Pa s), centreline velocity {vc:.5g} m/s "
          f"({vc/(Tw*half/(2*eta0)):.3f} times that of a Newtonian fluid of viscosity eta0)")
    ok = True
    t = last["time"]
    # Is the last frame steady? The 1-D start-up (the same problem without SPH) at that time
    # must be within tolerance/6 of the steady state, in the centreline velocity and the
    # stresses at the wall.
    times = np.array([fr["time"] for fr in frames]) if a.transient else np.array([0.0, t])
    y1d, v1d, tau1d, yf1d = startup_1d(p, rho, F, y0, y1, times, n=a.n1d)
    drift_v = abs(np.interp(yc, y1d, v1d[-1]) - vc) / vc
    drift_s = max(abs(tau1d[-1, k, 0] - ref_all["tau"][0, k]) / float(np.max(np.abs(ref_all["tau"][:, k])))
                  for k in range(4))
    print(f"the 1-D start-up at t/lambda_0b = {t/p.lam_b:.3g} is {100*drift_v:.3f} % (velocity) and "
          f"{100*drift_s:.3f} % (wall stresses) from the steady state")
    if not max(drift_v, drift_s) < a.tolerance / 6:
        print(f"FAIL: the last frame (t = {t:g} s) is not steady: the start-up has not decayed below "
              f"{100*a.tolerance/6:.3g} % (run longer)")
        ok = False
    if "T" not in last:
        print("FAIL: the frames have no extra_stress")
        return False, None
    y = last["y"]
    ref = channel_reference(y, p, rho, F, y0, y1, curve=curve)
    interior = np.abs(y - yc) <= half - a.interior * 2 * half
    T = last["T"]
    gdot_sim = local_slope(y, last["vx"], 2.5 * dx)
    sim = {
        "T_xy": T[:, 1],
        "tau_xy": T[:, 1] - p.eta_s * gdot_sim,
        "tau_xx": T[:, 0],
        "tau_yy": T[:, 2],
        "N1": T[:, 0] - T[:, 2],
        "v_x": last["vx"],
    }
    tau = ref["tau"]
    exact = {"T_xy": ref["T_xy"], "tau_xy": tau[:, 1], "tau_xx": tau[:, 0], "tau_yy": tau[:, 2],
             "N1": tau[:, 0] - tau[:, 2], "v_x": ref["v"]}
    rt = ref_all["tau"]
    scale_src = {"T_xy": ref_all["T_xy"], "tau_xy": rt[:, 1], "tau_xx": rt[:, 0], "tau_yy": rt[:, 2],
                 "N1": rt[:, 0] - rt[:, 2], "v_x": ref_all["v"]}
    if "Tzz" in last:
        sim["tau_zz"] = last["Tzz"]
        exact["tau_zz"] = tau[:, 3]
        scale_src["tau_zz"] = rt[:, 3]
        sim["N2"] = T[:, 2] - last["Tzz"]
        exact["N2"] = tau[:, 2] - tau[:, 3]
        scale_src["N2"] = rt[:, 2] - rt[:, 3]
    print(f"steady state at t/lambda_0b = {t/p.lam_b:.3g} over {int(interior.sum())} interior particles "
          f"(error / largest reference magnitude; N2 reported, not checked):")
    errors = {}
    for k in sim:
        scale = float(np.max(np.abs(scale_src[k])))
        e = float(np.max(np.abs(sim[k][interior] - exact[k][interior]))) / scale
        errors[k] = e
        checked = k != "N2"
        flag = "" if (e < a.tolerance or not checked) else "   <-- FAIL"
        print(f"  {k:7s} max |ref| {scale:12.5g}   error {100*e:7.3f} %{flag}")
        if checked and not e < a.tolerance:
            ok = False
    if a.csv:
        keys = list(sim)
        with open(a.csv, "w") as out:
            out.write("y," + ",".join(f"{k}_sim,{k}_ref" for k in keys) + ",interior\n")
            for i in np.argsort(y):
                out.write(f"{y[i]:.10g}," + ",".join(f"{sim[k][i]:.10g},{exact[k][i]:.10g}" for k in keys)
                          + f",{int(interior[i])}\n")
        print(f"wrote {a.csv}")
    if a.png:
        plot_profiles(a.png, y, sim, ref_all, yc, half, p, wi, t)
    ctx = {"p": p, "rho": rho, "F": F, "ref_all": ref_all, "yc": yc, "half": half, "vc": vc,
           "times": times, "y1d": y1d, "v1d": v1d, "tau1d": tau1d, "yf1d": yf1d, "errors": errors}
    return ok, ctx


def plot_profiles(path, y, sim, ref_all, yc, half, p, wi, t):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    Y = (y - yc) / half
    Ys = np.linspace(-1, 1, len(ref_all["v"]))
    keys = [k for k in ("v_x", "T_xy", "N1", "tau_yy", "tau_zz") if k in sim]
    labels = {"v_x": "v_x [m/s]", "T_xy": "T_xy [Pa]", "N1": "N1 = T_xx - T_yy [Pa]",
              "tau_yy": "T_yy = tau_yy [Pa]", "tau_zz": "T_zz = tau_zz [Pa]"}
    rt = ref_all["tau"]
    src = {"v_x": ref_all["v"], "T_xy": ref_all["T_xy"], "N1": rt[:, 0] - rt[:, 2],
           "tau_yy": rt[:, 2], "tau_zz": rt[:, 3]}
    fig, axs = plt.subplots(1, len(keys), figsize=(3.0 * len(keys), 3.8), sharey=True)
    for ax, k in zip(axs, keys):
        ax.plot(src[k], Ys, "k-", lw=1.2, label="homogeneous XPP")
        ax.plot(sim[k], Y, ".", ms=2.5, color="tab:blue", label="vesph")
        ax.set_xlabel(labels[k])
        ax.grid(alpha=0.3)
    if "v_x" in sim:
        eta0 = p.eta_s + p.eta_p
        Tw = abs(ref_all["T_xy"][0])
        axs[0].plot(Tw * half / (2 * eta0) * (1 - Ys ** 2), Ys, "k:", lw=1, label="Newtonian, eta0")
    axs[0].set_ylabel("(y - y_c)/a")
    axs[0].legend(fontsize=7, loc="lower left")
    fig.suptitle(f"XPP channel at t/lambda_0b = {t/p.lam_b:.3g}: Wi_wall = {wi:.3g}, r = {p.r:g}, q = {p.q:g}, "
                 f"alpha = {p.alpha:g}, beta = {p.eta_s/(p.eta_s+p.eta_p):.3g}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def transient(a, frames, ctx):
    """Start-up history: finite, bounded, smooth; and against the 1-D start-up."""
    p, half, yc, vc = ctx["p"], ctx["half"], ctx["yc"], ctx["vc"]
    # steady values of the interior maxima: at the edge of the interior band
    lim = half - a.interior * 2 * half
    edge = ctx["ref_all"]["curve"].tau_at_rate(ctx["ref_all"]["curve"].rate_at_stress(ctx["rho"] * abs(ctx["F"]) * lim))
    txy_ref = ctx["rho"] * abs(ctx["F"]) * lim
    txx_ref = float(edge[0])
    y1d, v1d, tau1d, yf1d = ctx["y1d"], ctx["v1d"], ctx["tau1d"], ctx["yf1d"]
    rows = []
    ok = True
    for k, fr in enumerate(frames):
        y = fr["y"]
        vals = [fr["vx"]] + ([fr["T"]] if "T" in fr else []) + ([fr["Tzz"]] if "Tzz" in fr else [])
        if not all(np.all(np.isfinite(v)) for v in vals):
            print(f"FAIL: non-finite velocity or stress at t = {fr['time']:g} s")
            return False
        c = central_rows(y, yc, half)
        uc = float(fr["vx"][c].mean())
        uc_1d = float(np.interp(y[c], y1d, v1d[k]).mean())
        interior = np.abs(y - yc) <= lim
        if "T" in fr:
            mxy = float(np.max(np.abs(fr["T"][interior, 1])))
            mxx = float(np.max(fr["T"][interior, 0]))
        else:
            mxy = mxx = 0.0
        # the 1-D reference at the same interior particles (interpolated from the cell faces),
        # total T_xy = eta_s gdot + tau_xy
        v_ext = np.concatenate([[-v1d[k][0]], v1d[k], [-v1d[k][-1]]])
        g1d = np.diff(v_ext) / (y1d[1] - y1d[0])
        yi = y[interior]
        mxy_1d = float(np.max(np.abs(np.interp(yi, yf1d, p.eta_s * g1d + tau1d[k, 1]))))
        mxx_1d = float(np.max(np.interp(yi, yf1d, tau1d[k, 0])))
        rows.append((fr["time"], fr["time"] / p.lam_b, uc / vc, uc_1d / vc, mxy / txy_ref, mxy_1d / txy_ref,
                     mxx / txx_ref, mxx_1d / txx_ref))
    R = np.array(rows)
    print(f"start-up histories over {len(R)} frames, divided by their steady values (U_c {vc:.5g} m/s; "
          f"interior max |T_xy| {txy_ref:.5g} Pa and T_xx {txx_ref:.5g} Pa, at |y - y_c| = {lim:.4g} m), "
          f"vesph and the 1-D start-up:")
    print(f"{'t/lambda':>9} {'U_c':>8} {'1-D':>8} {'|T_xy|':>8} {'1-D':>8} {'T_xx':>8} {'1-D':>8}")
    for r in R:
        print(f"{r[1]:9.3f} " + " ".join(f"{v:8.4f}" for v in r[2:]))
    names = (("centreline velocity", 2), ("max |T_xy|", 4), ("max T_xx", 6))
    for nm, col in names:
        h, h1 = R[:, col], R[:, col + 1]
        peak = float(np.max(np.abs(h)))
        dev = h - h1
        kdev = int(np.argmax(np.abs(dev)))
        rough = float(np.max(np.abs(np.diff(dev, 2)))) if len(h) > 2 else 0.0
        bad = [peak > a.bound, not rough < a.roughness, not abs(dev[kdev]) < a.tolerance]
        print(f"  {nm:20s} peak {peak:.4f} (bound {a.bound:g}); deviation from the 1-D start-up: largest "
              f"{100*abs(dev[kdev]):.2f} % at t/lambda_0b = {R[kdev, 1]:.3g} (bound {100*a.tolerance:g} %), "
              f"largest second difference {rough:.4f} (bound {a.roughness:g})"
              f"{'   <-- FAIL' if any(bad) else ''}")
        ok = ok and not any(bad)
    if a.transient_csv:
        with open(a.transient_csv, "w") as out:
            out.write("time_s,t_over_lambda_b,centreline,centreline_1d,max_abs_Txy,max_abs_Txy_1d,max_Txx,"
                      "max_Txx_1d\n")
            for r in R:
                out.write(",".join(f"{v:.10g}" for v in r) + "\n")
        print(f"wrote {a.transient_csv}")
    if a.transient_png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4.2))
        for (nm, col), colr in zip(names, ("tab:blue", "tab:orange", "tab:green")):
            ax.plot(R[:, 1], R[:, col + 1], "-", color=colr, lw=1.2)
            ax.plot(R[:, 1], R[:, col], "o", color=colr, ms=3, label=f"{nm} (vesph; line: 1-D start-up)")
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        ax.set_xlabel("t / lambda_0b")
        ax.set_ylabel("value / steady value")
        ax.set_title(f"XPP start-up channel flow: Wi_wall = {p.lam_b*abs(ctx['ref_all']['gdot'][0]):.3g}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.transient_png, dpi=110)
        print(f"wrote {a.transient_png}")
    return ok


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("solve", help="steady homogeneous shear at one rate")
    s.add_argument("--rate", type=float, required=True, help="shear rate, 1/s")
    s.add_argument("--modulus", type=float, required=True, help="G, Pa")
    s.add_argument("--lambda-b", type=float, required=True, help="lambda_0b, s")
    s.add_argument("--ratio", type=float, required=True, help="r = lambda_0b/lambda_0s")
    s.add_argument("--arms", type=float, required=True, help="q")
    s.add_argument("--anisotropy", type=float, required=True, help="alpha")
    s.add_argument("--solvent", type=float, default=0.0, help="eta_s, Pa s")
    s.add_argument("--ode", action="store_true", help="also integrate the homogeneous ODE")
    c = sub.add_parser("check", help="check a vesph XPP channel output")
    c.add_argument("h5file")
    c.add_argument("--tolerance", type=float, default=0.03)
    c.add_argument("--interior", type=float, default=0.1)
    c.add_argument("--n1d", type=int, default=64, help="cells of the 1-D start-up reference")
    c.add_argument("--csv")
    c.add_argument("--png")
    c.add_argument("--transient", action="store_true")
    c.add_argument("--bound", type=float, default=2.0)
    c.add_argument("--roughness", type=float, default=0.01)
    c.add_argument("--transient-csv")
    c.add_argument("--transient-png")
    a = ap.parse_args(argv)
    if a.cmd == "solve":
        p = Xpp(a.modulus, a.lambda_b, a.ratio, a.arms, a.anisotropy, a.solvent)
        x = steady_shear(a.rate, p)
        print(p.describe())
        print(f"gdot = {a.rate:g} 1/s, Wi = {a.rate*p.lam_b:g}")
        print(f"tau_xx = {x[0]:.10g} Pa, tau_xy = {x[1]:.10g} Pa, tau_yy = {x[2]:.10g} Pa, tau_zz = {x[3]:.10g} Pa")
        print(f"eta = {(p.eta_s*a.rate + x[1])/a.rate:.10g} Pa s, N1 = {x[0]-x[2]:.10g} Pa, N2 = {x[2]-x[3]:.10g} Pa")
        if a.ode:
            y = steady_shear_ode(a.rate, p)
            print(f"ODE route: {y}  max difference {np.max(np.abs(y - x)):.3g} Pa")
        return 0
    try:
        scene, dx, frames = read_frames(a.h5file)
        ok, ctx = check(a, scene, dx, frames)
        if a.transient and ctx is not None:
            ok = transient(a, frames, ctx) and ok
    except (OSError, KeyError, ValueError, RuntimeError, ToolError) as e:
        print(f"error: {e}")
        return 2
    print("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
