"""Check a vesph Hagen-Poiseuille start-up in a pipe (3D; Newtonian or Oldroyd-B) against the
analytic Bessel-series solution (docs/validation.md §17).

Usage
-----
    tools/vesph-post pipe_check H5FILE [--times T ...] [--tolerance TOL]
        [--stress-tolerance 0.03] [--interior 0.2] [--no-stresses] [--criterion profile|centreline]
        [--png OUT.png] [--csv OUT.csv]

The pipe comes from the resolved scene stored in the file: the fluid block of shape
"cylinder" (centre, diameter = 2R, axis), the body force g = effects.body_force.acceleration
projected on the axis, rho = fluid.density, eta_s = fluid.viscosity and, when the scene has
[effects.oldroyd_b], eta_p = polymer_viscosity and lambda = relaxation_time (a Newtonian scene:
eta_p = 0). With eta0 = eta_s + eta_p, nu0 = eta0/rho, the steady centreline velocity is
u_c = g R^2/(4 nu0), and the reference (vesph.analytic):

    Newtonian   u = u_c [(1 - r^2/R^2) - sum_k c_k J0(j_k r/R) exp(-nu j_k^2 t/R^2)]
    Oldroyd-B   u = u_c [(1 - r^2/R^2) - sum_k c_k J0(j_k r/R) A_k(t/lambda)]   (Waters & King)

(j_k the zeros of J0, c_k = 8/(j_k^3 J1(j_k)), A_k the retarded mode of startup_mode).

Checks (exit 0 when all pass, 1 otherwise):
1. velocity: at each checked frame the fluid particles are binned by their distance r from the
   axis (bins one particle spacing wide); in each bin the mean axial velocity against the mean
   of the analytic velocity at the same particles; the largest difference over the bins,
   divided by u_c, below --tolerance (default 2 % for a Newtonian scene, 3 % for Oldroyd-B).
   The largest single-particle difference is printed too (not asserted). With --criterion
   centreline only the innermost bin's error is asserted (the plane channel's criterion of
   docs/validation.md §6, the centreline velocity history); the profile's is still printed.
2. Oldroyd-B only, unless --no-stresses: at the last frame (which must be steady: the analytic
   transient there below 0.1 % of u_c) the steady stresses over the bins inside
   r <= (1 - --interior) R: the total shear stress T_rz = -rho g r/2, the polymer part
   tau_rz = eta_p/eta0 T_rz (the simulated one: T_rz minus the solvent part eta_s du/dr, du/dr
   from the least-squares fit u = u0 + u2 r^2 of the frame's fluid velocities) and
   N1 = T_zz - T_rr = 2 lambda eta_p (du/dr)^2 (z the axis, r outwards: the frame's
   extra_stress turned into the particle's axial/radial frame), each bin's mean against the
   analytic mean over the same particles, the largest difference divided by the component's
   analytic value at the wall r = R, below --stress-tolerance (default 3 %).
"""
import argparse
import sys

import numpy as np

from vesph.analytic import pipe_oldroyd_b_startup, pipe_steady_stresses
from vesph.output import Output, ToolError, run_reporting_errors

STEADY_LIMIT = 1e-3   # the analytic transient at the stress frame, fraction of u_c


class PipeOutput(Output):
    def _check_scene(self):
        if self.dim != 3:
            raise ToolError(f"{self.path}: a {self.dim}D run; the pipe check is for 3D pipes")


def pipe_parameters(scene):
    """dict of the pipe and the fluid: R, centre, axis (unit vector), g (along the axis), rho,
    eta_s, eta_p, lam (0 for a Newtonian fluid). Raises ToolError for a scene without a
    cylindrical fluid block."""
    blocks = [b for b in scene.get("blocks", []) if b.get("kind") == "fluid"]
    cyl = [b for b in blocks if b.get("shape") == "cylinder"]
    if len(cyl) != 1 or len(blocks) != 1:
        raise ToolError("the scene must have one fluid block, of shape \"cylinder\" (the pipe)")
    b = cyl[0]
    try:
        R = 0.5 * float(b["diameter"])
        centre = np.array(b["centre"], dtype=float)
        axis = np.array(b.get("axis", [0.0, 0.0, 1.0]), dtype=float)
        rho = float(scene["fluid"]["density"])
        eta_s = float(scene["fluid"]["viscosity"])
        acc = np.array(scene["effects"]["body_force"]["acceleration"], dtype=float)
    except (KeyError, TypeError, ValueError) as e:
        raise ToolError(f"the scene lacks a pipe parameter ({e}): fluid cylinder centre, "
                        "diameter, axis; fluid.density, fluid.viscosity; effects.body_force")
    axis = axis / np.linalg.norm(axis)
    g = float(acc @ axis)
    if np.linalg.norm(acc - g * axis) > 1e-12 * max(abs(g), 1e-300):
        raise ToolError("the body force is not along the pipe's axis")
    model = scene["effects"].get("oldroyd_b")
    if scene["effects"].get("ucm") is not None or scene["effects"].get("xpp") is not None:
        raise ToolError("the pipe check knows the Newtonian and Oldroyd-B fluids only")
    eta_p = float(model["polymer_viscosity"]) if model else 0.0
    lam = float(model["relaxation_time"]) if model else 0.0
    return {"R": R, "centre": centre, "axis": axis, "g": g, "rho": rho, "eta_s": eta_s,
            "eta_p": eta_p, "lam": lam}


