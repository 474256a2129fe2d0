#!/usr/bin/python3
"""Work-precision study: accuracy against cost for the vesph integrators.

Usage
-----
    /usr/bin/python3 tools/study_work_precision.py [--out DIR] [--quick] [--t-end T]
        [--ny N] [--steps DT ...] [--rtols R ...] [--ref-step DT] [--threads N]
        [--vesph BIN] [--scene FILE] [--keep-runs DIR]

The transient plane-Poiseuille case (cases/poiseuille_newtonian.toml, H/40 by default) is
run to t_end (default 0.1125 s, one frame there) with
  * leapfrog, midpoint and arkode-fixed DORMAND_PRINCE_7_4_5 at fixed steps
    integrator.step = 2e-4 (the viscous stability limit 0.125 h^2/nu of this case),
    1e-4, 5e-5, 2.5e-5 s;
  * arkode (adaptive) with DORMAND_PRINCE_7_4_5 and BOGACKI_SHAMPINE_4_2_3 at
    rtol = 1e-2 ... 1e-8 (default absolute tolerances: rtol times dx, rho0 delta, V).
For every run it measures
  (a) err_analytic: max over fluid particles |vx - v(y, t_end)| / (F H^2/(8 nu)),
      v the analytic start-up solution (tools/poiseuille_check.py);
  (b) err_temporal: max over fluid particles, matched by id, of |vx - vx_ref| / (F H^2/(8 nu))
      against a reference at the same resolution: arkode-fixed DORMAND_PRINCE_7_4_5 at
      step --ref-step (default 1.25e-5 s).  A 5th-order reference at a step 2x below the
      smallest tested step has a temporal error ~2^5 = 32x below that of DP5 at 2.5e-5 s
      and many orders below the 2nd-order methods; a leapfrog reference at step/16 would
      be only 256x better than leapfrog at 2e-4 s and could not resolve the errors of the
      5th-order runs.  The script prints an estimate of the reference's own error,
      err_temporal(DP5 at 2 x ref-step) / 31.
against wall time (summary.json wall_seconds) and rhs evaluations (rhs_evals).  For the
ARKODE runs it reports the fraction of accepted steps that were as long as the stability
limit (at_limit; steps equal to min(cfl h/(c+vmax), 0.125 h^2/nu) within 0.1 %), the median
step / limit, and "control" (vesph.studies.common.step_control): "limit" (the stability limit sets
the step), "held" (the step is constant just below the limit: ARKODE's default fixed-step
bounds [1, 1.5] do not grow a step by less than 1.5x; vesph sets them to [1, 1] since commit
ac193f7, so this should no longer occur) or "error" (the error estimate sets the step).

Writes DIR/work_precision.csv, DIR/work_precision.png (2x2 log-log panels: both errors
against wall time and against rhs evaluations, one series per integrator/table; ARKODE
points at the stability limit drawn hollow) and DIR/commands.txt; prints the table.
--quick: t_end = 0.0225 s, steps 2e-4, 1e-4, 5e-5, rtol 1e-2, 1e-4, 1e-6, 1e-8, reference
at 2.5e-5 s (about a minute).

Exit status: 0 when every run finished or was recorded as unstable (vesph exit 3);
1 when a run failed otherwise (or the reference did not finish); 2 for usage errors.
"""

import argparse
import math
import sys

from vesph.studies import common as sc

