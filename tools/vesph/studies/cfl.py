#!/usr/bin/python3
"""Step-limit study: raise the stability coefficients of the fixed-step integrators until
the Poiseuille start-up becomes unstable.

Usage
-----
    /usr/bin/python3 tools/study_cfl.py [--out DIR] [--quick] [--viscous C ...] [--cfl C ...]
        [--t-end-viscous T] [--t-end-acoustic T] [--no-extend] [--threads N]
        [--vesph BIN] [--scene FILE] [--keep-runs DIR]

Integrators: leapfrog, midpoint, arkode-fixed DORMAND_PRINCE_7_4_5,
arkode-fixed BOGACKI_SHAMPINE_4_2_3 and symplectic, each with the step from the stability limits
(theory.md section 8), on the H/40 Poiseuille case.

Sweep "viscous": the case as it is (c = 8.94e-3 m/s from delta = 0.01), where the viscous
  limit controls; integrator.viscous_coefficient = 0.0625 ... 1.0 (step coef h^2/nu with
  h^2/nu = 1.6e-3 s) with integrator.cfl = 1.0 so that the acoustic limit
  (cfl h/(c + vmax) = 4.5e-3 s) does not interfere; t_end = 0.1125 s.
Sweep "acoustic": sound_speed = 1.0 m/s, so that the acoustic limit cfl h/(c + vmax)
  = 4e-5 cfl s is below the viscous one (0.125 h^2/nu = 2e-4 s) for cfl < 5;
  integrator.cfl = 0.125 ... 1.0; t_end = 0.01125 s (the steps are short).
The scene keys accept coefficients up to 1; when an integrator is still stable at the
largest listed coefficient, the sweep goes on (unless --no-extend) with coefficients
x sqrt(2) (1.41, 2, 2.83, 4, 5.66, 8 times the largest) given as the equivalent exact step,
integrator.step = coef h^2/nu or coef h/c (column "via" = step), until the first unstable
run; in the acoustic sweep only while the step stays below 0.25 h^2/nu = 4e-4 s, where the
viscous part is stable for every integrator here.
A run that finishes but whose error exceeds 10 % or whose density deviation is over 100
times that of the same integrator at the smallest coefficient is flagged in the "note"
column (an instability that grows too slowly to stop the run by t_end).

Every run sets checks.max_speed = 1e-4 m/s (four times the steady centreline velocity
2.5e-5 m/s) so that a growing instability stops the run (vesph exit 3, recorded as
"unstable") within a few steps rather than running on to c.  Reported per run: error vs
analytic at t_end (max |vx - v| / (F H^2/(8 nu))), max density deviation (summary.json),
wall time, steps, rhs evaluations, the nominal step, the step per rhs evaluation, status
(ok / unstable) and, for unstable runs, the time of the last good state.

Writes DIR/cfl.csv, DIR/cfl.png (error and density deviation against the coefficient, one
column of panels per sweep, unstable points marked with x at the top of the panel) and
DIR/commands.txt; prints the table and, per sweep and integrator, the largest stable and
the smallest unstable coefficient.
--quick: viscous 0.125, 0.35, 0.5, 0.7, 1.0; cfl 0.25, 0.7, 1.0; t_end 0.0225 / 0.0045 s.

--scene-sweep: instead of the Poiseuille sweeps, raise integrator.cfl on the scene given by
  --scene (a dam break, a drop; its own settings otherwise, extra --set overrides with
  --set) for each integrator of --integrators (default leapfrog, symplectic, arkode,
  arkode-fixed DP5), coefficients --cfl (default 0.0625 ... 1.0; the scene keys accept up to
  1, arkode's cap up to 10) to --t-end, until the first unstable run per integrator. Unstable:
  vesph exit 3 (its checks: NaN, density deviation, speed guard, a particle leaving the
  domain), or a max density deviation over 3 times that of the same integrator at the
  smallest coefficient (noted "growing"). Reported per run: steps, rhs evaluations, wall
  time, max density deviation and the fluid's x-extent at t_end (max x - min x: the surge
  front of a dam break, the spread of a drop) against the smallest-coefficient run of the
  first integrator. Writes DIR/cfl_scene.csv and DIR/commands.txt.

Exit status: 0 when every run finished or was recorded as unstable; 1 when a run failed
otherwise; 2 for usage errors.
"""