def radial_frame(pos, P):
    """(r, e_r) of positions pos [N,3]: the distance from the axis and the unit radial vector
    (along the first transverse direction on the axis itself)."""
    d = pos - P["centre"]
    perp = d - np.outer(d @ P["axis"], P["axis"])
    r = np.linalg.norm(perp, axis=1)
    er = np.zeros_like(perp)
    on = r > 0
    er[on] = perp[on] / r[on, None]
    if not np.all(on):
        t = np.cross(P["axis"], [1.0, 0.0, 0.0])
        if np.linalg.norm(t) < 0.5:
            t = np.cross(P["axis"], [0.0, 1.0, 0.0])
        er[~on] = t / np.linalg.norm(t)
    return r, er


def tensor(stress):
    """[N,3,3] symmetric tensors from vesph's 3D extra_stress components (xx xy xz yy yz zz)."""
    xx, xy, xz, yy, yz, zz = stress.T
    return np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1),
                     np.stack([xz, yz, zz], -1)], -2)


def bin_means(r, values, width, rmax):
    """Bins [k w, (k+1) w) up to rmax: (index of the bins holding particles, mean r, the mean
    of each row of values [m, N] per bin)."""
    idx = np.minimum((r / width).astype(int), int(np.ceil(rmax / width)) - 1)
    used = np.unique(idx)
    count = np.bincount(idx)[used]
    mean_r = np.bincount(idx, weights=r)[used] / count
    means = [np.bincount(idx, weights=v)[used] / count for v in values]
    return used, mean_r, means


RADIAL_GRID = 1001    # the series is evaluated at this many radii and interpolated (linear:
                      # below 1e-5 of u_c even in the wall layer of t = 0.005 R^2/nu)


def analytic(r, t, P):
    """The analytic axial velocity at radii r (the series on RADIAL_GRID radii, interpolated:
    a frame has tens of thousands of particles, the series thousands of modes)."""
    grid = np.linspace(0.0, P["R"], RADIAL_GRID)
    u = pipe_oldroyd_b_startup(grid, t, P["g"], P["rho"], P["eta_s"], P["eta_p"], P["lam"], P["R"])
    return np.interp(r, grid, u) if np.ndim(r) else float(np.interp(r, grid, u))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("h5file")
    ap.add_argument("--times", type=float, nargs="+", metavar="T",
                    help="times [s] to check (the closest frame within 1e-6 relative); default "
                         "every frame with t > 0")
    ap.add_argument("--tolerance", type=float,
                    help="binned velocity error, fraction of u_c (default 0.02 Newtonian, 0.03 Oldroyd-B)")
    ap.add_argument("--stress-tolerance", type=float, default=0.03)
    ap.add_argument("--interior", type=float, default=0.2,
                    help="the stresses are compared at r <= (1 - INTERIOR) R (default 0.2)")
    ap.add_argument("--no-stresses", action="store_true", help="skip the steady-stress check")
    ap.add_argument("--criterion", choices=("profile", "centreline"), default="profile",
                    help="velocity acceptance: every bin (profile, default) or the innermost bin's "
                         "history alone (centreline: the plane channel's criterion, validation.md §6)")
    ap.add_argument("--png")
    ap.add_argument("--csv")
    a = ap.parse_args(argv)
    return run_reporting_errors("pipe_check", check, a)


def select(out, times):
    if not times:
        return [k for k, (_, t) in enumerate(out.frames) if t > 0]
    chosen = []
    for T in times:
        k = int(np.argmin(np.abs(out.times - T)))
        if abs(out.times[k] - T) > 1e-6 * max(abs(T), 1e-300):
            raise ToolError(f"no frame at t = {T:g} s (closest {out.times[k]:g} s)")
        chosen.append(k)
    return sorted(set(chosen))


