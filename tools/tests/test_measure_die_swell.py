"""die_swell_measure and die_swell_lip (vesph.measure.die_swell, .die_swell_lip) on synthetic
planar die-swell outputs."""
import json
import math
import os

import h5py
import numpy as np

from support import (DS_A, DS_B, DS_C, DS_DX, DS_EXIT, DS_SCENE, DS_U, DS_VY, DS_W, ds_frames,
                     expect, expect_unreadable_files_fail, load_tests_of, read_csv_rows, tool,
                     write_die_swell)


def make_die_swell_tests(tmp):
    d = os.path.join(tmp, "die_swell")
    os.makedirs(d, exist_ok=True)
    tol = DS_DX / DS_W                       # 0.04
    ve = write_die_swell(os.path.join(d, "ve.h5"))
    newt = write_die_swell(os.path.join(d, "newt.h5"), stress=False)

    def measure(path, *args, prefix=None):
        prefix = prefix or os.path.splitext(os.path.basename(path))[0]
        rc, out, err = tool("die_swell_measure.py", path, "--out-dir", d, "--prefix", prefix,
                            *args)
        res = {}
        for suf in ("swell.csv", "profiles.csv"):
            fn = os.path.join(d, f"{prefix}_{suf}")
            res[suf] = read_csv_rows(fn) if rc in (0, 1) and os.path.exists(fn) else []
        fn = os.path.join(d, f"{prefix}_summary.json")
        if rc in (0, 1) and os.path.exists(fn):
            with open(fn) as fh:
                res["json"] = json.load(fh)
        return rc, out, err, res

    def swell_ratio_and_steady():
        rc, out, err, res = measure(ve)
        rows = res["swell.csv"]
        expect(rc == 0 and len(rows) == 9, f"exit {rc}, {len(rows)} rows", out + err)
        cols = list(rows[0].keys())
        expect(cols == ["time_s", "ratio_x0.21", "ratio_x0.23", "ratio_x0.25", "ratio_average",
                        "filled_x0.21", "filled_x0.23", "filled_x0.25", "filled_average"],
               f"columns {cols}")
        nan = lambda v: math.isnan(float(v))  # noqa: E731
        expect(all(nan(rows[0][c]) for c in cols[1:]), f"t = 0 should be all NaN: {rows[0]}")
        expect(abs(float(rows[1]["ratio_x0.21"]) - 1.2) <= tol and nan(rows[1]["ratio_x0.23"])
               and nan(rows[1]["ratio_average"]), f"t = 0.1: {rows[1]}")
        expect(abs(float(rows[2]["ratio_x0.23"]) - 1.2) <= tol and nan(rows[2]["ratio_x0.25"])
               and nan(rows[2]["ratio_average"]), f"t = 0.2: {rows[2]}")
        for r, n in zip(rows[3:], (29, 31, 30, 29, 31, 30)):
            for c in cols[1:]:   # compact lattice: the filled width is the envelope's
                expect(abs(float(r[c]) - n * DS_DX / DS_W) <= 1e-9, f"t = {r['time_s']} {c}: "
                       f"{r[c]} != {n * DS_DX / DS_W}")
        js = res["json"]
        a = js["average"]
        expect(js["frames_used"] == 3 and abs(js["time_window_s"][0] - 0.6) < 1e-12
               and abs(js["time_window_s"][1] - 0.8) < 1e-12, f"window {js}")
        expect(abs(a["mean"] - 1.2) < 1e-9 and abs(a["half_range"] - 0.04) < 1e-9
               and abs(a["std"] - 0.04 * math.sqrt(2 / 3)) < 1e-9, f"steady {a}")
        st = js["stations"]
        expect([s["frames_defined"] for s in st] == [8, 7, 6]
               and all(abs(s["mean"] - 1.2) < 1e-9 for s in st), f"stations {st}")
        expect("mean 1.2" in out, "steady mean not printed", out)
        f = js["filled"]
        expect(abs(f["mean"] - 1.2) < 1e-9 and abs(f["std"] - 0.04 * math.sqrt(2 / 3)) < 1e-9
               and all(abs(s["filled_mean"] - 1.2) < 1e-9 for s in st), f"filled {f} {st}")
        # --from: all six full frames; a wider slab sees the same width
        rc, out, err, res = measure(ve, "--from", "0.3", "--window", "3", "--no-png")
        a = res["json"]["average"]
        expect(rc == 0 and res["json"]["frames_used"] == 6 and abs(a["mean"] - 1.2) < 1e-9,
               f"--from 0.3: exit {rc}, {res.get('json')}", out + err)
        # --until: the window's upper end (the frame at 0.3 s alone: 29 rows, 29/25 = 1.16; the
        # default later half, 0.6-0.8 s, cut at 0.7 s: two frames)
        rc, out, err, res = measure(ve, "--from", "0.3", "--until", "0.35", "--no-png")
        js = res.get("json", {})
        expect(rc == 0 and js.get("frames_used") == 1 and abs(js["average"]["mean"] - 1.16) < 1e-9
               and js["time_window_s"] == [0.3, 0.3] and js["until_s"] == 0.35,
               f"--from 0.3 --until 0.35: exit {rc}, {js}", out + err)
        rc, out, err, res = measure(ve, "--until", "0.7", "--no-png")
        expect(rc == 0 and res["json"]["frames_used"] == 2
               and abs(res["json"]["time_window_s"][1] - 0.7) < 1e-12,
               f"--until 0.7: exit {rc}, {res.get('json')}", out + err)
        rc, out, err, res = measure(ve, "--until", "nan", "--no-png")
        expect(rc == 2 and "--until" in err, f"--until nan: exit {rc}", out + err)

    def voids_between_lanes():
        # The extrudate's rows two dx apart (lanes with voids between them): 15 rows span
        # 29 dx, envelope ratio 29/25 = 1.16, filled ratio 15/25 = 0.6.
        lanes = write_die_swell(os.path.join(d, "lanes.h5"), lane=2.0,
                                spec=[(0.0, 0.2, 15), (0.1, 0.26, 15), (0.2, 0.26, 15)])
        rc, out, err, res = measure(lanes, "--no-png")
        r = res["swell.csv"][-1]
        # (at 0.21 m one of the slab's four columns is in the swelling stretch: 16 rows)
        expect(rc == 0 and abs(float(r["ratio_average"]) - 1.16) < 1e-9
               and abs(float(r["filled_x0.23"]) - 0.6) < 1e-9
               and abs(float(r["filled_x0.25"]) - 0.6) < 1e-9
               and abs(float(r["filled_x0.21"]) - 61 / 100) < 1e-9,
               f"lanes: envelope {r.get('ratio_average')}, filled {r}", out + err)
        rc, out, err, res = measure(lanes, "--filled-window", "0", "--no-png")
        expect(rc == 2 and "--filled-window" in err, f"--filled-window 0: exit {rc}", out + err)

    def profiles_with_stress_and_pngs():
        rc, out, err, res = measure(ve, "--expect-min", "1.15", "--expect-max", "1.25")
        prof = res["profiles.csv"]
        expect(rc == 0 and "PASS" in out and len(prof) == 25, f"exit {rc}, {len(prof)} rows",
               out + err)
        expect(list(prof[0].keys()) == ["y_m", "speed_m_s", "Txx_Pa", "Tyy_Pa", "Txy_Pa",
                                        "N1_Pa"], f"columns {list(prof[0].keys())}")
        ys = [float(r["y_m"]) for r in prof]
        expect(ys == sorted(ys) and abs(ys[0] - 0.5 * DS_DX) < 1e-12, f"y {ys[:3]}")
        for r in prof:
            y = float(r["y_m"])
            vx = 4 * DS_U * y * (DS_W - y) / DS_W ** 2
            ref = {"speed_m_s": math.hypot(vx, DS_VY), "Txx_Pa": DS_A * y, "Tyy_Pa": DS_B,
                   "Txy_Pa": DS_C * (y - 0.5 * DS_W), "N1_Pa": DS_A * y - DS_B}
            for k, v in ref.items():
                expect(abs(float(r[k]) - v) <= 1e-9 * max(1.0, abs(v)), f"y = {y}: {k} {r[k]} "
                       f"!= {v}")
        for suf in ("swell", "profiles", "n1"):
            fn = os.path.join(d, f"ve_{suf}.png")
            expect(os.path.exists(fn) and os.path.getsize(fn) > 0, f"no {fn}")
        # --profile-time: the frame nearest 0.14 s is t = 0.1 s (no full extrudate: still fine)
        rc, out, err, res = measure(ve, "--profile-time", "0.14", "--no-png")
        expect(rc == 0 and res["json"]["profile"]["time_s"] == 0.1, f"--profile-time: exit "
               f"{rc} {res.get('json', {}).get('profile')}", out + err)

    def newtonian_velocity_only():
        rc, out, err, res = measure(newt)
        prof = res["profiles.csv"]
        expect(rc == 0 and list(prof[0].keys()) == ["y_m", "speed_m_s"],
               f"exit {rc}, columns {list(prof[0].keys()) if prof else None}", out + err)
        expect("no extra_stress" in out, "the missing stress is not reported", out)
        expect(os.path.getsize(os.path.join(d, "newt_n1.png")) > 0, "no particle picture")
        expect(abs(res["json"]["average"]["mean"] - 1.2) < 1e-9, "Newtonian steady mean")
        # default prefix = scene name, default out-dir = the file's directory
        rc, out, err = tool("die_swell_measure.py", newt, "--no-png")
        expect(rc == 0 and os.path.exists(os.path.join(d, "die_swell_synth_swell.csv"))
               and not os.path.exists(os.path.join(d, "die_swell_synth_swell.png")),
               f"default prefix: exit {rc}", out + err)

    def expect_checks_fail():
        rc, out, err, res = measure(ve, "--no-png", "--expect-min", "1.25")
        expect(rc == 1 and "FAIL" in out and "OUTSIDE" in out
               and res["json"]["checks"][0]["pass"] is False, f"--expect-min 1.25: exit {rc}",
               out + err)
        rc, out, err, _ = measure(ve, "--no-png", "--expect-max", "1.1")
        expect(rc == 1 and "FAIL" in out, f"--expect-max 1.1: exit {rc}", out + err)
        # no frame with a defined average (the extrudate never reaches 0.25 m)
        short = write_die_swell(os.path.join(d, "short.h5"), spec=ds_frames()[:3])
        rc, out, err, res = measure(short, "--no-png", "--expect-min", "1.0")
        expect(rc == 1 and "no frame with a defined average" in out
               and res["json"]["average"]["mean"] is None, f"short run: exit {rc}", out + err)

    def bad_input():
        expect_unreadable_files_fail("die_swell_measure.py", d, {"format": "other"},
                                     prefix="die_swell_measure: error:")
        nof = write_die_swell(os.path.join(d, "noframes.h5"), frames=False)
        rc, out, err = tool("die_swell_measure.py", nof)
        expect(rc == 1 and "no /frames" in err, f"no frames: exit {rc}", out + err)
        d3 = write_die_swell(os.path.join(d, "d3.h5"), dim=3, frames=False)
        rc, out, err = tool("die_swell_measure.py", d3)
        expect(rc == 1 and "2D" in err, f"3D: exit {rc}", out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--stations", "0.19", "0.23")
        expect(rc == 2 and "not beyond the die exit" in err, f"station in die: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--profile-x", "0.22")
        expect(rc == 2 and "not inside the die" in err, f"profile x outside: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--profile-x", "-0.05", "--no-png")
        expect(rc == 1 and "no fluid particle" in err, f"profile x without fluid: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--expect-min", "1.3", "--expect-max",
                            "1.2")
        expect(rc == 2, f"--expect-min > --expect-max: exit {rc}", out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--window", "0")
        expect(rc == 2 and "--window" in err, f"--window 0: exit {rc}", out + err)

    return [("die_swell_measure: swell ratio per station, NaN before arrival, steady stats",
             swell_ratio_and_steady),
            ("die_swell_measure: filled (void-free) width of separated lanes", voids_between_lanes),
            ("die_swell_measure: analytic stress/velocity profiles, PNGs, --profile-time",
             profiles_with_stress_and_pngs),
            ("die_swell_measure: Newtonian run without extra_stress, default prefix",
             newtonian_velocity_only),
            ("die_swell_measure: --expect-min/--expect-max failures", expect_checks_fail),
            ("die_swell_measure: bad input errors and exit codes", bad_input)]


def make_die_swell_lip_tests(tmp):
    d = os.path.join(tmp, "die_swell_lip")
    os.makedirs(d, exist_ok=True)

    def lip_table():
        # The synthetic die swell (25 rows in the die, 30 from 0.21 m on, T_yy = b = 30 Pa) with
        # a pressure falling linearly along the die at 1.5 times plane Poiseuille's gradient for
        # mu = 2 Pa s, U = 0.1 m/s (12 mu U / W^2 = 2.4e4 Pa/m) and p = 0 beyond the exit.
        scene = DS_SCENE + "[fluid]\ndensity = 1000.0\nviscosity = 2.0\n[inflow]\nmean_velocity = 0.1\n"
        h5 = write_die_swell(os.path.join(d, "lip.h5"), scene=scene)
        G = 1.5 * 12 * 2.0 * 0.1 / DS_W ** 2
        with h5py.File(h5, "r+") as f:
            for nm in f["frames"]:
                g = f["frames"][nm]
                x = g["position"][:, 0]
                g["pressure"][...] = np.where(x < DS_EXIT, G * (DS_EXIT - x), 0.0)
                # beyond the exit: the rows move along at 0.08 m/s and away from the centreline
                # at 0.05 m/s, and carry T_xx = -40 Pa
                y = g["position"][:, 1]
                beyond = x >= DS_EXIT
                g["velocity"][beyond, 0] = 0.08
                g["velocity"][beyond, 1] = np.sign(y[beyond] - 0.5 * DS_W) * 0.05
                g["extra_stress"][beyond, 0] = -40.0
        out_csv = os.path.join(d, "lip.csv")
        rc, out, err = tool("die_swell_lip.py", h5, "--frames", "4", "--csv", out_csv)
        expect(rc == 0 and "-3.6e+04 Pa/m" in out and "+50 %" in out,
               f"die gradient: exit {rc}", out + err)
        rows = read_csv_rows(out_csv) if os.path.exists(out_csv) else []
        expect(len(rows) == 13, f"{len(rows)} bands, expected 13 (exit - dx to exit + 2 W by 4 dx)")
        far = [r for r in rows if float(r["x0_m"]) >= 0.21]
        expect(far and all(abs(float(r["count_ratio"]) - 1.2) < 1e-6 for r in far),
               f"count ratio 30/25 beyond 0.21 m: {[r['count_ratio'] for r in far]}")
        expect(all(abs(float(r["T_yy_outer_Pa"]) - 30.0) < 1e-9 and abs(float(r["p_outer_Pa"])) < 1e-9
                   and abs(float(r["balance_outer_Pa"]) - 30.0) < 1e-9 for r in far),
               f"outer rows: p 0, T_yy 30, balance 30: {far[:1]}")
        expect(all(abs(float(r["v_outward_outer_m_s"]) - 0.05) < 1e-12
                   and abs(float(r["T_xx_outer_Pa"]) + 40.0) < 1e-9 for r in far),
               f"outer rows: outward velocity 0.05, T_xx -40: {far[:1]}")
        # momentum flux of 30 rows at u = 0.08 m/s, p = 0, T_xx = -40 Pa: J = 30 dx (rho u^2 + 40),
        # Q = 30 dx rho u; momentum width Q^2 / (rho J) / W = 1.2 rho u^2 / (rho u^2 + 40)
        j_exp = 30 * DS_DX * (1000.0 * 0.08 ** 2 + 40.0)
        w_exp = 1.2 * 6.4 / 46.4
        expect(all(abs(float(r["momentum_flux_N_m"]) - j_exp) < 1e-5 * j_exp     # the CSV's 6 digits
                   and abs(float(r["momentum_width"]) - w_exp) < 1e-5 * w_exp for r in far),
               f"momentum flux {j_exp:.6g} N/m, width {w_exp:.6g}: {[(r['momentum_flux_N_m'], r['momentum_width']) for r in far[:2]]}")
        expect(f"momentum flux {j_exp:.1f} N/m, momentum width {w_exp:.3f} W" in out,
               "the jet's momentum flux and width line", out)
        rc, out, err = tool("die_swell_lip.py", os.path.join(d, "missing.h5"))
        expect(rc == 1 and "die_swell_lip: error" in err, f"missing file: exit {rc}", out + err)
        rc, out, err = tool("die_swell_lip.py", h5, "--frames", "0")
        expect(rc == 2, f"--frames 0: exit {rc}", out + err)

    def lip_labels():
        # Runs of the same name in different study directories keep apart (the plot's curves
        # and the CSV are keyed by the label); the same file twice is numbered.

        from vesph.measure import die_swell_lip as dsl
        got = dsl.run_labels(["out/a/s1/r/r.h5", "out/a/s2/r/r.h5", "out/b/q/q.h5"])
        expect(got == ["s1/r/r", "s2/r/r", "b/q/q"], f"labels {got}, expected one directory more for all")
        got = dsl.run_labels(["x/r/r.h5", "y/q/q.h5"])
        expect(got == ["r/r", "q/q"], f"labels {got}, expected the directory and name only")
        got = dsl.run_labels(["x/r/r.h5", "x/r/r.h5"])
        expect(len(set(got)) == 2 and got[1].endswith("#2"), f"the same file twice: {got}")

    return [("die_swell_lip: die pressure gradient against Poiseuille, bands past the exit", lip_table),
            ("die_swell_lip: run labels tell runs of the same name apart", lip_labels)]


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_die_swell_tests, make_die_swell_lip_tests)
