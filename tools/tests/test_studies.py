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
load_tests = load_tests_of(make_die_swell_study_tests, make_peer_dam_break_tests)
