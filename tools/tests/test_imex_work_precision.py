"""study_imex_work_precision (vesph.studies.imex_work_precision): the --quick study on the two
channels runs every series and writes the CSV and the PNG, arkode-imex's step exceeds the
explicit viscous limit while the leapfrog and the midpoint sit at it, --plot-only redraws the
PNG from the CSV; the die's scene; the
reference error matched by particle id when particles enter and leave. Needs the vesph binary
(VESPH, default build/vesph); the quick study takes a few seconds."""
import math
import os
import subprocess
import tomllib

import numpy as np

from support import TOOLS, expect, load_tests_of, read_csv_rows


def make_imex_work_precision_tests(tmp):
    from vesph.catalogue import vesph_binary
    from vesph.studies import common as sc
    from vesph.studies import imex_work_precision as iwp

    def quick_study():
        out = os.path.join(tmp, "quick")
        p = subprocess.run([os.path.join(TOOLS, "vesph-post"), "study_imex_work_precision",
                            "--quick", "--case", "poiseuille", "oldroyd_b", "--out", out,
                            "--vesph", vesph_binary()], capture_output=True, text=True)
        expect(p.returncode == 0, f"exit {p.returncode}", p.stdout + p.stderr)
        rows = read_csv_rows(os.path.join(out, "imex_work_precision.csv"))
        expect(os.path.getsize(os.path.join(out, "imex_work_precision.png")) > 0
               and os.path.exists(os.path.join(out, "commands.txt")), "no PNG or commands.txt")
        for case in ("poiseuille", "oldroyd_b"):
            crs = [r for r in rows if r["case"] == case]
            series = {r["series"] for r in crs}
            want = {"arkode-imex ARK324L2SA", "arkode-imex-fixed ARK324L2SA", "leapfrog",
                    "midpoint", "reference"} | ({"arkode BS3"} if case == "poiseuille" else set())
            expect(want <= series, f"{case}: series {sorted(series)}, missing {sorted(want - series)}")
            expect(all(r["status"] == "ok" for r in crs), f"{case}: a run did not finish: "
                   f"{[(r['series'], r['status']) for r in crs]}")
            for r in crs:
                expect(math.isfinite(float(r["err_reference"])) and math.isfinite(float(r["err_analytic"])),
                       f"{case} {r['series']}: no error measured")
            ref = [r for r in crs if r["series"] == "reference"]
            expect(len(ref) == 1 and float(ref[0]["err_reference"]) == 0.0, f"{case}: reference row {ref}")
            # the mean step over the explicit viscous limit: IMEX (rtol 1e-3, and the fixed
            # step at the explicit part's limit) well above it, the explicit fixed steps at it
            imex = [r for r in crs if r["integrator"] == "arkode-imex-fixed"
                    or (r["integrator"] == "arkode-imex" and float(r["rtol"]) == 1e-3)]
            expect(len(imex) == 2 and all(float(r["dt_over_viscous"]) > 1.5 for r in imex),
                   f"{case}: IMEX's step does not exceed the viscous limit: "
                   f"{[(r['series'], r['dt_over_viscous']) for r in imex]}")
            for r in crs:
                if r["integrator"] in ("leapfrog", "midpoint"):
                    expect(abs(float(r["dt_over_viscous"]) - 1) < 0.02 and r["control"] == "limit",
                           f"{case} {r['series']}: step {r['dt_over_viscous']} x viscous limit, "
                           f"control {r['control']}")
            imex_adaptive = [r for r in crs if r["integrator"] == "arkode-imex"]
            expect(all(r["control"] in ("limit", "error") for r in imex_adaptive),
                   f"{case}: IMEX control {[r['control'] for r in imex_adaptive]}")
        # --plot-only redraws the PNG from the CSV without running vesph
        png = os.path.join(out, "imex_work_precision.png")
        os.remove(png)
        p = subprocess.run([os.path.join(TOOLS, "vesph-post"), "study_imex_work_precision",
                            "--quick", "--case", "poiseuille", "oldroyd_b", "--out", out,
                            "--plot-only", "--vesph", "/nonexistent/vesph"], capture_output=True, text=True)
        expect(p.returncode == 0 and os.path.getsize(png) > 0, f"--plot-only: exit {p.returncode}",
               p.stdout + p.stderr)

    def die_scene():
        s = iwp.die_scene(500.0)
        back = tomllib.loads(iwp.dss.toml_dumps(s))
        e = back["effects"]
        expect(back["fluid"]["viscosity"] == 500.0 and back["inflow"]["mean_velocity"] == iwp.DIE_MEAN_SPEED
               and back["solver"]["scheme"] == "isph" and "viscosity" in e
               and not {"second_order_fluid", "velocity_gradient", "stress_divergence",
                        "equation_of_state"} & set(e),
               f"die scene: fluid {back['fluid']}, inflow {back['inflow']}, effects {sorted(e)}")
        case = iwp.die_case(0.01, False, tmp)
        expect(abs(case.viscous_limit - 0.125 * (1.6e-3) ** 2 / 0.5) < 1e-15
               and os.path.exists(case.scene), f"die case: viscous limit {case.viscous_limit}")

    def reference_error_by_id():
        # the run lost particle 0 (left at the outflow) and released particle 5; the reference
        # released 4 (not yet in the run): compared on ids 1, 2, 3
        def run(ids, vx, vy):
            r = sc.Run(label="r", sets=[], cmd=[], returncode=0, status="ok")
            ids = np.asarray(ids)
            r.frames = [sc.FluidFrame(time=1.0, ids=ids, y=np.zeros(len(ids)), vx=np.asarray(vx, float),
                                      rho=np.ones(len(ids)), vy=np.asarray(vy, float))]
            return r
        a = run([1, 2, 3, 5], [1.0, 2.0, 3.0, 9.0], [0.0, 0.0, 0.4, 9.0])
        ref = run([0, 1, 2, 3, 4], [7.0, 1.0, 2.0, 3.3, 7.0], [7.0, 0.0, 0.0, 0.0, 7.0])
        mx, rms, matched = iwp.reference_error(a, ref, 1.0, 0.5)
        expect(abs(mx - 1.0) < 1e-12 and abs(rms - math.sqrt(1.0 / 3)) < 1e-12 and matched == 0.6,
               f"max {mx}, rms {rms}, matched {matched}")

    return [("study_imex_work_precision --quick: every series, IMEX step above the viscous "
             "limit, CSV and PNG", quick_study),
            ("study_imex_work_precision: the Newtonian ISPH die scene", die_scene),
            ("study_imex_work_precision: reference error on the ids of both frames",
             reference_error_by_id)]


load_tests = load_tests_of(make_imex_work_precision_tests)
