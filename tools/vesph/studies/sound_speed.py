#!/usr/bin/python3
"""Sound-speed study: the admissible density variation delta of thesis eq. (3.38).

Usage
-----
    /usr/bin/python3 tools/study_sound_speed.py [--out DIR] [--quick] [--deltas D ...]
        [--t-end T] [--rtol R] [--threads N] [--vesph BIN] [--scene FILE] [--keep-runs DIR]

The H/40 Poiseuille start-up (cases/poiseuille_newtonian.toml) is run to t_end (default
0.1125 s) with the sound speed from eq. (3.38), phi = 4, V = 2.5e-5 m/s, L = 1e-3 m and
delta = 0.1, 0.03, 0.01, 0.003, 0.001, 0.0003, 0.0001; the body-force term dominates, so
c = sqrt(4 F L / delta) = sqrt(8e-7 / delta) m/s (2.83e-3 ... 8.94e-2 m/s).  Integrators:
leapfrog (step from the stability limits) and arkode DORMAND_PRINCE_7_4_5 at rtol 1e-6.
A third series (leave it out with --no-gravity-series) runs the leapfrog with an added
transverse body force g_y = -F = -2e-4 m/s^2 (acceleration [F, -F]; |g| = sqrt(2) F enters
eq. 3.38): the x-flow and its analytic solution are unchanged, but the fluid must now carry
a hydrostatic pressure difference rho0 g H, i.e. a density difference g H / c^2 ~ delta,
which it reaches after about one acoustic transit H/c (column H/c).  In the plain channel no
pressure gradient is needed and the density deviation is whatever the discretisation
produces.

Per run: c, the stability limits (theory.md section 8, v_max = 0; h = 4e-5 m):
acoustic 0.125 h/c, viscous 0.125 h^2/nu = 2e-4 s, and which is smaller; the measured mean
step t_end/steps; for arkode the fraction of steps at the stability limit, the median
step / limit and the step control ("limit", "held" at a constant step just below it, or
"error"; see vesph.studies.common.step_control); max density deviation
max |rho/rho0 - 1| over the run (summary.json) and its ratio to delta; error vs analytic at
t_end (max |vx - v| / (F H^2/(8 nu))); wall time, steps, rhs evaluations.  It fits the
slope of log(density deviation) against log(delta) per integrator (expected 1, since
drho/rho0 ~ dp/(rho0 c^2) ~ 1/c^2 ~ delta).

Writes DIR/sound_speed.csv, DIR/sound_speed.png (density deviation, error, mean step with
the two limits, and wall time, against delta) and DIR/commands.txt; prints the table.
--quick: delta = 0.1, 0.01, 0.001, 0.0003 and t_end = 0.045 s.

Exit status: 0 when every run finished or was recorded as unstable (vesph exit 3); 1 when a
run failed otherwise; 2 for usage errors.
"""

import argparse
import math
import sys

import numpy as np

from vesph import limits
from vesph.studies import common as sc