import argparse
import math
import sys

from vesph import limits
from vesph.studies import common as sc

STUDY = "cfl"
INTEGRATORS = [("leapfrog", None), ("midpoint", None), ("arkode-fixed", "DORMAND_PRINCE_7_4_5"),
               ("arkode-fixed", "BOGACKI_SHAMPINE_4_2_3"), ("symplectic", None)]
COLUMNS = [("sweep", "sweep", "s"), ("series", "integrator", "s"), ("coefficient", "coef", ".4g"),
           ("via", "via", "s"), ("dt", "step [s]", ".3g"), ("status", "status", "s"),
           ("final_time", "t reached [s]", ".4g"), ("steps", "steps", "d"),
           ("rhs_evals", "rhs evals", "d"), ("dt_per_rhs", "dt/rhs [s]", ".3g"),
           ("wall_s", "wall [s]", ".2f"), ("err_analytic", "err analytic", ".3e"),
           ("max_density_deviation", "max |drho|/rho0", ".3e"), ("note", "note", "s")]
EXTEND = [2 ** (k / 2) for k in range(1, 7)]      # x 1.41, 2, 2.83, 4, 5.66, 8
ACOUSTIC_STEP_CAP = 0.25       # acoustic sweep: steps stay below 0.25 h^2/nu (viscous-stable)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sc.common_arguments(ap, STUDY)
    ap.add_argument("--viscous", type=float, nargs="+", help="viscous coefficients")
    ap.add_argument("--cfl", type=float, nargs="+", help="CFL coefficients")
    ap.add_argument("--t-end-viscous", type=float, help="end time of the viscous sweep, s")
    ap.add_argument("--t-end-acoustic", type=float, help="end time of the acoustic sweep, s")
    ap.add_argument("--acoustic-sound-speed", type=float, default=1.0,
                    help="sound speed of the acoustic sweep, m/s (default 1.0)")
    ap.add_argument("--no-extend", action="store_true",
                    help="do not go beyond the listed coefficients")
    ap.add_argument("--ny", type=int, default=40, help="particles across H (default 40)")
    ap.add_argument("--scene-sweep", action="store_true",
                    help="sweep integrator.cfl on --scene itself (see above)")
    ap.add_argument("--integrators", nargs="+",
                    help="--scene-sweep: integrators, TYPE or arkode[-fixed]:TABLE")
    ap.add_argument("--t-end", type=float, help="--scene-sweep: end time, s (default the scene's)")
    ap.add_argument("--set", dest="sets", action="append", default=[],
                    help="--scene-sweep: an extra override for every run (repeatable)")
    a = ap.parse_args(argv)
    if a.scene_sweep:
        return scene_sweep(a)
    if a.quick:
        visc = a.viscous or [0.125, 0.35, 0.5, 0.7, 1.0]
        cfls = a.cfl or [0.25, 0.7, 1.0]
        t_visc = a.t_end_viscous or 0.0225
        t_ac = a.t_end_acoustic or 0.0045
    else:
        visc = a.viscous or [0.0625, 0.125, 0.25, 0.35, 0.5, 0.6, 0.7, 1.0]
        cfls = a.cfl or [0.0625, 0.125, 0.25, 0.35, 0.5, 0.7, 1.0]
        t_visc = a.t_end_viscous or 0.1125
        t_ac = a.t_end_acoustic or 0.01125

    runner = sc.Runner(a, STUDY)
    geo = sc.geometry(a.ny) + ["checks.max_speed=0.0001"]
    h = sc.SMOOTHING_RATIO * sc.H / a.ny
    c_visc = sc.rule_sound_speed(0.01)
    c_ac = a.acoustic_sound_speed
    rows = []

    sweeps = [
        ("viscous", visc, t_visc, ["integrator.cfl=1.0"], c_visc,
         lambda k: f"integrator.viscous_coefficient={sc.fnum(k)}", lambda k: k * h * h / sc.NU),
        ("acoustic", cfls, t_ac, [f"effects.equation_of_state.sound_speed={sc.fnum(c_ac)}"], c_ac,
         lambda k: f"integrator.cfl={sc.fnum(k)}", lambda k: k * h / c_ac),
    ]
    for sweep, coefs, t_end, extra, c, key_set, step_of in sweeps:
        lim = sc.step_limits(h, c, vesph=a.vesph)
        print(f"# sweep {sweep}: c = {c:.4g} m/s, t_end = {t_end} s; with default coefficients "
              f"acoustic {lim['acoustic']:.3g} s, viscous {lim['viscous']:.3g} s",
              file=sys.stderr)
        for kind, table in INTEGRATORS:
            series = sc.integrator_label(kind, table)
            todo = [(k, "key") for k in coefs]
            if not a.no_extend:
                todo += [(max(coefs) * e, "step") for e in EXTEND]
            last_ok = True
            for k, via in todo:
                if via == "step" and not last_ok:
                    break
                if via == "step" and sweep == "viscous" and k > 4.0 * max(coefs):
                    break
                if via == "step" and sweep == "acoustic" and \
                        step_of(k) > ACOUSTIC_STEP_CAP * h * h / sc.NU * (1 + 1e-12):
                    break   # the viscous stability limit would interfere
                s = geo + extra + sc.integrator_sets(kind, table)
                s += [key_set(k)] if via == "key" else [f"integrator.step={sc.fnum(step_of(k))}"]
                run = runner.run(f"{sweep} {series} coef={k:.4g} ({via})", s, t_end)
                ok = run.ok
                rows.append({
                    "sweep": sweep, "series": series, "integrator": kind, "table": table or "",
                    "coefficient": k, "via": via, "dt": step_of(k), "status": run.status,
                    "final_time": run.final_time, "steps": run.steps, "rhs_evals": run.rhs_evals,
                    "dt_per_rhs": run.final_time / run.rhs_evals if run.rhs_evals > 0 else math.nan,
                    "wall_s": run.wall,
                    "err_analytic": sc.analytic_error(run, t_end) if ok else math.nan,
                    "max_density_deviation": run.density_deviation, "t_end": t_end})
                rows[-1]["note"] = note(rows[-1], rows)
                if via == "step":
                    last_ok = ok
                elif k == max(coefs):
                    last_ok = ok

    out = runner.out
    sc.write_csv(out / "cfl.csv", rows, COLUMNS)
    print(f"step-limit study: Poiseuille start-up H/{a.ny} (h = {h:g} m), "
          f"OMP_NUM_THREADS = {a.threads}, checks.max_speed = 1e-4 m/s")
    print(f"viscous sweep: c = {c_visc:.4g} m/s, cfl = 1.0, t_end = {t_visc} s, "
          f"step = coef x h^2/nu = coef x {h * h / sc.NU:.3g} s")
    lim = sc.step_limits(h, c_ac, vesph=a.vesph)
    print(f"acoustic sweep: c = {c_ac:g} m/s, viscous_coefficient = "
          f"{limits.default_coefficients(vesph=a.vesph)['viscous']:g} "
          f"({lim['viscous']:.3g} s), t_end = {t_ac} s, step = coef x h/(c+vmax) "
          f"= coef x {h / c_ac:.3g} s")
    print("err analytic = max |vx - v| / (F H^2/(8 nu)) at t_end; '-' for unstable runs\n")
    sc.print_table(rows, COLUMNS)
    print("\nstability boundary (largest stable / smallest unstable coefficient):")
    for sweep in ("viscous", "acoustic"):
        for kind, table in INTEGRATORS:
            series = sc.integrator_label(kind, table)
            rs = [r for r in rows if r["sweep"] == sweep and r["series"] == series]
            clean = [r["coefficient"] for r in rs if r["status"] == "ok" and not r["note"]]
            stable = [r["coefficient"] for r in rs if r["status"] == "ok"]
            unstable = [r["coefficient"] for r in rs if r["status"] == "unstable"]
            g = lambda xs, f: f"{f(xs):.3g}" if xs else "-"
            nonmono = stable and unstable and max(stable) > min(unstable)
            print(f"  {sweep:<8s} {series:<18s} clean up to {g(clean, max):>6s}; finished up to "
                  f"{g(stable, max):>6s}; unstable (exit 3) from "
                  f"{g(unstable, min) if unstable else 'none tried'}"
                  + ("  (not monotone!)" if nonmono else ""))
    sc.safe_plot(plot, out / "cfl.png", rows)
    print(f"\nwrote {out / 'cfl.csv'}, {out / 'cfl.png'}, {out / 'commands.txt'}")
    return runner.finish()


