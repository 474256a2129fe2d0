#!/usr/bin/python3
"""Convergence study: observed spatial and temporal orders on the Poiseuille start-up.

Usage
-----
    /usr/bin/python3 tools/study_convergence.py [--out DIR] [--quick] [--ny N ...]
        [--t-end T] [--temporal-ny N] [--t-temporal T] [--dt0 DT] [--ref-factor K]
        [--threads N] [--vesph BIN] [--scene FILE] [--keep-runs DIR]

(a) Spatial: dx = H/10, H/20, H/40, H/80 (--ny 10 20 40 80; --quick 10 20 40) at fixed
    h/dx = 1.6 (quintic kernel), periodic length 20 dx, walls 5 dx, leapfrog with the step
    from the stability limits, sound speed of the case (delta = 0.01).  Error vs analytic at
    t_end (default 0.1125 s): err_max = max over fluid particles |vx - v(y,t)| / (F H^2/(8 nu))
    and err_rms (root mean square of the same); observed order log2(e(2 dx)/e(dx)).
    The error contains the spatial SPH error, the weak-compressibility error (delta fixed)
    and the leapfrog's temporal error (small, see the temporal part): it converges only
    while the spatial error dominates.
(b) Temporal: dx = H/20 (--temporal-ny), every fixed-step integrator (leapfrog, midpoint,
    arkode-fixed HEUN_EULER_2_1_2, BOGACKI_SHAMPINE_4_2_3, ZONNEVELD_5_3_4,
    DORMAND_PRINCE_7_4_5) with integrator.step = dt0, dt0/2, dt0/4 (dt0 = 1e-4 s, below the
    limits at H/20: viscous 8e-4 s, acoustic 1.1e-3 s), frames at t = 0.0225 s (--t-temporal;
    a multiple of every step; the flow is still developing there).  Errors, max over fluid
    particles matched by id of |vx - vx_ref| / (F H^2/(8 nu)):
      err_self   against the same integrator at dt0/32 (--ref-factor),
      err_dp5    against arkode-fixed DORMAND_PRINCE_7_4_5 at dt0/32 (a common reference;
                 for DP5 itself the two are the same).
    Observed orders log2(e(dt)/e(dt/2)).  Errors below 1e-13 are near round-off (the
    velocities are ~1e-6...1e-5 m/s and the positions ~1e-3 m, so a relative round-off of
    1e-16 per operation accumulates to ~1e-15...1e-14 of F H^2/(8 nu)); orders computed from
    such errors are flagged "round-off" and are not reliable.

Writes DIR/convergence_spatial.csv, DIR/convergence_temporal.csv, DIR/convergence.png
(error against dx and against dt, log-log, with slope guides) and DIR/commands.txt; prints
both tables.  --quick: ny 10 20 40 and t = 0.0045 s for the temporal part.

Exit status: 0 when every run finished or was recorded as unstable (vesph exit 3); 1 when a
run failed otherwise; 2 for usage errors.
"""

import argparse
import math
import sys

import numpy as np

from vesph.studies import common as sc

STUDY = "convergence"
ROUNDOFF = 1e-13
SPATIAL_COLUMNS = [("ny", "H/dx", "d"), ("dx", "dx [m]", ".4g"), ("h", "h [m]", ".4g"),
                   ("n_fluid", "N fluid", "d"), ("status", "status", "s"), ("steps", "steps", "d"),
                   ("mean_dt", "mean dt [s]", ".3g"), ("limit", "limit", "s"),
                   ("wall_s", "wall [s]", ".2f"), ("max_density_deviation", "max |drho|/rho0", ".2e"),
                   ("err_max", "err max", ".4e"), ("order_max", "order (max)", ".2f"),
                   ("err_rms", "err rms", ".4e"), ("order_rms", "order (rms)", ".2f")]
TEMPORAL_COLUMNS = [("series", "integrator", "s"), ("nominal_order", "order", "d"),
                    ("dt", "step [s]", ".4g"), ("status", "status", "s"), ("steps", "steps", "d"),
                    ("rhs_evals", "rhs evals", "d"), ("wall_s", "wall [s]", ".2f"),
                    ("err_self", "err vs own ref", ".3e"), ("order_self", "order", ".2f"),
                    ("err_dp5", "err vs DP5 ref", ".3e"), ("order_dp5", "order", ".2f"),
                    ("err_analytic", "err analytic", ".4e"), ("note", "note", "s")]