def check(a):
    with PipeOutput(a.h5file) as out:
        P = pipe_parameters(out.scene)
        R, dx = P["R"], out.dx
        eta0 = P["eta_s"] + P["eta_p"]
        viscoelastic = P["eta_p"] > 0 and P["lam"] > 0
        tol = a.tolerance if a.tolerance is not None else (0.03 if viscoelastic else 0.02)
        uc = P["g"] * R * R * P["rho"] / (4.0 * eta0)
        print(f"pipe R = {R:g} m ({2 * R / dx:g} spacings across), g = {P['g']:g} m/s^2, "
              f"nu0 = {eta0 / P['rho']:g} m^2/s, steady centreline velocity u_c = {uc:.5g} m/s")
        if viscoelastic:
            E = P["lam"] * eta0 / (P["rho"] * R * R)
            print(f"Oldroyd-B: lambda = {P['lam']:g} s, beta = eta_s/eta0 = {P['eta_s'] / eta0:g}, "
                  f"E = lambda nu0/R^2 = {E:g}")
        rows, profiles = [], []
        frames = select(out, a.times)
        if not frames:
            raise ToolError("no frame with t > 0 to check")
        last = None
        for k in frames:
            t = out.frames[k][1]
            g = out.read(k, ("kind", "position", "velocity"))
            fl = g["kind"] == 0
            pos = g["position"][fl]
            r, er = radial_frame(pos, P)
            u = g["velocity"][fl] @ P["axis"]
            exact = analytic(r, t, P)
            used, mr, (us, ue) = bin_means(r, (u, exact), dx, R)
            err_bins = np.abs(us - ue) / uc
            err_max = float(np.max(np.abs(u - exact))) / uc
            centre = (float(us[0]), float(ue[0]))
            rows.append((t, float(err_bins.max()), float(mr[np.argmax(err_bins)]) / R, err_max,
                         centre[0] / uc, centre[1] / uc, float(err_bins[0])))
            profiles.append((t, mr, us, ue))
            last = (k, t, fl, pos, r, er, u)
        print(f"{'t [s]':>9} {'binned err %':>12} {'at r/R':>7} {'particle err %':>14} "
              f"{'u_axis/u_c sim':>14} {'analytic':>9} {'axis err %':>10}")
        for row in rows:
            print(f"{row[0]:9.4g} {100 * row[1]:12.3f} {row[2]:7.3f} {100 * row[3]:14.3f} "
                  f"{row[4]:14.4f} {row[5]:9.4f} {100 * row[6]:10.3f}")
        ok = True
        column, what = (1, "binned velocity error") if a.criterion == "profile" else (6, "centreline (innermost bin) error")
        bad = [row for row in rows if not row[column] < tol]
        if bad:
            worst = max(bad, key=lambda row: row[column])
            print(f"FAIL: {what} above {100 * tol:g} % at {len(bad)} frame(s), worst "
                  f"{100 * worst[column]:.3f} % at t = {worst[0]:g} s")
            ok = False
        else:
            print(f"{what} below {100 * tol:g} % at every frame (worst {100 * max(row[column] for row in rows):.3f} %)")
        stress = None
        if viscoelastic and not a.no_stresses:
            stress, stress_ok = steady_stress_check(out, P, last, a)
            ok = ok and stress_ok
        if a.csv:
            with open(a.csv, "w") as fh:
                fh.write("time_s,binned_error,worst_bin_r_over_R,particle_error,axis_sim,axis_exact,axis_error\n")
                for row in rows:
                    fh.write(",".join(f"{v:.10g}" for v in row) + "\n")
            print(f"wrote {a.csv}")
        if a.png:
            plot(a.png, P, uc, rows, profiles, stress, out.name)
            print(f"wrote {a.png}")
    print("RESULT: " + ("PASS" if ok else "FAIL"))
    return 0 if ok else 1