SCENE_COLUMNS = [("series", "integrator", "s"), ("coefficient", "cfl", ".4g"), ("status", "status", "s"),
                 ("final_time", "t reached [s]", ".4g"), ("steps", "steps", "d"),
                 ("rhs_evals", "rhs evals", "d"), ("rhs_per_step", "rhs/step", ".2f"),
                 ("wall_s", "wall [s]", ".2f"), ("max_density_deviation", "max |drho|/rho0", ".3e"),
                 ("extent", "x-extent [m]", ".5g"), ("extent_change", "vs reference", ".2e"),
                 ("note", "note", "s")]


def scene_sweep(a):
    """integrator.cfl raised on a scene of its own until the run is unstable (--scene-sweep)."""
    if a.t_end is None:
        print("cfl: --scene-sweep needs --t-end", file=sys.stderr)
        return 2
    cfls = a.cfl or ([0.125, 0.25, 0.5, 1.0] if a.quick else [0.0625, 0.125, 0.175, 0.25, 0.35, 0.5, 0.7, 1.0])
    specs = a.integrators or ["leapfrog", "symplectic", "arkode", "arkode-fixed:DORMAND_PRINCE_7_4_5"]
    runner = sc.Runner(a, STUDY)
    rows, reference = [], None
    for spec in specs:
        kind, _, table = spec.partition(":")
        series = sc.integrator_label(kind, table or None)
        first = None
        for k in sorted(cfls):
            if k > (10.0 if kind == "arkode" else 1.0):
                continue
            s = list(a.sets) + sc.integrator_sets(kind, table or None) + [f"integrator.cfl={sc.fnum(k)}"]
            run = runner.run(f"{series} cfl={k:.4g}", s, a.t_end)
            row = {"series": series, "coefficient": k, "status": run.status, "final_time": run.final_time,
                   "steps": run.steps, "rhs_evals": run.rhs_evals,
                   "rhs_per_step": run.rhs_evals / run.steps if run.steps > 0 else math.nan,
                   "wall_s": run.wall, "max_density_deviation": run.density_deviation,
                   "extent": math.nan, "extent_change": math.nan, "note": ""}
            last = run.frame_at(a.t_end) if run.ok else None
            if last is not None and last.x is not None and len(last.x):
                row["extent"] = float(last.x.max() - last.x.min())
            if run.ok and first is None:
                first = row
            if reference is None and run.ok:
                reference = row
            if reference is not None and math.isfinite(row["extent"]):
                row["extent_change"] = row["extent"] / reference["extent"] - 1
            if run.ok and first is not None and row is not first and \
                    row["max_density_deviation"] > 3 * first["max_density_deviation"]:
                row["note"] = f"growing: drho x{row['max_density_deviation'] / first['max_density_deviation']:.2g}"
            rows.append(row)
            if not run.ok or row["note"]:
                break
    sc.write_csv(runner.out / "cfl_scene.csv", rows, SCENE_COLUMNS)
    print(f"CFL sweep on {a.scene} to t = {a.t_end} s, OMP_NUM_THREADS = {a.threads}"
          + (", --set " + " --set ".join(a.sets) if a.sets else ""))
    print(f"x-extent: max x - min x of the fluid at t_end; 'vs reference': relative to "
          f"{reference['series']} at cfl {reference['coefficient']:g}" if reference else "no run finished")
    sc.print_table(rows, SCENE_COLUMNS)
    print("\nlargest stable coefficient (no exit 3, no growing density deviation):")
    for spec in specs:
        kind, _, table = spec.partition(":")
        series = sc.integrator_label(kind, table or None)
        rs = [r for r in rows if r["series"] == series]
        good = [r["coefficient"] for r in rs if r["status"] == "ok" and not r["note"]]
        bad = [r["coefficient"] for r in rs if r["status"] != "ok" or r["note"]]
        print(f"  {series:<18s} stable up to {max(good) if good else '-'}; "
              f"unstable from {min(bad) if bad else 'none tried'}")
    print(f"\nwrote {runner.out / 'cfl_scene.csv'}, {runner.out / 'commands.txt'}")
    return runner.finish()