STUDY = "work_precision"
COLUMNS = [("series", "series", "s"), ("integrator", "integrator", "s"), ("table", "table", "s"),
           ("step", "step [s]", ".3g"), ("rtol", "rtol", ".0e"), ("status", "status", "s"),
           ("steps", "steps", "d"), ("rejected", "rejected", "d"), ("rhs_evals", "rhs evals", "d"),
           ("wall_s", "wall [s]", ".2f"), ("mean_dt", "mean dt [s]", ".3g"),
           ("at_limit", "at limit", ".2f"), ("dt_over_limit", "dt/limit", ".3f"),
           ("control", "control", "s"), ("err_analytic", "err analytic", ".3e"),
           ("err_temporal", "err temporal", ".3e")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sc.common_arguments(ap, STUDY)
    ap.add_argument("--t-end", type=float, help="end time, s (default 0.1125; --quick 0.0225)")
    ap.add_argument("--ny", type=int, default=40, help="particles across H (default 40)")
    ap.add_argument("--steps", type=float, nargs="+", help="fixed steps, s")
    ap.add_argument("--rtols", type=float, nargs="+", help="ARKODE relative tolerances")
    ap.add_argument("--ref-step", type=float, help="step of the reference run, s")
    ap.add_argument("--tables", nargs="+",
                    default=["DORMAND_PRINCE_7_4_5", "BOGACKI_SHAMPINE_4_2_3"],
                    help="tables for the adaptive arkode runs")
    ap.add_argument("--fixed-tables", nargs="+", default=["DORMAND_PRINCE_7_4_5"],
                    help="tables for the arkode-fixed runs")
    a = ap.parse_args(argv)
    if a.quick:
        t_end = a.t_end or 0.0225
        steps = a.steps or [2e-4, 1e-4, 5e-5]
        rtols = a.rtols or [1e-2, 1e-4, 1e-6, 1e-8]
        ref_step = a.ref_step or 2.5e-5
    else:
        t_end = a.t_end or 0.1125
        steps = a.steps or [2e-4, 1e-4, 5e-5, 2.5e-5]
        rtols = a.rtols or [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
        ref_step = a.ref_step or 1.25e-5

    runner = sc.Runner(a, STUDY)
    geo = sc.geometry(a.ny)
    h = sc.SMOOTHING_RATIO * sc.H / a.ny
    lim = sc.step_limits(h, sc.rule_sound_speed(0.01), vesph=a.vesph)
    print(f"# work-precision: H/{a.ny}, t_end = {t_end} s, stability limit of the fixed-step "
          f"integrators {lim['smallest']:.3g} s ({lim['controls']}); "
          f"OMP_NUM_THREADS={a.threads}", file=sys.stderr)

    ref = runner.run(f"reference arkode-fixed DP5 step={ref_step:g}",
                     geo + sc.integrator_sets("arkode-fixed", "DORMAND_PRINCE_7_4_5", ref_step), t_end)
    if not ref.ok:
        print("the reference run did not finish", file=sys.stderr)
        runner.finish()
        return 1

    plan = []
    for kind in ("leapfrog", "midpoint"):
        for dt in steps:
            plan.append((kind, None, dt, None))
    for table in a.fixed_tables:
        for dt in steps:
            plan.append(("arkode-fixed", table, dt, None))
    for table in a.tables:
        for rtol in rtols:
            plan.append(("arkode", table, None, rtol))

    rows, runs = [], []
    for kind, table, dt, rtol in plan:
        series = sc.integrator_label(kind, table)
        label = series + (f" step={dt:g}" if dt else f" rtol={rtol:g}")
        run = runner.run(label, geo + sc.integrator_sets(kind, table, dt, rtol), t_end)
        runs.append(run)
        row = {"series": series, "integrator": kind, "table": table or "", "step": dt,
               "rtol": rtol, "status": run.status, "steps": run.steps,
               "rejected": run.rejected, "rhs_evals": run.rhs_evals, "wall_s": run.wall,
               "mean_dt": t_end / run.steps if run.ok and run.steps > 0 else math.nan,
               "at_limit": math.nan, "dt_over_limit": math.nan, "control": "",
               "err_analytic": math.nan, "err_temporal": math.nan}
        if run.ok:
            row["err_analytic"] = sc.analytic_error(run, t_end)
            row["err_temporal"] = sc.temporal_error(run, ref, t_end)
            if kind == "arkode":
                row["at_limit"], row["dt_over_limit"], row["control"] = sc.step_control(run, vesph=a.vesph)
        rows.append(row)

    ref_row = {"series": "reference", "integrator": "arkode-fixed",
               "table": "DORMAND_PRINCE_7_4_5", "step": ref_step, "status": ref.status,
               "steps": ref.steps, "rejected": ref.rejected, "rhs_evals": ref.rhs_evals,
               "wall_s": ref.wall, "mean_dt": t_end / ref.steps,
               "err_analytic": sc.analytic_error(ref, t_end), "err_temporal": 0.0}
    rows.append(ref_row)

    out = runner.out
    sc.write_csv(out / "work_precision.csv", rows, COLUMNS)
    print(f"work-precision study: Poiseuille start-up, H/{a.ny} (dx = {sc.H / a.ny:g} m, "
          f"h = {h:g} m), t_end = {t_end} s, OMP_NUM_THREADS = {a.threads}")
    print(f"stability limits (v = 0): acoustic {lim['acoustic']:.3g} s, viscous "
          f"{lim['viscous']:.3g} s, force {lim['force']:.3g} s -> {lim['controls']} controls")
    print(f"errors relative to F H^2/(8 nu) = {sc.U_CENTRE:g} m/s; temporal error against "
          f"arkode-fixed DORMAND_PRINCE_7_4_5 at step {ref_step:g} s")
    print("ARKODE step control: at limit = fraction of steps equal to the stability limit, "
          "dt/limit = median step / limit;\n  control: 'limit' = the stability limit sets the "
          "step; 'held' = one constant step between limit/1.5 and the limit (ARKODE's\n"
          "  default fixed-step bounds [1, 1.5]; vesph sets [1, 1], so not expected); "
          "'error' = the error estimate sets the step\n")
    sc.print_table(rows, COLUMNS)

    # reference quality: DP5 fixed at 2 x ref_step against the reference
    check = [r for r in rows if r["series"] == "arkode-fixed DP5" and r["step"]
             and abs(r["step"] - 2 * ref_step) <= 1e-9 * ref_step]
    if check and math.isfinite(check[0]["err_temporal"]):
        e2 = check[0]["err_temporal"]
        print(f"\nreference check: err_temporal(DP5 at {2 * ref_step:g} s) = {e2:.2e}, so the "
              f"reference's own temporal error is about {e2 / 31:.1e} if DP5 is in its "
              f"asymptotic range; values of 1e-14 or below are round-off, i.e. the reference is "
              f"then exact to round-off")
    ark = [r for r in rows if r["integrator"] == "arkode" and r["status"] == "ok"]
    if ark:
        print("\nARKODE step control:")
        for r in ark:
            print(f"  {r['series']} rtol={r['rtol']:g}: {r['control']:<5s} "
                  f"({100 * r['at_limit']:.0f} % of steps at the limit, median step "
                  f"{r['dt_over_limit']:.3f} x limit)")
    unstable = [r for r in rows if r["status"] == "unstable"]
    for r in unstable:
        print(f"unstable: {r['series']} step={r['step']} rtol={r['rtol']}")

    sc.safe_plot(plot, out / "work_precision.png", rows, t_end, a.ny, ref_step)
    print(f"\nwrote {out / 'work_precision.csv'}, {out / 'work_precision.png'}, "
          f"{out / 'commands.txt'}")
    return runner.finish()


def plot(path, rows, t_end, ny, ref_step):
    plt = sc.pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(8.0, 6.4), sharey="row")
    series = [s for s in dict.fromkeys(r["series"] for r in rows) if s != "reference"]
    markers = "osD^v<>"
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, s in enumerate(series):
        rs = [r for r in rows if r["series"] == s and r["status"] == "ok"]
        if not rs:
            continue
        for i, ykey in enumerate(("err_analytic", "err_temporal")):
            for j, xkey in enumerate(("wall_s", "rhs_evals")):
                ax = axes[i, j]
                xs = [r[xkey] for r in rs]
                ys = sc.positive([r[ykey] for r in rs])
                ax.plot(xs, ys, "-", color=colors[k % len(colors)], lw=0.8)
                for r, x, y in zip(rs, xs, ys):
                    hollow = r["integrator"] == "arkode" and r["control"] in ("limit", "held")
                    ax.plot([x], [y], markers[k % len(markers)], color=colors[k % len(colors)],
                            mfc="none" if hollow else colors[k % len(colors)],
                            label=s if r is rs[0] else None)
    for i, name in enumerate(("error vs analytic", "temporal error vs reference")):
        for j, xname in enumerate(("wall time [s]", "rhs evaluations")):
            ax = axes[i, j]
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.25)
            ax.set_xlabel(xname)
            if j == 0:
                ax.set_ylabel(f"{name}\n/ (F H²/8ν)")
    for i, ykey in enumerate(("err_analytic", "err_temporal")):
        ys = [r[ykey] for r in rows if r["status"] == "ok" and r["series"] != "reference"
              and r[ykey] > 0]
        if ys:   # at least two decades, so that a flat series does not fill the panel
            lo, hi = min(ys), max(ys)
            mid = math.sqrt(lo * hi)
            axes[i, 0].set_ylim(min(lo / 1.5, mid / 10), max(hi * 1.5, mid * 10))
    axes[0, 0].legend(loc="best")
    for j in range(2):
        axes[1, j].axhspan(1e-17, 1e-13, color="grey", alpha=0.12, lw=0)
    axes[1, 0].text(0.45, 0.92, "grey: below 1e-13, near round-off", transform=axes[1, 0].transAxes,
                    fontsize=7)
    fig.suptitle(f"Work-precision, Poiseuille H/{ny}, t = {t_end:g} s; reference: arkode-fixed DP5, "
                 f"dt = {ref_step:g} s\nhollow: ARKODE step set by the stability limit "
                 f"(at it, or held just below it), not by the error estimate", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
