#!/usr/bin/python3
"""Work-precision on stiff cases: arkode-imex against the explicit integrators where the
viscous limit binds.

Usage
-----
    tools/vesph-post study_imex_work_precision [--case NAME ...] [--out DIR] [--quick]
        [--threads N] [--vesph BIN] [--keep-runs DIR] [--plot-only]

Cases (--case, default all; docs/studies.md section 6):
  poiseuille   the Poiseuille start-up (cases/poiseuille_newtonian.toml, H/40) at 100 times
               the demo's viscosity, mu = 0.1 Pa s, with F = 0.02 m/s^2 (100 times too) so the
               steady centreline speed F H^2/(8 nu) stays 2.5e-5 m/s (Re 100 times lower,
               2.5e-4); to t = 0.005 s = 0.5 H^2/nu.  Viscous limit 2e-6 s, acoustic 5.6e-5 s.
               Analytic error: the start-up series (vesph.analytic.analytic_velocity).
  oldroyd_b    the Oldroyd-B start-up (cases/startup_channel_oldroyd_b.toml) at E = lambda
               eta0/(rho a^2) = 100, beta = 0.5: eta_s = eta_p = 0.05 Pa s (eta0 100 times the
               case's), lambda = 0.25 s, F = 0.02 m/s^2 (the same steady speed; Re 100 times
               lower), H/20 (the explicit runs take 15 600 steps per lambda at H/20, 62 500
               at H/40); to t = 2 lambda = 0.5 s.
               Viscous limit (solvent viscosity) 1.6e-5 s, acoustic 1.1e-4 s (9.7e-5 s with the
               elastic wave speed, which arkode-imex integrates implicitly).  Analytic error:
               Waters & King (vesph.analytic.waters_king), relative to the steady centreline
               speed 2.5e-5 m/s.
  die_re0.5    the Newtonian ISPH die of `die_swell_study wsph_isph` (vesph.studies.die_swell,
  die_re0.01   10 across, W = 0.01 m; scene in DIR/scenes/): feed mean speed 0.5 m/s ramped
               over 2 ms, mu = 10 Pa s (Re = rho W U/mu = 0.5) or 500 Pa s (Re = 0.01); to
               t = 10 ms (Re 0.5) or 2 ms (Re 0.01).  Viscous limit 3.2e-5 s and 6.4e-7 s; the
               explicit part's (advective) limit 0.175 h/U_peak = 3.7e-4 s.  No analytic
               solution: the error is against the reference only.  Particles enter and leave:
               the velocities are compared on the ids present in both frames.

Per case it runs
  * arkode-imex with ARK324L2SA at several rtol and ARK436L2SA at one or two;
  * arkode-imex-fixed (ARK324L2SA) at the explicit part's limit (acoustic limit under WCSPH,
    advective cfl h/U_peak under ISPH) and at half of it;
  * semi-implicit at the same steps, when `vesph list` has it;
  * leapfrog at integrator.step = 6 (channels), 2, 1 and 1/2 (not at Re 0.01) times the
    explicit viscous limit 0.125 h^2/nu; midpoint at the limit.  The default coefficient 0.125
    is 4 times below the leapfrog's measured bound 0.5 (docs/studies.md section 2), so 2x is
    expected to be stable in the channels and 6x to go unstable (vesph exits 3: recorded as
    status "unstable");
  * arkode (explicit, adaptive): DORMAND_PRINCE_7_4_5 (poiseuille) and BOGACKI_SHAMPINE_4_2_3
    at rtol 1e-3 (every rtol of the explicit ARKODE runs at the stability limit here,
    docs/studies.md section 1);
  * a reference at the same resolution: arkode-fixed DORMAND_PRINCE_7_4_5 at the explicit
    limit (poiseuille, oldroyd_b: 5th order, its temporal error far below the others'), or the
    leapfrog at 1/4 (die_re0.5) or 1/2 (die_re0.01) of the viscous limit (a reference with the
    ISPH projection after every small step: an IMEX reference would share IMEX's projection
    splitting error, docs/studies.md section 6).
For every run: err_reference = max over fluid particles, matched by id, of |v - v_ref| / U
(both velocity components; U the case's velocity scale: 2.5e-5 m/s for the channels, the
feed's mean 0.5 m/s for the die), err_reference_rms (the same as an rms), err_analytic (the
channels: max |vx - v_exact| / U), wall time (summary.json wall_seconds, one thread),
rhs evaluations, steps, the mean step over the explicit viscous limit (dt/visc), and the
step's controller (vesph.studies.common.step_control): the limit is the explicit part's
(without the viscous limit and, for Oldroyd-B, without the elastic wave speed under
arkode-imex, with them otherwise; the force limit is not included), "limit" when at least half
of the steps are at it, "error" when the error estimate sets the step (adaptive runs),
"fixed" for a fixed step below the limit.

Writes DIR/imex_work_precision.csv, DIR/imex_work_precision.png (one panel per case: error
against the reference vs wall time, one series per integrator; points whose step the stability
limit sets drawn hollow; the analytic error of the reference, i.e. the spatial error, as a
dashed line), DIR/commands.txt (every vesph command), DIR/scenes/ (the die scenes), and
prints the table.  --plot-only redraws the PNG from DIR's CSV without running vesph.
--quick: tiny versions for the tests (seconds for the channels): H/10 channels over 20
viscous-limit steps, the die over 0.2 ms, one or two runs per integrator.

Exit status: 0 when every run finished or was recorded as unstable; 1 when a run failed
otherwise (or a reference did not finish); 2 for usage errors.
"""

