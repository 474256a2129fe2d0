#!/usr/bin/python3
"""Check a vesph channel flow of a second-order fluid (thesis §4.3.2) against the analytic
solution.

Usage
-----
    /usr/bin/python3 tools/second_order_channel_check.py H5FILE [--tolerance 0.03]
        [--interior H_FRACTION] [--transient] [--retardation QUASI_H5 [--retardation-tolerance 0.01]]
        [--png OUT.png] [--csv OUT.csv]

Inputs come from the resolved scene stored in the file (root attribute ``scene``): rho =
fluid.density, mu = fluid.viscosity, [effects.second_order_fluid] form, derivative, alpha1,
alpha2, F = effects.body_force.acceleration[0], the channel from the fluid blocks (y0, y1; H,
centre y_c). nu = mu/rho.

Steady state (last frame): the Newtonian parabola v = F/(2 nu) (y - y0)(y1 - y), shear rate
g = dv/dy = -F (y - y_c)/nu, T_xy = mu g in every form, and the normal stresses of the form
(vesph/physics/constitutive/second_order_fluid.hpp; eps = c1 Ahat + c2 A.A with c1 = alpha1,
c2 = alpha2 for Rivlin-Ericksen and c1 = alpha1/2, c2 = -(alpha1/2 + alpha2) for CEF):
    T_xx = (c2 + x c1) g^2,  T_yy = (c2 + y c1) g^2 with (x, y) = (-2, 0) contravariant,
    (0, 2) covariant, (0, 0) mixed, (-1, 1) Jaumann;  N1 = T_xx - T_yy.
Compared over the interior particles (farther than --interior times H from the walls, default
0.1): v_x, T_xy, T_xx, T_yy, N1, each error divided by a scale: the largest analytic value of
that quantity, or for a quantity that vanishes identically (T_xx, T_yy, N1 of some forms) the
largest |c1| g^2 (the size of the elastic stress). All below --tolerance (default 3 %).

--transient: also compare the centreline velocity history with the start-up solution of the
linear problem rho dv/dt = mu v_yy + c1 d(v_yy)/dt + rho F (unsteady shear: DA_xy/Dt = dg/dt,
no convective part in T_xy),
    v(y, t) = sum_{n odd} 4 F H^2/(nu n^3 pi^3) sin(k_n (y - y0)) [1 - exp(-nu k_n^2 t/(1 + c1 k_n^2/rho))],
k_n = n pi/H, which holds when the scene computes DA/Dt (material_derivative = "lagged");
with "quasi_steady" the reference is the Newtonian start-up (c1 = 0 in the exponent). The
error at every frame, divided by the steady centreline velocity, must be below --tolerance.

--retardation QUASI_H5: H5FILE is a run with material_derivative = "lagged" and QUASI_H5 the
same scene with "quasi_steady". The difference of their centreline histories isolates what
DA/Dt adds, the retardation of the start-up; most of the spatial error cancels in it. It is
compared at every frame with the analytic difference (retarded minus Newtonian start-up);
the largest deviation, divided by v_max, must be below --retardation-tolerance (default 1 %).
The steady checks above still apply to H5FILE.
Exit 0 when every check passes, 1 otherwise.
"""
import argparse
import sys

import numpy as np

from vesph.analytic import coefficients, startup_velocity, steady_stresses
from vesph.output import Output, run_reporting_errors

def parameters(scene):
    eff = scene["effects"]
    m = eff.get("second_order_fluid")
    if m is None:
        raise ValueError("the scene has no [effects.second_order_fluid]")
    blocks = [b for b in scene["blocks"] if b["kind"] == "fluid"]
    return dict(
        rho=float(scene["fluid"]["density"]), mu=float(scene["fluid"]["viscosity"]),
        form=m.get("form", "rivlin_ericksen"), derivative=m.get("derivative", "contravariant"),
        alpha1=float(m["alpha1"]), alpha2=float(m["alpha2"]),
        lagged=m.get("material_derivative", "lagged") == "lagged",
        F=float(eff["body_force"]["acceleration"][0]),
        y0=min(b["min"][1] for b in blocks), y1=max(b["max"][1] for b in blocks))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("h5file")
    ap.add_argument("--tolerance", type=float, default=0.03)
    ap.add_argument("--interior", type=float, default=0.1)
    ap.add_argument("--transient", action="store_true")
    ap.add_argument("--retardation")
    ap.add_argument("--retardation-tolerance", type=float, default=0.01)
    ap.add_argument("--png")
    ap.add_argument("--csv")
    a = ap.parse_args(argv)
    return run_reporting_errors("second_order_channel_check", check, a)


def centreline_velocity(fr, yc, H):
    """(y, v_x, the mask of the two rows next to the centreline) of the fluid of a frame."""
    fl = fr["kind"] == 0
    y = fr["position"][fl, 1]
    dist = np.abs(y - yc)
    return y, fr["velocity"][fl, 0], dist <= dist.min() * (1 + 1e-6) + 1e-12 * H