STUDY = "sound_speed"
COLUMNS = [("series", "integrator", "s"), ("delta", "delta", ".4g"), ("c", "c [m/s]", ".4g"),
           ("transit", "H/c [s]", ".3g"),
           ("acoustic_limit", "acoustic [s]", ".3g"), ("viscous_limit", "viscous [s]", ".3g"),
           ("controls", "limit", "s"), ("status", "status", "s"), ("steps", "steps", "d"),
           ("rhs_evals", "rhs evals", "d"), ("mean_dt", "mean dt [s]", ".3g"),
           ("at_limit", "at limit", ".2f"), ("dt_over_limit", "dt/limit", ".3f"),
           ("control", "control", "s"), ("wall_s", "wall [s]", ".2f"),
           ("max_density_deviation", "max |drho|/rho0", ".3e"),
           ("deviation_over_delta", "dev/delta", ".3e"), ("err_analytic", "err analytic", ".3e")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sc.common_arguments(ap, STUDY)
    ap.add_argument("--deltas", type=float, nargs="+", help="values of delta")
    ap.add_argument("--t-end", type=float, help="end time, s (default 0.1125; --quick 0.045)")
    ap.add_argument("--rtol", type=float, default=1e-6, help="arkode rtol (default 1e-6)")
    ap.add_argument("--ny", type=int, default=40, help="particles across H (default 40)")
    ap.add_argument("--no-gravity-series", action="store_true",
                    help="leave out the leapfrog series with a transverse body force g_y = -F")
    a = ap.parse_args(argv)
    if a.quick:
        deltas = a.deltas or [0.1, 0.01, 0.001, 0.0003]
        t_end = a.t_end or 0.045
    else:
        deltas = a.deltas or [0.1, 0.03, 0.01, 0.003, 0.001, 0.0003, 0.0001]
        t_end = a.t_end or 0.1125

    runner = sc.Runner(a, STUDY)
    geo = sc.geometry(a.ny)
    h = sc.SMOOTHING_RATIO * sc.H / a.ny
    integrators = [("leapfrog", None, None, False), ("arkode", "DORMAND_PRINCE_7_4_5", a.rtol, False)]
    if not a.no_gravity_series:
        integrators.append(("leapfrog", None, None, True))
    rows = []
    for kind, table, rtol, gravity in integrators:
        series = label(kind, table, rtol, gravity)
        g = math.hypot(sc.FORCE, sc.FORCE) if gravity else sc.FORCE
        extra = [f"effects.body_force.acceleration={sc.vec(sc.FORCE, -sc.FORCE)}"] if gravity else []
        for d in deltas:
            c = sc.rule_sound_speed(d, g=g)
            lim = sc.step_limits(h, c, amax=g, vesph=a.vesph)
            run = runner.run(f"{series} delta={d:g}",
                             geo + extra + [sc.sound_speed_rule(d)]
                             + sc.integrator_sets(kind, table, None, rtol), t_end)
            if run.ok and abs(run.sound_speed - c) > 1e-9 * c:
                print(f"warning: vesph's c = {run.sound_speed} differs from eq. 3.38's {c}",
                      file=sys.stderr)
            rows.append({
                "series": series, "delta": d, "c": run.sound_speed if run.summary else c,
                "transit": sc.H / c,
                "acoustic_limit": lim["acoustic"], "viscous_limit": lim["viscous"],
                "controls": lim["controls"], "status": run.status, "steps": run.steps,
                "rhs_evals": run.rhs_evals,
                "mean_dt": t_end / run.steps if run.ok and run.steps > 0 else math.nan,
                "at_limit": math.nan, "dt_over_limit": math.nan, "control": "",
                "wall_s": run.wall, "max_density_deviation": run.density_deviation,
                "deviation_over_delta": run.density_deviation / d,
                "err_analytic": sc.analytic_error(run, t_end) if run.ok else math.nan})
            if run.ok and kind == "arkode":
                rows[-1]["at_limit"], rows[-1]["dt_over_limit"], rows[-1]["control"] = \
                    sc.step_control(run, vesph=a.vesph)

    out = runner.out
    sc.write_csv(out / "sound_speed.csv", rows, COLUMNS)
    print(f"sound-speed study: Poiseuille start-up H/{a.ny} (h = {h:g} m), t_end = {t_end} s, "
          f"OMP_NUM_THREADS = {a.threads}")
    print("c from thesis eq. (3.38) with phi = 4, V = 2.5e-5 m/s, L = 1e-3 m: c = sqrt(8e-7/delta)")
    print("limits with v_max = 0 and the default coefficients (cfl 0.125, viscous 0.125); "
          "limit = the smaller one")
    print("arkode: at limit = fraction of steps equal to the stability limit, dt/limit = median "
          "step / limit, control: 'limit' = the stability limit\n  sets the step, 'held' = a "
          "constant step between limit/1.5 and the limit (not expected: vesph sets ARKODE's "
          "fixed-step bounds to [1, 1]), "
          "'error' = the error estimate\n")
    sc.print_table(rows, COLUMNS)
    print()
    for kind, table, rtol, gravity in integrators:
        series = label(kind, table, rtol, gravity)
        rs = [r for r in rows if r["series"] == series and r["status"] == "ok"
              and r["max_density_deviation"] > 0]
        if len(rs) >= 2:
            p = np.polyfit(np.log([r["delta"] for r in rs]),
                           np.log([r["max_density_deviation"] for r in rs]), 1)
            print(f"{series}: max density deviation ~ delta^{p[0]:.3f} "
                  f"(fit over all {len(rs)} values)")
        settled = [r for r in rs if r["transit"] < 0.5 * t_end]
        if len(settled) >= 2 and len(settled) < len(rs):
            p = np.polyfit(np.log([r["delta"] for r in settled]),
                           np.log([r["max_density_deviation"] for r in settled]), 1)
            print(f"{series}: max density deviation ~ delta^{p[0]:.3f} over the "
                  f"{len(settled)} runs with H/c < t_end/2")
    coef = limits.default_coefficients(vesph=a.vesph)
    cross = coef["cfl"] * h / (coef["viscous"] * h * h / sc.NU)
    d_cross = 8e-7 / cross ** 2
    print(f"the acoustic limit is the smaller one for c > {cross:.4g} m/s, i.e. "
          f"delta < {d_cross:.3g}")
    sc.safe_plot(plot, out / "sound_speed.png", rows, d_cross, t_end, a.ny)
    print(f"\nwrote {out / 'sound_speed.csv'}, {out / 'sound_speed.png'}, {out / 'commands.txt'}")
    return runner.finish()


def label(kind, table, rtol, gravity):
    return (sc.integrator_label(kind, table) + (f" rtol={rtol:g}" if rtol else "")
            + (", g_y=-F" if gravity else ""))


def plot(path, rows, d_cross, t_end, ny):
    plt = sc.pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(8.0, 6.0), sharex=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    series = list(dict.fromkeys(r["series"] for r in rows))
    panels = [("max_density_deviation", "max |ρ/ρ0 − 1| over the run"),
              ("err_analytic", f"error vs analytic at t = {t_end:g} s / (F H²/8ν)"),
              ("mean_dt", "mean step t_end/steps [s]"), ("wall_s", "wall time [s]")]
    for k, s in enumerate(series):
        rs = [r for r in rows if r["series"] == s and r["status"] == "ok"]
        for ax, (key, _) in zip(axes.flat, panels):
            ax.plot([r["delta"] for r in rs], sc.positive([r[key] for r in rs]), "-o",
                    color=colors[k], label=s, lw=0.8)
        bad = [r for r in rows if r["series"] == s and r["status"] != "ok"]
        for r in bad:
            axes[0, 0].axvline(r["delta"], color=colors[k], ls=":", lw=0.8)
    ds = sorted({r["delta"] for r in rows})
    ok = [r for r in rows if r["status"] == "ok" and r["max_density_deviation"] > 0]
    if ok:
        r0 = min(ok, key=lambda r: (r["delta"], -r["max_density_deviation"]))
        axes[0, 0].plot(ds, [r0["max_density_deviation"] * d / r0["delta"] for d in ds], "k--",
                        lw=0.7, label="∝ δ")
    lims = sorted({(r["delta"], r["acoustic_limit"], r["viscous_limit"]) for r in rows
                   if r["series"] == series[0]})
    axes[1, 0].plot([l[0] for l in lims], [l[1] for l in lims], "k--", lw=0.7,
                    label=f"acoustic limit 0.125 h/c ({series[0]})")
    axes[1, 0].plot([l[0] for l in lims], [l[2] for l in lims], "k:", lw=0.9,
                    label="viscous limit 0.125 h²/ν")
    for ax, (_, name) in zip(axes.flat, panels):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.25)
        ax.set_ylabel(name)
        ax.axvline(d_cross, color="grey", lw=0.6, alpha=0.6)
    for ax in axes[1]:
        ax.set_xlabel("δ (eq. 3.38)   [grey line: acoustic = viscous limit]")
    axes[0, 0].legend(loc="best")
    axes[1, 0].legend(loc="best")
    fig.suptitle(f"Sound speed from δ, Poiseuille H/{ny}, t_end = {t_end:g} s", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