import argparse
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vesph.analytic import waters_king
from vesph.catalogue import catalogue
from vesph.checks import startup_channel
from vesph.studies import common as sc
from vesph.studies import die_swell as dss

STUDY = "imex_work_precision"
CASES = ("poiseuille", "oldroyd_b", "die_re0.5", "die_re0.01")
IMEX_TABLES = ("ARK324L2SA", "ARK436L2SA")
COLUMNS = [("case", "case", "s"), ("series", "series", "s"), ("integrator", "integrator", "s"),
           ("table", "table", "s"), ("step", "step [s]", ".3g"), ("rtol", "rtol", ".0e"),
           ("status", "status", "s"), ("steps", "steps", "d"), ("rejected", "rej", "d"),
           ("rhs_evals", "rhs evals", "d"), ("wall_s", "wall [s]", ".2f"),
           ("mean_dt", "mean dt [s]", ".3g"), ("dt_over_viscous", "dt/visc", ".2f"),
           ("at_limit", "at limit", ".2f"), ("dt_over_limit", "dt/limit", ".3f"),
           ("control", "control", "s"), ("err_reference", "err ref", ".3e"),
           ("err_reference_rms", "err ref rms", ".3e"), ("err_analytic", "err analytic", ".3e")]


@dataclass
class Case:
    """One stiff case: its scene, the limits that set the tested steps, its runs."""
    name: str
    title: str
    scene: str
    sets: list
    t_end: float
    h: float
    nu: float                  # kinematic viscosity of the viscous limit (solvent), m^2/s
    scheme: str                # wcsph | isph
    velocity_scale: float      # m/s, errors are relative to it
    explicit_limit: float      # s, the explicit part's limit (IMEX-fixed steps are fractions of it)
    viscous_factors: list      # leapfrog/midpoint steps as multiples of the viscous limit
    imex_rtols: dict           # table -> rtols
    arkode_runs: list          # (table, rtol) of explicit adaptive runs
    reference: tuple           # (kind, table, step)
    analytic: object = None    # fn(frame, run) -> max error / velocity_scale, or None
    elastic_speed: float = 0.0
    relaxation_time: float = 0.0
    notes: list = field(default_factory=list)

    @property
    def viscous_limit(self):
        return 0.125 * self.h * self.h / self.nu


# ------------------------------------------------------------------------------ the cases
def poiseuille_case(quick):
    ny = 10 if quick else 40
    h = sc.SMOOTHING_RATIO * sc.H / ny
    mu, force = 0.1, 0.02
    nu = mu / 1000.0
    c = sc.rule_sound_speed(0.01, nu=nu, g=force)        # thesis eq. (3.38): the F L/delta term
    visc = 0.125 * h * h / nu
    acoustic = 0.125 * h / (c + sc.U_CENTRE)
    return Case(
        name="poiseuille", title=f"Poiseuille start-up, nu x100, H/{ny}",
        scene=str(sc.REPO / "cases" / "poiseuille_newtonian.toml"),
        sets=sc.geometry(ny) + [f"fluid.viscosity={mu}",
                                f"effects.body_force.acceleration={sc.vec(force, 0.0)}"],
        t_end=20 * visc if quick else 0.005, h=h, nu=nu, scheme="wcsph",
        velocity_scale=sc.U_CENTRE, explicit_limit=acoustic,
        viscous_factors=[1.0] if quick else [6.0, 2.0, 1.0, 0.5],
        imex_rtols={"ARK324L2SA": [1e-3, 1e-6]} if quick else
        {"ARK324L2SA": [1e-3, 1e-4, 1e-5, 1e-6], "ARK436L2SA": [1e-4, 1e-6]},
        arkode_runs=[("BOGACKI_SHAMPINE_4_2_3", 1e-3)] if quick else
        [("DORMAND_PRINCE_7_4_5", 1e-3), ("BOGACKI_SHAMPINE_4_2_3", 1e-3)],
        reference=("arkode-fixed", "DORMAND_PRINCE_7_4_5", visc),
        analytic=lambda fr, run: sc.analytic_error(run, fr.time))