def steady_stress_check(out, P, last, a):
    """The steady stresses at the last checked frame (docstring, check 2): (data for the plot,
    passed)."""
    k, t, fl, pos, r, er, u = last
    R = P["R"]
    probe = np.linspace(0.0, R, 41)
    steady = P["g"] * P["rho"] / (4.0 * (P["eta_s"] + P["eta_p"])) * (R * R - probe * probe)
    transient = float(np.max(np.abs(analytic(probe, t, P) - steady)))
    uc = P["g"] * R * R * P["rho"] / (4.0 * (P["eta_s"] + P["eta_p"]))
    if not transient < STEADY_LIMIT * uc:
        print(f"FAIL: the last frame (t = {t:g} s) is not steady: the analytic transient there is "
              f"{100 * transient / uc:.3f} % of u_c (limit {100 * STEADY_LIMIT:g} %)")
        return None, False
    if not out.has(k, "extra_stress"):
        print("FAIL: the frames have no extra_stress")
        return None, False
    T = tensor(out.read(k, ("extra_stress",))["extra_stress"][fl])
    ax = P["axis"]
    T_ar = np.einsum("i,nij,nj->n", ax, T, er)
    T_aa = np.einsum("i,nij,j->n", ax, T, ax)
    T_rr = np.einsum("ni,nij,nj->n", er, T, er)
    # the solvent part eta_s du/dr from the fitted profile u = u0 + u2 r^2
    u2 = np.linalg.lstsq(np.stack([np.ones_like(r), r * r], 1), u, rcond=None)[0][1]
    tau_ar = T_ar - P["eta_s"] * 2.0 * u2 * r
    ref = pipe_steady_stresses(r, P["g"], P["rho"], P["eta_s"], P["eta_p"], P["lam"])
    wall = pipe_steady_stresses(R, P["g"], P["rho"], P["eta_s"], P["eta_p"], P["lam"])
    inner = r <= (1.0 - a.interior) * R
    used, mr, means = bin_means(r[inner], (T_ar[inner], ref["T_rz"][inner], tau_ar[inner],
                                           ref["tau_rz"][inner], T_aa[inner] - T_rr[inner],
                                           ref["N1"][inner]), out.dx, R)
    print(f"steady stresses at t = {t:g} s over {int(inner.sum())} particles at r <= "
          f"{1 - a.interior:g} R (bins of one spacing; errors of the wall values; fitted "
          f"u = u0 + u2 r^2: u2 = {u2:.5g} 1/(m s), analytic {-P['g'] * P['rho'] / (4 * (P['eta_s'] + P['eta_p'])):.5g})")
    ok = True
    result = {"r": mr}
    for name, sim, exact, scale in (("T_rz (total)", means[0], means[1], abs(float(wall["T_rz"]))),
                                    ("tau_rz (polymer)", means[2], means[3], abs(float(wall["tau_rz"]))),
                                    ("N1", means[4], means[5], float(wall["N1"]))):
        err = float(np.max(np.abs(sim - exact))) / scale
        print(f"  {name:17s} error {100 * err:7.3f} % of {scale:.4g} Pa")
        result[name] = (sim / scale, exact / scale, err)
        if not err < a.stress_tolerance:
            print(f"FAIL: {name} error {100 * err:.3f} % >= {100 * a.stress_tolerance:g} %")
            ok = False
    return result, ok


def plot(png, P, uc, rows, profiles, stress, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    R = P["R"]
    n = 3 if stress else 2
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 4.2))
    rr = np.linspace(0.0, R, 101)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    shown = profiles if len(profiles) <= 6 else [profiles[i] for i in
                                                 np.unique(np.geomspace(1, len(profiles), 6).astype(int) - 1)]
    for i, (t, mr, us, ue) in enumerate(shown):
        c = colors[i % len(colors)]
        axes[0].plot(rr / R, analytic(rr, t, P) / uc, "-", color=c, label=f"t = {t:.4g} s")
        axes[0].plot(mr / R, us / uc, "o", ms=3, color=c)
    axes[0].plot([], [], "ko", ms=3, label="vesph (bin means)")
    axes[0].set_xlabel("r / R")
    axes[0].set_ylabel("u / u_c")
    axes[0].legend(fontsize="small")
    ts = np.array([row[0] for row in rows])
    tt = np.linspace(0.0, ts.max(), 300)
    axes[1].plot(tt, [pipe_oldroyd_b_startup(0.0, x, P["g"], P["rho"], P["eta_s"], P["eta_p"], P["lam"], R) / uc
                      for x in tt], "k-", label="analytic, r = 0")
    axes[1].plot(ts, [row[4] for row in rows], "o", ms=3, label="vesph, innermost bin")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("u / u_c")
    twin = axes[1].twinx()
    twin.plot(ts, [100 * row[1] for row in rows], "rs", ms=3, label="binned error (right axis)")
    twin.set_ylabel("binned error, % of u_c", color="r")
    twin.set_ylim(0.0, max(3.5, 110 * max(row[1] for row in rows)))
    handles = axes[1].get_legend_handles_labels()
    extra = twin.get_legend_handles_labels()
    axes[1].legend(handles[0] + extra[0], handles[1] + extra[1], fontsize="small", loc="center right")
    if stress:
        ax = axes[2]
        mr = stress["r"] / R
        for (name, (sim, exact, _)), c in zip([(k, v) for k, v in stress.items() if k != "r"], colors):
            ax.plot(mr, exact, "-", color=c, label=f"{name} analytic")
            ax.plot(mr, sim, "o", ms=3, color=c, label=f"{name} vesph")
        ax.set_xlabel("r / R")
        ax.set_ylabel("stress / its steady value at the wall")
        ax.legend(fontsize="x-small")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"Hagen-Poiseuille start-up: {title}")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
