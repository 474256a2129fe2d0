#!/usr/bin/python3
"""Check a vesph start-up channel flow of an Oldroyd-B (or UCM) fluid against the transient
solution of Waters & King (1970).

Usage
-----
    /usr/bin/python3 tools/startup_channel_check.py H5FILE [--tolerance 0.03]
        [--interior H_FRACTION] [--png OUT.png] [--csv OUT.csv]

Inputs come from the resolved scene stored in the file (root attribute ``scene``):
rho = fluid.density, eta_s = fluid.viscosity (solvent), eta_p =
effects.oldroyd_b.polymer_viscosity (or effects.ucm), lambda = relaxation_time,
F = effects.body_force.acceleration[0], and the channel (the y-extent of the fluid blocks),
half-width a, centre y_c. With eta0 = eta_s + eta_p, nu0 = eta0/rho:

    E = lambda eta0/(rho a^2),  beta = eta_s/eta0,  Ubar = F a^2/(3 nu0),  T = t/lambda,
    Y = (y - y_c)/a
    U/Ubar = 1.5 (1 - Y^2) + sum_{k>=1} 48 (-1)^k / N^3 cos(N Y/2) A_k(T),  N = (2k-1) pi
    alpha = E N^2/4, b = (1 + beta alpha)/2, d = b^2 - alpha
    d > 0: c = sqrt(d), A = 0.5(1+g) e^{(c-b)T} + 0.5(1-g) e^{-(b+c)T}, g = (b - alpha)/c
    d < 0: c = sqrt(-d), A = e^{-bT} [cos(cT) + (b - alpha)/c sin(cT)]

Checks (exit 0 when all pass, 1 otherwise):
1. centreline velocity history: at every frame, the mean x-velocity of the two particle rows
   next to the centreline against the analytic mean at the same rows, error divided by the
   steady centreline velocity 1.5 Ubar, below --tolerance (default 3 %);
2. the steady stresses at the last frame (which must be at T >= 8, where every transient mode
   has decayed below 0.5 %): T_xy = eta0 dv/dy and T_xx = 2 lambda eta_p (dv/dy)^2 with the
   steady dv/dy = -F (y - y_c)/nu0, over the interior particles (farther than --interior
   times the channel height from the walls, default 0.1), error divided by the largest
   analytic value of that component, below --tolerance.
Also printed: the largest profile error over all fluid particles at each frame.
"""
import argparse
import sys

import numpy as np

from vesph.analytic import waters_king
from vesph.output import Output, run_reporting_errors


def parameters(scene):
    fl = scene["fluid"]
    eff = scene["effects"]
    model = eff.get("oldroyd_b") or eff.get("ucm")
    if model is None:
        raise ValueError("the scene has no [effects.oldroyd_b] or [effects.ucm]")
    blocks = [b for b in scene["blocks"] if b["kind"] == "fluid"]
    y0 = min(b["min"][1] for b in blocks)
    y1 = max(b["max"][1] for b in blocks)
    rho = float(fl["density"])
    eta_s = float(fl["viscosity"])
    eta_p = float(model["polymer_viscosity"])
    lam = float(model["relaxation_time"])
    F = float(eff["body_force"]["acceleration"][0])
    return rho, eta_s, eta_p, lam, F, y0, y1


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("h5file")
    ap.add_argument("--tolerance", type=float, default=0.03)
    ap.add_argument("--interior", type=float, default=0.1)
    ap.add_argument("--png")
    ap.add_argument("--csv")
    a = ap.parse_args(argv)
    return run_reporting_errors("startup_channel_check", check, a)