def oldroyd_b_analytic(fr, run):
    rho, eta_s, eta_p, lam, F, y0, y1 = startup_channel.parameters(run.scene)
    eta0 = eta_s + eta_p
    half = 0.5 * (y1 - y0)
    E = lam * eta0 / (rho * half * half)
    ubar = F * half * half / (3 * eta0 / rho)
    exact = waters_king((fr.y - (y0 + half)) / half, fr.time / lam, E, eta_s / eta0) * ubar
    return float(np.max(np.abs(fr.vx - exact))) / (1.5 * ubar)


def oldroyd_b_case(quick):
    ny = 10 if quick else 20
    h = sc.SMOOTHING_RATIO * sc.H / ny
    eta_s = eta_p = 0.05
    lam = 0.25                       # E = lam (eta_s + eta_p)/(rho a^2), a = H/2: 100
    force = 0.02
    nu_s = eta_s / 1000.0
    # the case's sound-speed rule (V = 5e-5 m/s): the F L/delta term dominates
    c = sc.rule_sound_speed(0.01, velocity=5e-5, nu=(eta_s + eta_p) / 1000.0, g=force)
    c_e = math.sqrt(eta_p / (lam * 1000.0))
    visc = 0.125 * h * h / nu_s
    acoustic_imex = 0.125 * h / (c + 2.5e-5)
    acoustic_explicit = 0.125 * h / (c + c_e + 2.5e-5)
    return Case(
        name="oldroyd_b", title=f"Oldroyd-B start-up, E = 100, beta = 0.5, H/{ny}",
        scene=str(sc.REPO / "cases" / "startup_channel_oldroyd_b.toml"),
        sets=sc.geometry(ny) + [f"fluid.viscosity={eta_s}",
                                f"effects.oldroyd_b.polymer_viscosity={eta_p}",
                                f"effects.oldroyd_b.relaxation_time={lam}",
                                f"effects.body_force.acceleration={sc.vec(force, 0.0)}"],
        t_end=20 * visc if quick else 2 * lam, h=h, nu=nu_s, scheme="wcsph",
        velocity_scale=sc.U_CENTRE, explicit_limit=acoustic_imex,
        viscous_factors=[1.0] if quick else [6.0, 2.0, 1.0, 0.5],
        imex_rtols={"ARK324L2SA": [1e-3]} if quick else
        {"ARK324L2SA": [1e-3, 1e-5], "ARK436L2SA": [1e-4]},
        arkode_runs=[] if quick else [("BOGACKI_SHAMPINE_4_2_3", 1e-3)],
        reference=("arkode-fixed", "DORMAND_PRINCE_7_4_5", min(visc, acoustic_explicit)),
        analytic=oldroyd_b_analytic, elastic_speed=c_e, relaxation_time=lam)


DIE_MEAN_SPEED = 0.5      # m/s, the feed's mean (centreline 0.75 m/s)
DIE_RAMP = 0.002          # s


def die_scene(mu):
    """The Newtonian ISPH die of the wsph_isph study at 10 across with the feed's mean speed
    DIE_MEAN_SPEED and viscosity mu: Re = rho W U / mu."""
    run = dss.Run("die", 1.5 * DIE_MEAN_SPEED, 0.0, scheme="isph")
    s = dss.scene_for(run, 10)
    e = s["effects"]
    for k in ("second_order_fluid", "velocity_gradient", "stress_divergence"):
        e.pop(k, None)               # Newtonian: the viscosity effect alone (procedure 3)
    s["fluid"]["viscosity"] = float(mu)
    s["inflow"]["mean_velocity"] = DIE_MEAN_SPEED
    s["inflow"]["ramp_time"] = DIE_RAMP
    s["output"] = {}                 # the runner sets output.times
    s["name"] = f"die_re{dss.RHO * dss.W * DIE_MEAN_SPEED / mu:g}"
    return s