TEMPORAL_INTEGRATORS = [("leapfrog", None, 2), ("midpoint", None, 2),
                        ("arkode-fixed", "HEUN_EULER_2_1_2", 2),
                        ("arkode-fixed", "BOGACKI_SHAMPINE_4_2_3", 3),
                        ("arkode-fixed", "ZONNEVELD_5_3_4", 4),
                        ("arkode-fixed", "DORMAND_PRINCE_7_4_5", 5)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sc.common_arguments(ap, STUDY)
    ap.add_argument("--ny", type=int, nargs="+", help="particles across H, spatial part")
    ap.add_argument("--t-end", type=float, default=0.1125, help="spatial part: time, s")
    ap.add_argument("--temporal-ny", type=int, default=20, help="temporal part: H/dx (default 20)")
    ap.add_argument("--t-temporal", type=float, help="temporal part: time, s (default 0.0225)")
    ap.add_argument("--dt0", type=float, default=1e-4, help="temporal part: largest step, s")
    ap.add_argument("--ref-factor", type=int, default=32,
                    help="temporal part: the reference step is dt0/ref-factor (default 32)")
    ap.add_argument("--skip-spatial", action="store_true")
    ap.add_argument("--skip-temporal", action="store_true")
    a = ap.parse_args(argv)
    nys = a.ny or ([10, 20, 40] if a.quick else [10, 20, 40, 80])
    t_temp = a.t_temporal or (0.0045 if a.quick else 0.0225)
    runner = sc.Runner(a, STUDY)
    out = runner.out
    srows, trows = [], []

    if not a.skip_spatial:
        for ny in sorted(nys):
            run = runner.run(f"spatial leapfrog H/{ny}", sc.geometry(ny), a.t_end)
            h = sc.SMOOTHING_RATIO * sc.H / ny
            lim = sc.step_limits(h, sc.rule_sound_speed(0.01), vesph=a.vesph)
            row = {"ny": ny, "dx": sc.H / ny, "h": h, "n_fluid": 20 * ny, "status": run.status,
                   "steps": run.steps, "limit": lim["controls"],
                   "mean_dt": a.t_end / run.steps if run.ok and run.steps > 0 else math.nan,
                   "wall_s": run.wall, "max_density_deviation": run.density_deviation,
                   "err_max": math.nan, "err_rms": math.nan,
                   "order_max": math.nan, "order_rms": math.nan}
            fr = run.frame_at(a.t_end) if run.ok else None
            if fr is not None:
                U, F, nu, y0, H = sc.velocity_scale(run)
                v = sc.analytic_velocity(fr.y, fr.time, F, nu, H, y0)
                row["err_max"] = float(np.max(np.abs(fr.vx - v))) / U
                row["err_rms"] = float(np.sqrt(np.mean((fr.vx - v) ** 2))) / U
                row["n_fluid"] = len(fr.ids)
            if srows:
                prev = srows[-1]
                ratio = row["ny"] / prev["ny"]
                row["order_max"] = sc.observed_order(prev["err_max"], row["err_max"], ratio)
                row["order_rms"] = sc.observed_order(prev["err_rms"], row["err_rms"], ratio)
            srows.append(row)
        sc.write_csv(out / "convergence_spatial.csv", srows, SPATIAL_COLUMNS)

    if not a.skip_temporal:
        geo = sc.geometry(a.temporal_ny)
        ratio_checks = [t_temp / (a.dt0 / k) for k in (1, 2, 4, a.ref_factor)]
        if any(abs(r - round(r)) > 1e-9 * r for r in ratio_checks):
            print(f"warning: t = {t_temp} s is not a multiple of every step", file=sys.stderr)
        runs = {}
        for kind, table, order in TEMPORAL_INTEGRATORS:
            series = sc.integrator_label(kind, table)
            for k in (a.ref_factor, 1, 2, 4):
                dt = a.dt0 / k
                runs[(series, k)] = runner.run(
                    f"temporal {series} step={dt:g}" + (" (reference)" if k == a.ref_factor else ""),
                    geo + sc.integrator_sets(kind, table, dt), t_temp)
        common = runs.get(("arkode-fixed DP5", a.ref_factor))
        if common is None or not common.ok:
            runner.failures.append("the common DP5 reference did not finish")
        for kind, table, order in TEMPORAL_INTEGRATORS:
            series = sc.integrator_label(kind, table)
            ref = runs[(series, a.ref_factor)]
            prev = None
            for k in (1, 2, 4, a.ref_factor):
                run = runs[(series, k)]
                ok = run.ok and ref.ok
                row = {"series": series, "nominal_order": order, "dt": a.dt0 / k,
                       "status": run.status, "steps": run.steps, "rhs_evals": run.rhs_evals,
                       "wall_s": run.wall,
                       "err_self": sc.temporal_error(run, ref, t_temp)
                       if ok and k != a.ref_factor else math.nan,
                       "err_dp5": sc.temporal_error(run, common, t_temp)
                       if run.ok and common is not None and common.ok and run is not common
                       else math.nan,
                       "err_analytic": sc.analytic_error(run, t_temp) if run.ok else math.nan,
                       "order_self": math.nan, "order_dp5": math.nan, "note": ""}
                if k == a.ref_factor:
                    row["note"] = "reference" + (" (common)" if run is common else "")
                if prev is not None and k != a.ref_factor:
                    row["order_self"] = sc.observed_order(prev["err_self"], row["err_self"])
                    row["order_dp5"] = sc.observed_order(prev["err_dp5"], row["err_dp5"])
                    small = [e for e in (prev["err_self"], row["err_self"], prev["err_dp5"],
                                         row["err_dp5"]) if math.isfinite(e) and e < ROUNDOFF]
                    if small:
                        row["note"] = "round-off"
                elif k == 1 and any(math.isfinite(e) and e < ROUNDOFF
                                    for e in (row["err_self"], row["err_dp5"])):
                    row["note"] = "round-off"
                trows.append(row)
                prev = row
        sc.write_csv(out / "convergence_temporal.csv", trows, TEMPORAL_COLUMNS)

    print(f"convergence study: Poiseuille start-up, OMP_NUM_THREADS = {a.threads}")
    if srows:
        print(f"\n(a) spatial: leapfrog, step from the limits, h = 1.6 dx, delta = 0.01, "
              f"t = {a.t_end} s; errors / (F H^2/(8 nu)); order = log(e_coarse/e_fine)/log(2)\n")
        sc.print_table(srows, SPATIAL_COLUMNS)
    if trows:
        print(f"\n(b) temporal: H/{a.temporal_ny}, t = {t_temp} s, steps dt0 = {a.dt0:g} s, "
              f"dt0/2, dt0/4; references at dt0/{a.ref_factor} = {a.dt0 / a.ref_factor:g} s; "
              f"errors / (F H^2/(8 nu)); 'round-off': an error below {ROUNDOFF:g}\n")
        sc.print_table(trows, TEMPORAL_COLUMNS)
        print("\nobserved temporal order (dt0/2 -> dt0/4, against the own reference):")
        for kind, table, order in TEMPORAL_INTEGRATORS:
            series = sc.integrator_label(kind, table)
            rs = [r for r in trows if r["series"] == series and r["note"] != "reference"
                  and not r["note"].startswith("reference")]
            last = rs[-1] if rs else None
            if last:
                print(f"  {series:<18s} nominal {order}: observed {sc.fmt_value(last['order_self'], '.2f')}"
                      f" (vs DP5 reference {sc.fmt_value(last['order_dp5'], '.2f')})"
                      + ("  [round-off: not meaningful]" if last["note"] == "round-off" else ""))
    sc.safe_plot(plot, out / "convergence.png", srows, trows, a.t_end, t_temp, a.temporal_ny)
    written = [out / n for n in ("convergence_spatial.csv", "convergence_temporal.csv",
                                 "convergence.png", "commands.txt")]
    print("\nwrote " + ", ".join(str(p) for p in written if p.exists()))
    return runner.finish()


def plot(path, srows, trows, t_end, t_temp, tny):
    plt = sc.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(8.6, 3.9))
    ax = axes[0]
    ok = [r for r in srows if r["status"] == "ok"]
    if ok:
        dx = np.array([r["dx"] for r in ok])
        for key, mk, name in (("err_max", "o-", "max"), ("err_rms", "s-", "rms")):
            e = np.array([r[key] for r in ok])
            ax.plot(dx, sc.positive(e), mk, label=f"leapfrog, {name} error", lw=0.9)
        e0 = ok[0]["err_max"]
        for p, ls in ((1, ":"), (2, "--")):
            ax.plot(dx, e0 * (dx / dx[0]) ** p, "k" + ls, lw=0.7, label=f"slope {p}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.invert_xaxis()
        ax.grid(True, which="both", alpha=0.25)
        ax.set_xlabel("dx [m]")
        ax.set_ylabel("error vs analytic / (F H²/8ν)")
        ax.set_title(f"(a) spatial, t = {t_end:g} s")
        ax.legend(loc="best")
    ax = axes[1]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    series = list(dict.fromkeys(r["series"] for r in trows))
    for k, s in enumerate(series):
        rs = [r for r in trows if r["series"] == s and not r["note"].startswith("reference")
              and r["status"] == "ok"]
        if not rs:
            continue
        ax.plot([r["dt"] for r in rs], sc.positive([r["err_self"] for r in rs], 1e-17), "-o",
                color=colors[k % len(colors)], lw=0.9,
                label=f"{s} (order {rs[0]['nominal_order']})")
    if trows:
        ax.axhspan(1e-17, ROUNDOFF, color="grey", alpha=0.12, label=f"below {ROUNDOFF:g} (near round-off)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.25)
        ax.set_xlabel("step [s]")
        ax.set_ylabel("temporal error vs own reference / (F H²/8ν)")
        ax.set_title(f"(b) temporal, H/{tny}, t = {t_temp:g} s")
        ax.legend(loc="best", fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