def check(a):
    with Output(a.h5file) as out:
        scene = out.scene
        P = parameters(scene)
        rho, mu, F = P["rho"], P["mu"], P["F"]
        nu = mu / rho
        H = P["y1"] - P["y0"]
        yc = 0.5 * (P["y0"] + P["y1"])
        c1, c2 = coefficients(P["form"], P["alpha1"], P["alpha2"])
        vmax = F * H * H / (8 * nu)
        gmax = F * H / (2 * nu)
        print(f"{P['form']} / {P['derivative']}: alpha1 = {P['alpha1']:g}, alpha2 = {P['alpha2']:g} Pa s^2, "
              f"v_max = {vmax:.4g} m/s, wall shear rate {gmax:.4g} 1/s, DA/Dt "
              f"{'lagged' if P['lagged'] else 'quasi-steady'}")
        ok = True
        history = []
        for k, (name, t) in enumerate(out.frames):
            y, vx, central = centreline_velocity(out.read(k, ("kind", "position", "velocity")), yc, H)
            ref = startup_velocity(y[central] - P["y0"], t, F, nu, H, c1 / rho if P["lagged"] else 0.0).mean()
            newt = startup_velocity(y[central] - P["y0"], t, F, nu, H, 0.0).mean()
            history.append((t, float(vx[central].mean()), float(ref), float(newt)))
        if a.transient:
            errs = [abs(s - r) / vmax for _, s, r, _ in history]
            worst = int(np.argmax(errs))
            print(f"centreline history: largest error {100*errs[worst]:.3f} % of v_max at t = {history[worst][0]:g} s "
                  f"(reference {'retarded, c1/rho = %.3g m^2' % (c1/rho) if P['lagged'] else 'Newtonian'}); "
                  f"largest retarded-Newtonian difference {100*max(abs(r-n) for _, _, r, n in history)/vmax:.3f} %")
            if not errs[worst] < a.tolerance:
                print(f"FAIL: centreline error {100*errs[worst]:.3f} % >= {100*a.tolerance:g} %")
                ok = False
        if a.retardation:
            if not P["lagged"]:
                print("FAIL: --retardation needs H5FILE run with material_derivative = \"lagged\"")
                return 1
            with Output(a.retardation) as q:
                if len(q.frames) != len(out.frames):
                    print("FAIL: the two runs have different frames")
                    return 1
                worst, peak = 0.0, 0.0
                for k, (t, vl, ref, newt) in enumerate(history):
                    if abs(q.frames[k][1] - t) > 1e-9 * max(t, 1e-30):
                        print("FAIL: the two runs have different frame times")
                        return 1
                    _, vq, central = centreline_velocity(q.read(k, ("kind", "position", "velocity")), yc, H)
                    dsim = vl - float(vq[central].mean())
                    worst = max(worst, abs(dsim - (ref - newt)))
                    peak = max(peak, abs(ref - newt))
                print(f"retardation by DA/Dt: peak (analytic) {100*peak/vmax:.3f} % of v_max, largest deviation of "
                      f"lagged minus quasi-steady from it {100*worst/vmax:.3f} % of v_max "
                      f"({100*worst/peak if peak > 0 else 0:.1f} % of the effect)")
                if not worst / vmax < a.retardation_tolerance:
                    print(f"FAIL: retardation deviation {100*worst/vmax:.3f} % >= {100*a.retardation_tolerance:g} %")
                    ok = False
        last = len(out.frames) - 1
        t = out.frames[last][1]
        if not out.has(last, "extra_stress"):
            print("FAIL: the frames have no extra_stress")
            return 1
        g = out.read(last, ("kind", "position", "velocity", "extra_stress"))
        fl = g["kind"] == 0
        y = g["position"][fl, 1]
        vx = g["velocity"][fl, 0]
        T = g["extra_stress"][fl]
        interior = np.abs(y - yc) <= 0.5 * H - a.interior * H
        shear = -F * (y - yc) / nu
        v_exact = F / (2 * nu) * (y - P["y0"]) * (P["y1"] - y)
        txx, txy, tyy = steady_stresses(P["form"], P["derivative"], P["alpha1"], P["alpha2"], mu, shear)
        elastic_scale = abs(c1) * gmax ** 2
        rows = []
        for nm, sim, ex in (("v_x", vx, v_exact), ("T_xy", T[:, 1], txy), ("T_xx", T[:, 0], txx),
                            ("T_yy", T[:, 2], tyy), ("N1", T[:, 0] - T[:, 2], txx - tyy)):
            scale = float(np.max(np.abs(ex)))
            if scale < 1e-9 * (elastic_scale + mu * gmax):
                scale = elastic_scale
            err = float(np.max(np.abs(sim[interior] - ex[interior]))) / scale
            rows.append((nm, err, scale))
            flag = "" if err < a.tolerance else "  FAIL"
            print(f"steady {nm:5s} at t = {t:g} s over {int(interior.sum())} interior particles: "
                  f"error {100*err:.3f} % of {scale:.4g}{flag}")
            ok = ok and err < a.tolerance
        if a.csv:
            with open(a.csv, "w") as csv_file:
                csv_file.write("y_m,vx_m_s,vx_exact,Txx_Pa,Txx_exact,Txy_Pa,Txy_exact,Tyy_Pa,Tyy_exact\n")
                for k in np.argsort(y):
                    csv_file.write(",".join(f"{v:.10g}" for v in (y[k], vx[k], v_exact[k], T[k, 0], txx[k], T[k, 1],
                                                             txy[k], T[k, 2], tyy[k])) + "\n")
        if a.png:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            fig, axs = plt.subplots(1, 4, figsize=(14, 3.8))
            o = np.argsort(y)
            for ax, nm, sim, ex in zip(axs, ("v_x [m/s]", "T_xy [Pa]", "N1 [Pa]", "T_yy [Pa]"),
                                       (vx, T[:, 1], T[:, 0] - T[:, 2], T[:, 2]), (v_exact, txy, txx - tyy, tyy)):
                ax.plot(y[o] / H, ex[o], "k-", label="analytic")
                ax.plot(y[o] / H, sim[o], "o", ms=2.5, label="vesph")
                ax.set_xlabel("y / H")
                ax.set_title(nm)
                ax.grid(alpha=0.3)
            axs[0].legend()
            fig.suptitle(f"second-order fluid, {P['form']} / {P['derivative']}, t = {t:g} s")
            fig.tight_layout()
            fig.savefig(a.png, dpi=100)
            print(f"wrote {a.png}")
    print("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