def die_case(re, quick, scenes_dir):
    mu = dss.RHO * dss.W * DIE_MEAN_SPEED / re
    s = die_scene(mu)
    path = Path(scenes_dir) / f"{s['name']}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"# {STUDY}: the Newtonian ISPH die at Re = {re:g} (mu = {mu:g} Pa s), "
                    f"10 across\n" + dss.toml_dumps(s) + "\n")
    dx = dss.W / 10
    h = 1.6 * dx
    nu = mu / dss.RHO
    visc = 0.125 * h * h / nu
    advective = 0.175 * h / (1.5 * DIE_MEAN_SPEED)     # cfl h / U_peak, the ISPH cfl
    t_end = 2e-4 if quick else (0.01 if re >= 0.1 else 0.002)
    if quick:
        imex_rtols = {"ARK324L2SA": [1e-3]}
    else:
        imex_rtols = {"ARK324L2SA": [1e-2, 1e-3, 1e-4, 1e-5], "ARK436L2SA": [1e-3, 1e-5]}
    return Case(
        name=f"die_re{re:g}", title=f"ISPH die swell, Re = {re:g}, 10 across",
        scene=str(path), sets=[], t_end=t_end, h=h, nu=nu, scheme="isph",
        velocity_scale=DIE_MEAN_SPEED, explicit_limit=min(advective, t_end / 4),
        viscous_factors=[1.0] if quick else [2.0, 1.0, 0.5] if re >= 0.1 else [1.0],
        imex_rtols=imex_rtols,
        arkode_runs=[] if quick else [("BOGACKI_SHAMPINE_4_2_3", 1e-3)],
        reference=("leapfrog", None, visc / (4 if re >= 0.1 else 2)))


def make_case(name, quick, out):
    if name == "poiseuille":
        return poiseuille_case(quick)
    if name == "oldroyd_b":
        return oldroyd_b_case(quick)
    return die_case(float(name.removeprefix("die_re")), quick, Path(out) / "scenes")


# ------------------------------------------------------------------------------ errors
def reference_error(run, ref, t, scale):
    """(max, rms) over the fluid particles present in both frames (matched by id) of
    |v - v_ref| / scale, and the fraction of the reference's particles matched."""
    fr = run.frame_at(t) if run.frames else None
    fref = ref.frame_at(t) if ref is not None and ref.frames else None
    if fr is None or fref is None:
        return math.nan, math.nan, math.nan
    common, i, j = np.intersect1d(fr.ids, fref.ids, assume_unique=True, return_indices=True)
    if len(common) == 0:
        return math.nan, math.nan, 0.0
    d = np.hypot(fr.vx[i] - fref.vx[j], fr.vy[i] - fref.vy[j]) / scale
    return float(np.max(d)), float(np.sqrt(np.mean(d * d))), len(common) / len(fref.ids)


def classify(case, run, kind, step):
    """(at_limit, dt/limit, control) of a run against the limit of its explicit part."""
    implicit = kind in ("arkode-imex", "arkode-imex-fixed", "semi-implicit")
    elastic_implicit = kind in ("arkode-imex", "arkode-imex-fixed")
    at, ratio, control = sc.step_control(
        run, nu=case.nu, scheme=case.scheme, implicit_viscous=implicit,
        elastic_speed=0.0 if elastic_implicit else case.elastic_speed,
        relaxation_time=None if elastic_implicit else (case.relaxation_time or None))
    if step is not None and control:
        control = "limit" if at >= 0.5 else "fixed"
    if step is not None and not control:
        control = "fixed"
    return at, ratio, control


