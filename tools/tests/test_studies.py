"""die_swell_study (vesph.studies.die_swell): the scenes of every study, the tabulation of two
synthetic runs and the bad-argument errors; peer_dam_break's integrator specifications."""
import json
import os
import subprocess

import numpy as np

from support import (DS_DX, DS_EXIT, DS_W, TOOLS, expect, load_tests_of, read_csv_rows, tool,
                     write_die_swell)


def make_die_swell_study_tests(tmp):
    import tomllib
    from vesph.studies import die_swell as dss

    d = os.path.join(tmp, "die_swell_study")
    os.makedirs(d, exist_ok=True)

    def scenes():
        with open(dss.BASE_CASE, "rb") as fh:
            base = tomllib.load(fh)
        for study in dss.STUDIES:
            for r in dss.study_runs(study):
                shifted = dss.scene_for(r, 10, 1.5)
                ps = shifted["effects"].get("particle_shifting")
                expect(ps == {"coefficient": 1.5, "speed": dss.g6(r.v / 1.5)}
                       and "particle_shifting" not in dss.scene_for(r, 10)["effects"]
                       and shifted["effects"]["free_surface"] == (dss.scene_for(r, 10)["effects"].get("free_surface")
                                                                   or {"threshold": 0.8}),
                       f"{study}/{r.label}: --shifting scene wrong: {ps}, {shifted['effects'].get('free_surface')}")
                for n in (10, 25):
                    s = dss.scene_for(r, n)
                    back = tomllib.loads(dss.toml_dumps(s))
                    expect(back == s, f"{study}/{r.label}: the TOML text does not read back")
                    if r.model == "oldroyd_b":   # the same mu and Psi1 = -2 alpha1 (RE contravariant)
                        ob = s["effects"]["oldroyd_b"]
                        expect("second_order_fluid" not in s["effects"]
                               and abs(s["fluid"]["viscosity"] + ob["polymer_viscosity"] - dss.MU) < 1e-4
                               and abs(2 * ob["polymer_viscosity"] * ob["relaxation_time"] + 2 * r.alpha1)
                               < 1e-5 * abs(r.alpha1), f"{r.label}: Oldroyd-B not matched: {ob}")
                    else:
                        expect(s["effects"]["second_order_fluid"]["alpha2"] == dss.g6(-0.1 * r.alpha1),
                               f"{r.label}: alpha2 != -0.1 alpha1")
                    expect(abs(s["inflow"]["mean_velocity"] - r.v / 1.5) < 1e-6 * r.v,
                           f"{r.label}: mean velocity != v/1.5")
                    e = s["effects"]
                    expect(("viscosity" in e) == (r.procedure == 3)
                           and ("stress_divergence" in e) == (r.procedure != 4),
                           f"{r.label}: procedure {r.procedure} has the wrong effects: {sorted(e)}")
                    isph = r.scheme == "isph"
                    expect(("equation_of_state" not in e and "continuity" not in e
                            and s.get("solver", {}).get("scheme") == "isph") if isph
                           else "solver" not in s and e["equation_of_state"]["sound_speed"] >= 120.0,
                           f"{r.label}: scheme {r.scheme} not set up")
                    if n == 25:    # the thesis resolution: the base case's geometry exactly
                        for k in range(3):
                            for key in ("min", "max"):
                                expect(np.allclose(s["blocks"][k][key], base["blocks"][k][key],
                                                   atol=1e-12),
                                       f"{r.label}: blocks[{k}].{key} {s['blocks'][k][key]} != "
                                       f"the base case's {base['blocks'][k][key]}")
                        for key in ("min", "max"):
                            expect(np.allclose(s["inflow"][key], base["inflow"][key], atol=1e-12),
                                   f"{r.label}: inflow.{key} differs from the base case")
        # --room: the default domain is the base case's (y from -0.01 to 0.02 m); room R puts
        # its lateral edges R die widths from the centreline, nothing else changes.
        r = dss.study_runs("frontier")[0]
        s0, s35 = dss.scene_for(r, 10), dss.scene_for(r, 10, room=3.5)
        expect(s0["domain"]["min"][1] == base["domain"]["min"][1]
               and s0["domain"]["max"][1] == base["domain"]["max"][1]
               and s35["domain"]["min"] == [s0["domain"]["min"][0], -0.03]
               and s35["domain"]["max"] == [s0["domain"]["max"][0], 0.04]
               and {k: v for k, v in s35.items() if k != "domain"}
               == {k: v for k, v in s0.items() if k != "domain"},
               f"--room: domain {s0['domain']} / {s35['domain']}")
        rc, out, err = tool("die_swell_study.py", "frontier", "--shifting", "1", "--room", "3.5",
                            "--dry-run", "--only", "re10_de1_leapfrog", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "frontier_shifting_room3.5", "re10_de1_leapfrog",
                                                       "re10_de1_leapfrog.toml")),
               f"--room 3.5 --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "frontier", "--room", "1", "--dry-run", "--out", d)
        expect(rc == 2 and "--room" in err, f"--room 1: exit {rc}", err)
        # --wall-floor: pressure_floor on both die walls of a WCSPH run, nothing else changes;
        # an ISPH run (wsph_isph's) is left alone; --scheme isph refuses it.
        sf = dss.scene_for(r, 10, wall_floor=0.0)
        expect([b.get("pressure_floor") for b in sf["blocks"]] == [None, 0.0, 0.0]
               and {k: v for k, v in sf.items() if k != "blocks"} == {k: v for k, v in s0.items() if k != "blocks"}
               and [{k: v for k, v in b.items() if k != "pressure_floor"} for b in sf["blocks"]] == s0["blocks"],
               f"--wall-floor: blocks {sf['blocks']}")
        ri = [x for x in dss.study_runs("wsph_isph") if x.scheme == "isph"][0]
        expect(all("pressure_floor" not in b for b in dss.scene_for(ri, 10, wall_floor=0.0)["blocks"]),
               "--wall-floor: the ISPH run's walls were given a floor")
        rc, out, err = tool("die_swell_study.py", "contraction", "--wall-floor", "0", "--dry-run", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "contraction_floor0", "newtonian_a1_0", "newtonian_a1_0.toml")),
               f"--wall-floor 0 --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "contraction", "--scheme", "isph", "--wall-floor", "0",
                            "--dry-run", "--out", d)
        expect(rc == 2 and "--wall-floor" in err, f"--wall-floor with --scheme isph: exit {rc}", err)
        # --surface-condition: [effects.surface_pressure] with the ISPH scene's flags (0.97) in a
        # WCSPH run, also over the shifting's 0.8; the ISPH run untouched; --scheme isph refuses.
        for shift in (0.0, 1.0):
            ss = dss.scene_for(r, 10, shifting=shift, surface=True)
            expect(ss["effects"].get("surface_pressure") == {}
                   and ss["effects"]["free_surface"]["threshold"] == 0.97,
                   f"--surface-condition (shifting {shift}): {ss['effects'].get('free_surface')}")
        si = dss.scene_for(ri, 10, surface=True)
        expect("surface_pressure" not in si["effects"] and si["effects"]["free_surface"] == {"threshold": 0.97},
               f"--surface-condition changed the ISPH run: {si['effects'].get('free_surface')}")
        rc, out, err = tool("die_swell_study.py", "contraction", "--wall-floor", "0", "--surface-condition",
                            "--dry-run", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "contraction_floor0_sp", "newtonian_a1_0", "newtonian_a1_0.toml")),
               f"--surface-condition --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "contraction", "--scheme", "isph", "--surface-condition",
                            "--dry-run", "--out", d)
        expect(rc == 2 and "--surface-condition" in err, f"--surface-condition with --scheme isph: exit {rc}", err)
        de = {v: sorted(round(r.De, 9) for r in dss.study_runs("deborah") if r.v == v)
              for v in (5.0, 10.0)}
        expect(de == {5.0: [0, 0.02, 0.1, 0.2, 0.3], 10.0: [0, 0.02, 0.1, 0.2, 0.3, 0.4, 0.5]},
               f"Deborah numbers of Table 4-1: {de}")
        front = [r for r in dss.study_runs("frontier") if r.v == 10.0]
        expect(max(r.De for r in front) >= 1.0 and {r.integrator for r in front} == {"leapfrog", "arkode"},
               "the frontier study reaches De >= 1 at Re 10 under both integrators")
        rc, out, err = tool("die_swell_study.py", "procedures", "--dry-run", "--out", d)
        expect(rc == 0 and out.count(" run ") == 4
               and os.path.exists(os.path.join(d, "procedures", "case4", "case4.toml")),
               f"--dry-run: exit {rc}", out + err)
        # --scheme isph: every run of a study as ISPH, filed beside the WCSPH study; the ISPH
        # scene is the wsph_isph study's (predictor projection, density relaxation, symmetric
        # grad p in the right-hand side and the correction).
        rc, out, err = tool("die_swell_study.py", "frontier", "--scheme", "isph", "--dry-run",
                            "--only", "re10_de1_leapfrog", "--out", d)
        path = os.path.join(d, "frontier_isph", "re10_de1_leapfrog", "re10_de1_leapfrog.toml")
        expect(rc == 0 and out.count(" run ") == 1 and os.path.exists(path),
               f"--scheme isph --dry-run: exit {rc}", out + err)
        if os.path.exists(path):
            with open(path, "rb") as fh:
                s = tomllib.load(fh)
            expect(s["solver"] == {"scheme": "isph", "linear_solver": "umfpack",
                                   "gradient": "symmetric", "carried_pressure": "predictor",
                                   "density_relaxation_time": 3.2e-4}
                   and s["effects"]["pressure_gradient"]["form"] == "symmetric"
                   and "equation_of_state" not in s["effects"]
                   and s["integrator"]["type"] == "leapfrog",
                   f"--scheme isph scene: {s.get('solver')}, {sorted(s['effects'])}")
        rc, out, err = tool("die_swell_study.py", "wsph_isph", "--scheme", "isph", "--dry-run",
                            "--out", d)
        expect(rc == 2 and "already runs both" in err, f"--scheme isph wsph_isph: exit {rc}", err)

    def tabulation():
        # Two runs of the wsph_isph study with synthetic outputs: one finished (the synthetic
        # extrudate swells to 29, 31, 30 rows of 25 over the later half: mean 1.2, std 0.033,
        # one piece; three stragglers on the die's end face above the exit and one beyond the
        # front, all detached), one stopped as diverged.
        sd = os.path.join(d, "tab")
        face = [[DS_EXIT + 0.5 * DS_DX, DS_W + k * DS_DX] for k in (4, 6, 8)]
        stragglers = np.array(face + [[0.27, DS_W + 10 * DS_DX]])
        for label, status in (("wcsph", "ok"), ("isph", "diverged")):
            rd = os.path.join(sd, "wsph_isph", label)
            os.makedirs(rd, exist_ok=True)
            write_die_swell(os.path.join(rd, label + ".h5"), extra=stragglers if status == "ok" else None)
            js = {"status": status, "final_time": 0.8, "steps": 800,
                  "wall_seconds": 2.5, "message": "density deviation 0.6"}
            if status == "ok":
                js["flow"] = {"removed": 37, "released": 900}
            with open(os.path.join(rd, "summary.json"), "w") as fh:
                json.dump(js, fh)
        rc, out, err = tool("die_swell_study.py", "wsph_isph", "--measure-only", "--out", sd,
                            "--no-png")
        expect(rc == 0, f"--measure-only: exit {rc}", out + err)
        rows = {r["label"]: r for r in read_csv_rows(os.path.join(sd, "wsph_isph", "wsph_isph.csv"))}
        w, i = rows["wcsph"], rows["isph"]
        expect(abs(float(w["swell_mean"]) - 1.2) < 1e-9 and abs(float(w["swell_std"]) - 0.0326599) < 1e-6,
               f"swell mean/std {w['swell_mean']} {w['swell_std']}, expected 1.2, 0.03266", out)
        expect(w["clusters"] == "1" and w["detached"] == "4" and w["die_face_residue"] == "3"
               and w["stable"] == "True"
               and w["exit_status"] == "0" and w["thesis_swell"] == "1.362"
               and w["removed_at_outflow"] == "37" and i["removed_at_outflow"] == "nan",
               f"finished run: {w}", out)
        expect(i["exit_status"] == "3" and i["stable"] == "False" and "density" in i["message"],
               f"diverged run: {i}", out)
        expect(out.count("NO") >= 1 and "wcsph" in out, "the printed table", out)

    def bad_arguments():
        rc, out, err = tool("die_swell_study.py", "forms", "--only", "nosuch", "--dry-run",
                            "--out", d)
        expect(rc == 2 and "nosuch" in err, f"--only nosuch: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "forms", "--across", "3", "--dry-run")
        expect(rc == 2 and "--across" in err, f"--across 3: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "nosuch")
        expect(rc == 2, f"unknown study: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "forms", "--vesph", "/nonexistent/vesph",
                            "--out", d)
        expect(rc == 2 and "no such executable" in err, f"missing vesph: exit {rc}", out + err)

    return [("die_swell_study: scenes of every study (TOML round trip, thesis geometry at 25 "
             "across, procedures' effects, ISPH, Table 4-1 De)", scenes),
            ("die_swell_study: --measure-only tabulation, stable and diverged runs", tabulation),
            ("die_swell_study: bad arguments", bad_arguments)]


def make_die_swell_convergence_tests(tmp):
    import math
    import tomllib
    from vesph.studies import die_swell as dss
    from vesph.studies import die_swell_convergence as dsc

    d = os.path.join(tmp, "die_swell_convergence")
    os.makedirs(d, exist_ok=True)

    def richardson():
        # phi = phi_ext + C h^p on h = 1/N: the observed order and the extrapolated value come
        # back exactly, for equal and unequal refinement ratios and either order of the input.
        for p, ns in ((2.0, (10, 20, 40)), (1.0, (10, 16, 25)), (1.5, (25, 16, 10, 50)),
                      (0.7, (12, 30, 18))):
            vals = [1.19 + 0.8 * (1.0 / n) ** p for n in ns]
            o = dsc.observed_order(ns, vals)
            fine = sorted(ns, reverse=True)[:3]
            expect(o["status"] == "monotone" and o["n"] == fine and abs(o["p"] - p) < 1e-9
                   and abs(o["extrapolated"] - 1.19) < 1e-9 and o["asymptotic"],
                   f"p = {p}, N = {ns}: {o}")
            # GCI_fine = 1.25 |e21| / phi1 / (r^p - 1): here 1.25 |phi1 - phi_ext| / phi1
            expect(abs(o["gci"] - 1.25 * (vals[ns.index(fine[0])] - 1.19) / vals[ns.index(fine[0])])
                   < 1e-9, f"GCI {o['gci']}")
        # falling towards the limit from above and from below alike
        o = dsc.observed_order((10, 16, 25), [1.05 - 2.0 / n ** 2 for n in (10, 16, 25)])
        expect(o["status"] == "monotone" and abs(o["p"] - 2) < 1e-9 and abs(o["extrapolated"] - 1.05) < 1e-9,
               f"from below: {o}")
        # not monotone: no extrapolated value, a message that says so
        o = dsc.observed_order((10, 16, 25), (1.19, 1.09, 1.12))
        expect(o["status"] == "oscillatory" and math.isnan(o["extrapolated"])
               and "not monotone" in o["message"] and not o["asymptotic"], f"oscillatory: {o}")
        # monotone but the changes grow under refinement: order <= 0, no value
        o = dsc.observed_order((10, 20, 40), (1.19, 1.17, 1.12))
        expect(o["status"] == "diverging" and o["p"] < 0 and math.isnan(o["extrapolated"])
               and "not converging" in o["message"], f"diverging: {o}")
        # a very high order: a value, flagged as outside the asymptotic range
        o = dsc.observed_order((10, 20, 40), (1.3, 1.2, 1.19999))
        expect(o["status"] == "monotone" and o["p"] > 4 and not o["asymptotic"]
               and "not reliable" in o["message"], f"order > 4: {o}")
        o = dsc.observed_order((10, 16, 25), (1.1, 1.1, 1.1))
        expect(o["status"] == "unchanged" and o["extrapolated"] == 1.1, f"unchanged: {o}")
        o = dsc.observed_order((10, 16), (1.2, 1.1))
        expect(o["status"] == "too_few" and math.isnan(o["p"]), f"two resolutions: {o}")
        o = dsc.observed_order((10, 16, 25), (1.2, float("nan"), 1.1))
        expect(o["status"] == "undefined", f"a missing value: {o}")

    def re_sweep():
        # one row per Re from the finest resolution that has a flux swell; the spread over the
        # resolutions; the Richardson value only where the three finest are monotone
        nan = float("nan")
        rows = [{"Re": re, "across": n, "flux": f, "flux_std": 0.01, "envelope": 1.3, "envelope_std": 0.1,
                 "filled": 1.2, "filled_std": 0.02}
                for re, n, f in ((0.5, 10, 1.10), (0.5, 13, 1.14), (0.5, 16, 1.16), (2.0, 10, 1.05),
                                 (2.0, 13, nan), (20.0, 10, 0.93))]
        rich = dsc.richardson_rows(rows, [0.5, 2.0, 20.0])
        sweep = dsc.re_sweep_rows(rows, rich)
        expect([r["Re"] for r in sweep] == [0.5, 2.0, 20.0], f"one row per Re: {sweep}")
        r05, r2 = sweep[0], sweep[1]
        expect(r05["across_finest"] == 16 and r05["flux"] == 1.16 and abs(r05["flux_spread"] - 0.06) < 1e-12
               and r05["flux_status"] == "monotone" and r05["flux_richardson"] > 1.16,
               f"Re 0.5: {r05}")
        expect(r2["across_finest"] == 10 and r2["resolutions"] == "10" and math.isnan(r2["flux_richardson"]),
               f"Re 2: the run without a flux swell is left out: {r2}")
        png = os.path.join(d, "re_sweep.png")
        dsc.plot_re_sweep(rows, png, "test")
        expect(os.path.getsize(png) > 1000, "the Re sweep figure is written")

    def scenes():
        with open(dsc.CASE, "rb") as fh:
            base = tomllib.load(fh)
        # 25 across at Re = 0.5 with the case's variants and end time is the case itself, but for
        # the frames' interval and the name; the baseline is the case of sessions 6-24 (Morris'
        # Laplacian, every wall particle in the pressure force, no shifting)
        s = dsc.scene(25, 0.5, dsc.CASE_VARIANT, end=base["time"]["end"])
        expect({k: v for k, v in s.items() if k not in ("name", "output")}
               == {k: v for k, v in base.items() if k not in ("name", "output")},
               f"25 across, Re 0.5 with the case's variants differs from the case: {s}")
        e = dsc.scene(25, 0.5)["effects"]
        expect(e["viscosity"] == {} and e["pressure_gradient"] == {}
               and not {"velocity_gradient", "free_surface", "particle_shifting"} & set(e),
               f"the study's baseline is not the Laplacian die with walls that pull: {e}")
        for n in (10, 13, 16, 20, 40):
            for re in (0.5, 0.01):
                s = dsc.scene(n, re)
                back = tomllib.loads(dss.toml_dumps(s))
                expect(back == s, f"{n} across, Re {re}: the TOML does not read back")
                dx = s["particles"]["spacing"]
                lower, upper = s["blocks"][1], s["blocks"][2]
                expect(abs(dx * n - dsc.W) < 1e-9
                       and abs(-lower["min"][1] - 5 * dx) < 1e-9 and abs(upper["max"][1] - dsc.W - 5 * dx) < 1e-9
                       and abs(s["inflow"]["max"][0] - s["inflow"]["min"][0] - 5 * dx) < 1e-9
                       and s["domain"]["min"][0] <= s["inflow"]["min"][0],
                       f"{n} across: geometry {s['blocks']}, {s['inflow']}")
                mu, c = s["fluid"]["viscosity"], s["effects"]["equation_of_state"]["sound_speed"]
                # Re = rho W U / mu, and the die's pressure drop 12 mu U L / W^2 the same share
                # of rho c^2 as the case's (1.9 %)
                expect(abs(1000.0 * 0.01 * 0.5 / mu - re) < 1e-6 * re
                       and abs(12 * mu * 0.5 * 0.05 / 0.01 ** 2 / (1000.0 * c ** 2) - 0.01875) < 1e-5,
                       f"Re {re}: mu {mu}, c {c}")
        # each variant changes one thing
        ref = dsc.scene(10, 0.5)
        for v, changed in (({"wall_floor": 0.0}, "pressure_floor"), ({"xsph": 0.0}, "xsph off"),
                           ({"xsph": 0.25}, "xsph 0.25"), ({"delta": 0.02}, "delta"),
                           ({"delta": 0.0}, "delta off"), ({"shifting": 1.0}, "shifting"),
                           ({"sound_speed": 80.0}, "c")):
            s = dsc.scene(10, 0.5, v)
            e, e0 = s["effects"], ref["effects"]
            ok = {"pressure_floor": lambda: s["blocks"][1].get("pressure_floor") == 0.0
                  and s["blocks"][2].get("pressure_floor") == 0.0 and e == e0,
                  "xsph off": lambda: "xsph" not in e and s["blocks"] == ref["blocks"],
                  "xsph 0.25": lambda: e["xsph"] == {"epsilon": 0.25},
                  "delta": lambda: e["density_diffusion"] == {"delta": 0.02},
                  "delta off": lambda: "density_diffusion" not in e,
                  "shifting": lambda: e["particle_shifting"] == {"coefficient": 1.0, "speed": 0.5}
                  and e["free_surface"] == {"threshold": 0.8},
                  "c": lambda: e["equation_of_state"]["sound_speed"] == 80.0}[changed]()
            others = {k: x for k, x in s.items() if k not in ("effects", "blocks")} == \
                {k: x for k, x in ref.items() if k not in ("effects", "blocks")}
            expect(ok and others, f"variant {v}: {s}")
            expect(dsc.variant_suffix(v) != "", f"variant {v} has no folder suffix")
        # the viscous forms change the effects only; the smoothing ratio the particles only
        for form, gradient in (("stress", {}), ("stress_renormalised", {"form": "renormalised"})):
            s = dsc.scene(10, 0.5, {"viscous_form": form})
            e, e0 = s["effects"], ref["effects"]
            rest = {k: x for k, x in e.items() if k not in ("viscosity", "velocity_gradient")}
            expect(e["viscosity"] == {"form": "stress"} and e["velocity_gradient"] == gradient
                   and "velocity_gradient" not in e0 and rest == {k: x for k, x in e0.items() if k != "viscosity"}
                   and {k: x for k, x in s.items() if k != "effects"} == {k: x for k, x in ref.items() if k != "effects"},
                   f"viscous form {form}: {s}")
            expect(dsc.variant_suffix({"viscous_form": form}) == "_" + form, f"{form}: suffix")
        s = dsc.scene(10, 0.5, {"smoothing_ratio": 1.0})
        expect(s["particles"]["smoothing_ratio"] == 1.0
               and {k: x for k, x in s.items() if k != "particles"} == {k: x for k, x in ref.items() if k != "particles"},
               f"smoothing ratio: {s['particles']}")
        expect(dsc.variant_suffix({"smoothing_ratio": 1.0}) == "_h1", "smoothing ratio: suffix")
        # the artificial stress adds its effect and nothing else
        s = dsc.scene(10, 0.5, {"artificial_stress": 0.2})
        expect(s["effects"]["artificial_stress"] == {"epsilon": 0.2, "exponent": 4}
               and {k: x for k, x in s["effects"].items() if k != "artificial_stress"} == ref["effects"]
               and dsc.variant_suffix({"artificial_stress": 0.2}) == "_as0.2", f"artificial stress: {s['effects']}")
        # ISPH: the projection's solver table and surface flags from the ISPH case, no equation
        # of state, continuity or density diffusion; the normal-stress surface adds its key and
        # the velocity gradient it reads
        with open(os.path.join(TOOLS, "..", "cases", "die_swell_newtonian_isph_imex.toml"), "rb") as fh:
            isph_case = tomllib.load(fh)
        s = dsc.scene(10, 0.5, {"scheme": "isph"})
        e = s["effects"]
        expect(s["solver"] == isph_case["solver"] and e["free_surface"] == isph_case["effects"]["free_surface"]
               and e["pressure_gradient"] == isph_case["effects"]["pressure_gradient"]
               and not ({"equation_of_state", "continuity", "density_diffusion"} & set(e))
               and s["blocks"] == ref["blocks"] and s["particles"] == ref["particles"]
               and dsc.variant_suffix({"scheme": "isph"}) == "_isph", f"isph: {s}")
        s = dsc.scene(10, 0.5, {"scheme": "isph", "surface_pressure": "normal_stress", "viscous_form": "stress_renormalised"})
        expect(s["solver"]["surface_pressure"] == "normal_stress" and s["effects"]["velocity_gradient"] == {"form": "renormalised"}
               and dsc.variant_suffix({"scheme": "isph", "surface_pressure": "normal_stress"}) == "_isph_nstress",
               f"isph normal stress: {s}")
        # WCSPH: the normal-stress surface is [effects.surface_pressure] on the rows flagged at 0.97
        s = dsc.scene(10, 0.5, {"surface_pressure": "normal_stress", "viscous_form": "stress_renormalised"})
        expect(s["effects"]["surface_pressure"] == {"value": "normal_stress"}
               and s["effects"]["free_surface"] == {"threshold": 0.97} and "solver" not in s
               and "equation_of_state" in s["effects"], f"wcsph normal stress: {s['effects']}")
        # the dry walls: the pressure force's key and nothing else
        s = dsc.scene(10, 0.5, {"dry_walls": "omit"})
        expect(s["effects"]["pressure_gradient"] == {"dry_walls": "omit"}
               and {k: x for k, x in s["effects"].items() if k != "pressure_gradient"}
               == {k: x for k, x in ref["effects"].items() if k != "pressure_gradient"}
               and {k: x for k, x in s.items() if k != "effects"} == {k: x for k, x in ref.items() if k != "effects"}
               and dsc.variant_suffix({"dry_walls": "omit"}) == "_drywalls"
               and dsc.scene(10, 0.5, {"dry_walls": "include"}) == ref, f"dry walls: {s['effects']}")
        # the wetted faces: each die wall's wetted_face, into the die, and nothing else
        s = dsc.scene(10, 0.5, {"wetted_faces": True})
        expect(s["blocks"][1]["wetted_face"] == [0.0, 1.0] and s["blocks"][2]["wetted_face"] == [0.0, -1.0]
               and "wetted_face" not in s["blocks"][0]
               and {k: x for k, x in s.items() if k != "blocks"} == {k: x for k, x in ref.items() if k != "blocks"}
               and dsc.variant_suffix({"wetted_faces": True}) == "_wetted"
               and dsc.scene(10, 0.5, {"wetted_faces": False}) == ref, f"wetted faces: {s['blocks']}")
        expect(dsc.variant_suffix({"wall_floor": None, "xsph": None, "delta": None, "shifting": 0.0,
                                   "sound_speed": None, "integrator": None, "smoothing_ratio": None,
                                   "viscous_form": None, "dry_walls": "include"}) == "", "no variant: no suffix")

    def command():
        rc, out, err = tool("die_swell_study.py", "convergence", "--across", "10", "16", "--re", "0.5",
                            "--xsph", "0", "--end", "0.2", "--dry-run", "--out", d)
        sp = os.path.join(d, "convergence_xsph0", "re0.5_n16", "re0.5_n16.toml")
        expect(rc == 0 and os.path.exists(sp) and out.count(" run ") == 2, f"dry run: exit {rc}", out + err)
        with open(sp, "rb") as fh:
            s = tomllib.load(fh)
        expect(s["time"]["end"] == 0.2 and "xsph" not in s["effects"], f"scene written: {s}")
        for bad in (["--across", "3", "10", "16"], ["--re", "0"], ["--stations", "0.19"],
                    ["--xsph", "2"], ["--across", "10", "10", "16"], ["--smoothing-ratio", "2"],
                    ["--viscous-form", "tensor"], ["--scheme", "isph", "--dry-walls", "omit"]):
            rc, out, err = tool("die_swell_study.py", "convergence", *bad, "--dry-run", "--out", d)
            expect(rc == 2, f"{bad}: exit {rc}", out + err)

    def tabulation():
        # Three synthetic runs (the support's die-swell output: the extrudate 29, 31, 30 rows of
        # 25 over the later half, mean 1.2) tabulate; equal values give "unchanged".
        sd = os.path.join(d, "tab", "convergence")
        for n in (10, 16, 25):
            lab = dsc.label(0.5, n)
            rd = os.path.join(sd, lab)
            os.makedirs(rd, exist_ok=True)
            write_die_swell(os.path.join(rd, lab + ".h5"))
            with open(os.path.join(rd, "summary.json"), "w") as fh:
                json.dump({"status": "ok", "final_time": 0.8, "steps": 800, "wall_seconds": 2.5}, fh)
        rc, out, err = tool("die_swell_study.py", "convergence", "--across", "10", "16", "25", "--re", "0.5",
                            "--measure-only", "--out", os.path.join(d, "tab"), "--no-png")
        expect(rc == 0, f"--measure-only: exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(sd, "convergence.csv"))
        expect(len(rows) == 3 and all(abs(float(r["envelope"]) - 1.2) < 1e-9 for r in rows)
               and all(math.isfinite(float(r["flux"])) for r in rows),
               f"rows {rows}", out)
        rich = read_csv_rows(os.path.join(sd, "convergence_richardson.csv"))
        env = next(r for r in rich if r["measure"] == "envelope")
        expect(env["status"] == "unchanged" and abs(float(env["extrapolated"]) - 1.2) < 1e-9,
               f"richardson {env}", out)
        rc, out, err = tool("die_swell_study.py", "convergence", "--compare", "--re", "0.5",
                            "--out", os.path.join(d, "tab"))
        expect(rc == 0 and out.count("convergence ") == 3 and " 1.200 +-0.033" in out
               and os.path.exists(os.path.join(d, "tab", "convergence_variants.png")),
               f"--compare: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "convergence", "--compare", "--re", "7",
                            "--out", os.path.join(d, "tab"))
        expect(rc == 1 and "no convergence" in out, f"--compare at a Re never run: exit {rc}", out + err)

    return [("die_swell_study convergence: observed order and Richardson value (equal and unequal "
             "ratios, oscillatory, diverging, flagged orders)", richardson),
            ("die_swell_study convergence: scenes (the case at 25 across, Re and c scaling, one change "
             "per variant)", scenes),
            ("die_swell_study convergence: the swell against Re (one row per Re, its figure)", re_sweep),
            ("die_swell_study convergence: the command line (dry run, bad arguments)", command),
            ("die_swell_study convergence: --measure-only tabulation", tabulation)]


def make_peer_dam_break_tests(tmp):
    from vesph.studies import peer_dam_break as pdb

    def integrator_specifications():
        expect(pdb.parse_integrator("leapfrog") == ['integrator.type="leapfrog"'], "plain type")
        expect(pdb.parse_integrator("arkode:BOGACKI_SHAMPINE_4_2_3@1")
               == ['integrator.type="arkode"', 'integrator.table="BOGACKI_SHAMPINE_4_2_3"', "integrator.cfl=1.0"],
               f"type, table and cfl: {pdb.parse_integrator('arkode:BOGACKI_SHAMPINE_4_2_3@1')}")
        expect(pdb.parse_integrator("symplectic@0.25") == ['integrator.type="symplectic"', "integrator.cfl=0.25"],
               "type and cfl")
        for bad in ("arkode:", "symplectic@", "@1", "leapfrog@-1", "leapfrog@x"):
            try:
                pdb.parse_integrator(bad)
            except ValueError:
                continue
            raise AssertionError(f"{bad!r} accepted")
        p = subprocess.run([os.path.join(TOOLS, "vesph-post"), "peer_dam_break", "--integrator", "leapfrog,arkode:",
                            "--size", "ci"], capture_output=True, text=True)
        expect(p.returncode == 2 and "TYPE[:TABLE][@CFL]" in p.stderr,
               f"a malformed --integrator: exit {p.returncode}", p.stdout + p.stderr)

    return [("peer_dam_break: integrator specifications TYPE[:TABLE][@CFL] and their errors",
             integrator_specifications)]


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_die_swell_study_tests, make_die_swell_convergence_tests,
                            make_peer_dam_break_tests)