def check(a):
    with Output(a.h5file) as out:
        scene = out.scene
        rho, eta_s, eta_p, lam, F, y0, y1 = parameters(scene)
        eta0 = eta_s + eta_p
        nu0 = eta0 / rho
        half = 0.5 * (y1 - y0)
        yc = y0 + half
        E = lam * eta0 / (rho * half * half)
        beta = eta_s / eta0
        ubar = F * half * half / (3 * nu0)
        uc = 1.5 * ubar
        print(f"E = {E:.4g}, beta = {beta:.4g}, lambda = {lam:g} s, steady centreline velocity {uc:.4g} m/s")
        rows = []
        last = None
        for k, (name, t) in enumerate(out.frames):
            g = out.read(k, ("kind", "position", "velocity"))
            fl = g["kind"] == 0
            y = g["position"][fl, 1]
            vx = g["velocity"][fl, 0]
            Y = (y - yc) / half
            T = t / lam
            exact = waters_king(Y, T, E, beta) * ubar
            # the two rows next to the centreline
            dist = np.abs(y - yc)
            central = dist <= dist.min() * (1 + 1e-6)
            cl_sim = float(vx[central].mean())
            cl_exact = float(exact[central].mean())
            cl_err = abs(cl_sim - cl_exact) / uc
            prof_err = float(np.max(np.abs(vx - exact))) / uc
            rows.append((t, T, cl_sim, cl_exact, cl_err, prof_err))
            last = (k, fl, y, t)
        bad = [r for r in rows if not r[4] < a.tolerance]
        print(f"{'t [s]':>9} {'t/lambda':>9} {'U_c sim':>12} {'U_c exact':>12} {'cl err %':>9} {'profile err %':>13}")
        for r in rows:
            print(f"{r[0]:9.4g} {r[1]:9.4g} {r[2]:12.5g} {r[3]:12.5g} {100*r[4]:9.3f} {100*r[5]:13.3f}")
        ok = not bad
        if bad:
            print(f"FAIL: centreline error above {100*a.tolerance:g} % at {len(bad)} frame(s), worst "
                  f"{100*max(r[4] for r in bad):.3f} % at t = {max(bad, key=lambda r: r[4])[0]:g} s")
        # steady stresses at the last frame
        k, fl, y, t = last
        if t / lam < 8:
            print(f"FAIL: the last frame is at t/lambda = {t/lam:.3g} < 8, not steady")
            ok = False
        elif not out.has(k, "extra_stress"):
            print("FAIL: the frames have no extra_stress")
            ok = False
        else:
            T = out.read(k, ("extra_stress",))["extra_stress"][fl]
            yy = y - yc
            interior = np.abs(yy) <= half - a.interior * 2 * half
            dvdy = -F * yy / nu0
            txy = eta0 * dvdy
            txx = 2 * lam * eta_p * dvdy ** 2
            e_xy = float(np.max(np.abs(T[interior, 1] - txy[interior]))) / float(np.max(np.abs(txy)))
            e_xx = float(np.max(np.abs(T[interior, 0] - txx[interior]))) / float(np.max(np.abs(txx)))
            print(f"steady stresses at t/lambda = {t/lam:.3g} over {int(interior.sum())} interior particles: "
                  f"T_xy error {100*e_xy:.3f} %, T_xx error {100*e_xx:.3f} % (of their maxima)")
            for nm, e in (("T_xy", e_xy), ("T_xx", e_xx)):
                if not e < a.tolerance:
                    print(f"FAIL: {nm} error {100*e:.3f} % >= {100*a.tolerance:g} %")
                    ok = False
        if a.csv:
            with open(a.csv, "w") as csv_file:
                csv_file.write("time_s,t_over_lambda,centreline_sim,centreline_exact,centreline_error,profile_error\n")
                for r in rows:
                    csv_file.write(",".join(f"{v:.10g}" for v in r) + "\n")
        if a.png:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            fig, ax = plt.subplots(figsize=(7, 4.5))
            ts = np.linspace(0, rows[-1][1], 400)
            ax.plot(ts, [waters_king(np.array([0.0]), T_, E, beta)[0] * ubar / uc for T_ in ts], "k-", label="Waters & King")
            ax.plot([r[1] for r in rows], [r[2] / uc for r in rows], "o", ms=3, label="vesph (centre rows)")
            ax.set_xlabel("t / lambda")
            ax.set_ylabel("centreline velocity / steady value")
            ax.set_title(f"Oldroyd-B start-up, E = {E:g}, beta = {beta:g}")
            ax.grid(alpha=0.3)
            ax.legend()
            fig.tight_layout()
            fig.savefig(a.png, dpi=110)
            print(f"wrote {a.png}")
    print("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