# ------------------------------------------------------------------------------ running
def plan_runs(case, with_semi_implicit):
    """(kind, table, step, rtol) of every run of a case, the reference excluded."""
    plan = []
    for table, rtols in case.imex_rtols.items():
        for rtol in rtols:
            plan.append(("arkode-imex", table, None, rtol))
    fixed_steps = [case.explicit_limit * f for f in ((1.0,) if len(case.viscous_factors) == 1
                                                     else (1.0, 0.5))]
    for dt in fixed_steps:
        plan.append(("arkode-imex-fixed", "ARK324L2SA", dt, None))
    if with_semi_implicit:
        for dt in fixed_steps:
            plan.append(("semi-implicit", None, dt, None))
    for f in case.viscous_factors:
        plan.append(("leapfrog", None, f * case.viscous_limit, None))
    # the midpoint at the limit only: in these cases its errors are the leapfrog's to 2-3 digits
    plan.append(("midpoint", None, case.viscous_limit, None))
    for table, rtol in case.arkode_runs:
        plan.append(("arkode", table, None, rtol))
    return plan


def series_label(kind, table):
    if kind in ("arkode-imex", "arkode-imex-fixed") and table:
        return f"{kind} {table}"
    return sc.integrator_label(kind, table)


def run_case(runner, case, with_semi_implicit):
    runner.scene = case.scene
    kind, table, step = case.reference
    ref = runner.run(f"{case.name}: reference {series_label(kind, table)} step={step:.4g}",
                     case.sets + sc.integrator_sets(kind, table, step), case.t_end)
    rows = []
    if not ref.ok:
        print(f"{case.name}: the reference run did not finish", file=sys.stderr)
        return rows, False
    ref_row = row_for(case, ref, "reference", kind, table, step, None)
    ref_row["err_reference"] = ref_row["err_reference_rms"] = 0.0
    for kind, table, step, rtol in plan_runs(case, with_semi_implicit):
        series = series_label(kind, table)
        label = f"{case.name}: {series}" + (f" step={step:.4g}" if step else f" rtol={rtol:g}")
        run = runner.run(label, case.sets + sc.integrator_sets(kind, table, step, rtol),
                         case.t_end)
        row = row_for(case, run, series, kind, table, step, rtol)
        if run.ok:
            row["err_reference"], row["err_reference_rms"], matched = reference_error(
                run, ref, case.t_end, case.velocity_scale)
            if matched < 0.99:
                print(f"  {label}: {100 * matched:.1f} % of the reference's particles matched",
                      file=sys.stderr)
        rows.append(row)
    rows.append(ref_row)
    return rows, True


def row_for(case, run, series, kind, table, step, rtol):
    row = {"case": case.name, "series": series, "integrator": kind, "table": table or "",
           "step": step, "rtol": rtol, "status": run.status, "steps": run.steps,
           "rejected": run.rejected, "rhs_evals": run.rhs_evals, "wall_s": run.wall,
           "mean_dt": math.nan, "dt_over_viscous": math.nan, "at_limit": math.nan,
           "dt_over_limit": math.nan, "control": "", "err_reference": math.nan,
           "err_reference_rms": math.nan, "err_analytic": math.nan}
    if run.ok:
        if run.steps > 0:
            row["mean_dt"] = case.t_end / run.steps
            row["dt_over_viscous"] = row["mean_dt"] / case.viscous_limit
        row["at_limit"], row["dt_over_limit"], row["control"] = classify(case, run, kind, step)
        if case.analytic is not None:
            row["err_analytic"] = case.analytic(run.frame_at(case.t_end), run)
    return row


def read_rows(path):
    """The rows of a CSV this study wrote, with numbers as numbers (empty: NaN or None)."""
    import csv
    numeric = {k for k, _, spec in COLUMNS if spec != "s"}
    rows = []
    with open(path, newline="") as fh:
        for raw in csv.DictReader(fh):
            row = {}
            for k, v in raw.items():
                if k in numeric:
                    row[k] = (None if k in ("step", "rtol") else math.nan) if v == "" else float(v)
                else:
                    row[k] = v
            rows.append(row)
    return rows