def note(row, rows):
    """Flags for a run that finished but looks unstable: a large error, or a density
    deviation far above that of the same integrator at its smallest coefficient."""
    if row["status"] != "ok":
        return ""
    flags = []
    if row["err_analytic"] > 0.1:
        flags.append("error > 10 %")
    first = next(r for r in rows if r["sweep"] == row["sweep"] and r["series"] == row["series"])
    d0, d = first["max_density_deviation"], row["max_density_deviation"]
    if first["status"] == "ok" and d0 > 0 and d > 100 * d0:
        flags.append(f"growing: drho x{d / d0:.0e}")
    return "; ".join(flags)


def plot(path, rows):
    plt = sc.pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(8.0, 6.0))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    markers = "osD^v"
    for j, sweep in enumerate(("viscous", "acoustic")):
        srows = [r for r in rows if r["sweep"] == sweep]
        for i, key in enumerate(("err_analytic", "max_density_deviation")):
            ax = axes[i, j]
            vals = [r[key] for r in srows if r["status"] == "ok" and r[key] > 0]
            top = max(vals) * 3 if vals else 1.0
            for k, (kind, table) in enumerate(INTEGRATORS):
                series = sc.integrator_label(kind, table)
                rs = [r for r in srows if r["series"] == series]
                ok = [r for r in rs if r["status"] == "ok"]
                bad = [r for r in rs if r["status"] != "ok"]
                col = colors[k % len(colors)]
                ax.plot([r["coefficient"] for r in ok], sc.positive([r[key] for r in ok]),
                        "-" + markers[k], color=col, label=series, lw=0.8)
                if bad:
                    ax.plot([r["coefficient"] for r in bad], [top * (1.25 ** k)] * len(bad), "x",
                            color=col, ms=6, mew=1.5)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ticks = sorted({r["coefficient"] for r in srows})
            ax.set_xticks(ticks)
            ax.set_xticklabels([f"{t:.3g}" for t in ticks], rotation=45, fontsize=7)
            ax.xaxis.set_minor_locator(plt.NullLocator())
            ax.grid(True, which="both", alpha=0.25)
            ax.set_xlabel("integrator.viscous_coefficient (h²/ν units)" if sweep == "viscous"
                          else "integrator.cfl (h/(c+v) units), c = 1 m/s")
            ax.set_ylabel("error vs analytic / (F H²/8ν)" if i == 0 else "max |ρ/ρ0 − 1|")
            if i == 0:
                ax.set_title(f"{sweep} limit controls; x = unstable (exit 3)")
    axes[0, 0].legend(loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