def has_semi_implicit(vesph):
    return any(i.get("name") == "semi-implicit" for i in catalogue(vesph).get("integrators", []))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sc.common_arguments(ap, STUDY)
    ap.add_argument("--case", nargs="+", choices=CASES, default=list(CASES),
                    help="cases to run (default all)")
    ap.add_argument("--plot-only", action="store_true",
                    help="redraw DIR/imex_work_precision.png from DIR/imex_work_precision.csv "
                         "(the cases given, with the same --quick) without running vesph")
    a = ap.parse_args(argv)
    if a.plot_only:
        rows = read_rows(Path(a.out) / f"{STUDY}.csv")
        cases = [make_case(n, a.quick, a.out) for n in a.case]
        cases = [c for c in cases if any(r["case"] == c.name for r in rows)]
        plot(Path(a.out) / f"{STUDY}.png", rows, cases)
        print(f"wrote {Path(a.out) / (STUDY + '.png')}")
        return 0
    runner = sc.Runner(a, STUDY)
    semi = has_semi_implicit(a.vesph)
    print(f"# {STUDY}: cases {', '.join(a.case)}; OMP_NUM_THREADS={a.threads}; semi-implicit "
          f"{'included' if semi else 'not in this vesph (skipped)'}", file=sys.stderr)
    cases = [make_case(n, a.quick, runner.out) for n in a.case]
    rows, ok = [], True
    for case in cases:
        print(f"# {case.name}: {case.title}; t_end = {case.t_end:.4g} s, viscous limit "
              f"{case.viscous_limit:.3g} s, explicit part's limit {case.explicit_limit:.3g} s",
              file=sys.stderr)
        case_rows, case_ok = run_case(runner, case, semi)
        rows += case_rows
        ok = ok and case_ok
    out = runner.out
    sc.write_csv(out / f"{STUDY}.csv", rows, COLUMNS)
    print(f"work-precision on stiff cases; OMP_NUM_THREADS = {a.threads}; errors against each "
          "case's reference (max over matched particles of |v - v_ref| / U)")
    for case in cases:
        print(f"\n{case.name}: {case.title}, t_end = {case.t_end:.4g} s, viscous limit "
              f"{case.viscous_limit:.3g} s, explicit part's limit {case.explicit_limit:.3g} s, "
              f"U = {case.velocity_scale:g} m/s; reference {series_label(*case.reference[:2])} "
              f"at {case.reference[2]:.4g} s")
        sc.print_table([r for r in rows if r["case"] == case.name], COLUMNS[1:])
    for r in rows:
        if r["status"] == "unstable":
            print(f"unstable: {r['case']} {r['series']} step={r['step']}")
    sc.safe_plot(plot, out / f"{STUDY}.png", rows, cases)
    print(f"\nwrote {out / (STUDY + '.csv')}, {out / (STUDY + '.png')}, {out / 'commands.txt'}")
    rc = runner.finish()
    return rc if ok else 1


def plot(path, rows, cases):
    plt = sc.pyplot()
    n = len(cases)
    ncols = 1 if n == 1 else 2
    nrows = (n + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.6 * ncols, 3.7 * nrows), squeeze=False)
    markers = "osD^v<>ph*"
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    all_series = [s for s in dict.fromkeys(r["series"] for r in rows) if s != "reference"]
    style = {s: (colors[k % len(colors)], markers[k % len(markers)]) for k, s in enumerate(all_series)}
    for ax, case in zip(axes.flat, cases):
        crs = [r for r in rows if r["case"] == case.name]
        for s in [x for x in all_series if any(r["series"] == x for r in crs)]:
            rs = sorted((r for r in crs if r["series"] == s and r["status"] == "ok"
                         and math.isfinite(r["err_reference"])), key=lambda r: r["wall_s"])
            if not rs:
                continue
            color, marker = style[s]
            xs = [r["wall_s"] for r in rs]
            ys = sc.positive([r["err_reference"] for r in rs])
            ax.plot(xs, ys, "-", color=color, lw=0.8)
            for i, (r, x, y) in enumerate(zip(rs, xs, ys)):
                hollow = r["control"] in ("limit", "held")
                ax.plot([x], [y], marker, color=color, mfc="none" if hollow else color,
                        label=s if i == 0 else None)
        ref = [r for r in crs if r["series"] == "reference" and math.isfinite(r["err_analytic"])]
        if ref:
            ax.axhline(ref[0]["err_analytic"], color="grey", ls="--", lw=0.8,
                       label="spatial error (reference vs analytic)")
        unstable = sorted({f"{r['series']} at {r['step']:.3g} s" for r in crs
                           if r["status"] == "unstable"})
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.25)
        ax.set_xlabel("wall time [s] (one thread)")
        ax.set_ylabel("max |v - v_ref| / U")
        ax.set_title(f"{case.title}, t = {case.t_end:g} s"
                     + ("\nunstable: " + "; ".join(unstable) if unstable else ""), fontsize=7.5)
        ax.legend(loc="best", fontsize=5.5)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle("Work-precision on stiff cases: error against a fine reference vs wall time; "
                 "hollow: the stability limit sets the step", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
