"""startup_channel_profiles (vesph.measure.channel_profiles) on synthetic periodic channels with
known fields: profiles at stations, the centreline history, row clustering, the nearest-frame
rule, the errors and exit codes."""
import os
import re

import h5py
import numpy as np

from support import (DX, H, SU_A, SU_C, SU_NX, SU_TIMES, SU_UC, Checks, expect, load_tests_of,
                     read_csv_rows, su_expected_profile, tool, write_startup_case)
from vesph.measure.channel_profiles import cluster_rows


def make_profiles_tests(tmp):
    T = Checks()
    t = T.add

    # ---- startup_channel_profiles
    def prof(h5, *args, png=False):
        od = os.path.join(tmp, "prof_out")
        extra = () if png else ("--no-png",)
        rc, out, err = tool("startup_channel_profiles.py", h5, "--out-dir", od, *extra, *args)
        return rc, out, err, od

    def close(a, b, scale, what):
        expect(abs(float(a) - float(b)) <= 1e-12 * scale, f"{what}: {a} != {b}")

    SCALES = {"vx": SU_UC, "txx": SU_A, "txy": SU_C, "tyy": 1e-8, "n1": SU_A, "y": H}
    CSVCOL = {"vx": "vx_m_s", "txx": "Txx_Pa", "txy": "Txy_Pa", "tyy": "Tyy_Pa",
              "n1": "N1_Pa", "y": "y_m"}

    def check_profile(rows, info, frame, station, cols, stress=True, label=""):
        sel = [r for r in rows if abs(float(r["station_x_m"]) - station) < 1e-15
               and float(r["time_s"]) == SU_TIMES[frame]]
        expect(len(sel) == info["ny"], f"{label}: {len(sel)} rows at x = {station}, "
               f"t = {SU_TIMES[frame]}, expected {info['ny']}")
        expect(all(r["frame"] == f"{frame:06d}" for r in sel), f"{label}: frame column")
        ref = su_expected_profile(info, frame, cols)
        sel.sort(key=lambda r: float(r["y_m"]))
        for j, (r, e) in enumerate(zip(sel, ref)):
            expect(int(r["count"]) == e["count"],
                   f"{label}: row {j} count {r['count']}, expected {e['count']}")
            for k in (("y", "vx", "txx", "txy", "tyy", "n1") if stress else ("y", "vx")):
                close(r[CSVCOL[k]], e[k], SCALES[k], f"{label}: row {j} {k}")
            close(r["Y"], (e["y"] - info["yc"]) / info["a"], 1.0, f"{label}: row {j} Y")

    def check_centreline(csv_path, info, centre_rows, stress=True):
        rows = read_csv_rows(csv_path)
        expect(len(rows) == len(SU_TIMES), f"{len(rows)} centreline rows")
        for i, r in enumerate(rows):
            t, x, y, vx, txx, txy, tyy, row, col = info["frames"][i]
            m = np.isin(row, centre_rows)
            expect(float(r["time_s"]) == SU_TIMES[i] and int(r["step"]) == 10 * i,
                   f"centreline time/step {r}")
            expect(int(r["n_centre"]) == int(m.sum()),
                   f"frame {i}: n_centre {r['n_centre']}, expected {int(m.sum())}")
            close(r["vx_centre_m_s"], vx[m].mean(), SU_UC, f"frame {i} centreline v_x")
            if stress:
                close(r["max_abs_Txy_Pa"], np.max(np.abs(txy)), SU_C, f"frame {i} max|Txy|")
                close(r["max_N1_Pa"], np.max(txx - tyy), SU_A, f"frame {i} max N1")
            else:
                expect("max_N1_Pa" not in r, "stress column without extra_stress")

    h5_su, info_su = write_startup_case(os.path.join(tmp, "su"))

    @t
    def profiles_cluster_rows_unit():
        rng = np.random.default_rng(3)
        rows = np.repeat(np.arange(10), 7)
        y = (rows + 0.5) * DX + 0.2 * DX * rng.uniform(-1, 1, len(rows))
        perm = rng.permutation(len(y))
        lab, n, method = cluster_rows(y[perm], DX, 0.0)
        expect(n == 10 and method == "clustered", f"{n} rows, {method}")
        expect(np.array_equal(lab, rows[perm]), "row labels wrong")
        y2 = (rows + 0.5) * DX + 0.45 * DX * rng.uniform(-1, 1, len(rows))
        lab, n, method = cluster_rows(y2, DX, 0.0)
        expect(method.startswith("lattice bins") and n == 10, f"{n} rows, {method}")
        expect(np.array_equal(lab, rows), "fallback row labels wrong")
        # a row shifted by more than dx/2 from the lattice is still one cluster
        lab, n, method = cluster_rows(rows * DX + 0.7 * DX, DX, 0.0)
        expect(n == 10 and method == "clustered", f"shifted: {n} rows, {method}")

    @t
    def profiles_exact_default_station_and_time():
        rc, out, err, od = prof(h5_su)
        expect(rc == 0, f"exit {rc}", out + err)
        for needle in ("rows: clustered in 5 frame(s)", "extra_stress present",
                       "model: oldroyd_b", "y_c = 0.0005 m, a = 0.0005 m", "(periodic)"):
            expect(needle in out, f"{needle!r} missing", out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(list(rows[0].keys()) == ["station_x_m", "time_s", "frame", "y_m", "Y",
                                        "vx_m_s", "Txx_Pa", "Txy_Pa", "Tyy_Pa", "N1_Pa",
                                        "count"], f"header {list(rows[0].keys())}")
        expect(len(rows) == 40, f"{len(rows)} rows: default = one station, last frame")
        # middle x = 10 dx lies half-way between lattice columns 9 and 10
        check_profile(rows, info_su, 4, 10 * DX, [9, 10], label="default")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info_su, [19, 20])

    @t
    def profiles_stations_bins_periodic_times():
        rc, out, err, od = prof(h5_su, "--stations", f"0,{3.5 * DX!r}", "--times", "0.1,0.26")
        expect(rc == 0, f"exit {rc}", out + err)
        expect("time 0.26 s: nearest frame 000003 at t = 0.3 s" in out, "nearest-frame note",
               out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(len(rows) == 2 * 2 * 40, f"{len(rows)} rows")
        for fr in (1, 3):
            check_profile(rows, info_su, fr, 0.0, [0, SU_NX - 1], label="x=0 periodic")
            check_profile(rows, info_su, fr, 3.5 * DX, [3], label="x=3.5dx")
        rc, out, err, od = prof(h5_su, "--stations", f"0,{3.5 * DX!r}", "--times", "0.2",
                                "--bin-width", repr(3 * DX))
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        check_profile(rows, info_su, 2, 0.0, [18, 19, 0, 1], label="x=0 bin 3dx")
        check_profile(rows, info_su, 2, 3.5 * DX, [2, 3, 4], label="x=3.5dx bin 3dx")
        rc, out, err, od = prof(h5_su, "--all-times", "--prefix", "every")
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(od, "every_profiles.csv"))
        expect(len(rows) == 5 * 40, f"--all-times: {len(rows)} rows")
        for fr in range(5):
            check_profile(rows, info_su, fr, 10 * DX, [9, 10], label=f"all-times {fr}")

    @t
    def profiles_odd_rows_centre_row_only():
        h5, info = write_startup_case(os.path.join(tmp, "su_odd"), ny=39)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19])
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="odd")

    @t
    def profiles_disordered_rows_fall_back_to_lattice_bins():
        h5, info = write_startup_case(os.path.join(tmp, "su_dis"), jitter=0.45)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("rows: lattice bins (rows too disordered to cluster) in 5 frame(s)" in out,
               "fallback not reported", out)
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="disordered")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20])

    @t
    def profiles_newtonian_velocity_only():
        h5, info = write_startup_case(os.path.join(tmp, "su_newt"), stress=False)
        rc, out, err, od = prof(h5, png=True)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("no extra_stress in the frames" in out and "Newtonian" in out,
               "missing-stress note", out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(list(rows[0].keys()) == ["station_x_m", "time_s", "frame", "y_m", "Y", "vx_m_s",
                                        "count"], f"header {list(rows[0].keys())}")
        check_profile(rows, info, 4, 10 * DX, [9, 10], stress=False, label="newtonian")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20],
                         stress=False)
        for f in ("startup_synth_centreline.png", "startup_synth_profiles.png"):
            with open(os.path.join(od, f), "rb") as fh:
                expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", f"{f} not written")

    @t
    def profiles_3d_stress_components():
        h5, info = write_startup_case(os.path.join(tmp, "su_3d"), dim=3)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="3d")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20])

    @t
    def profiles_png_and_summary():
        od = os.path.join(tmp, "prof_png")
        rc, out, err = tool("startup_channel_profiles.py", h5_su, "--out-dir", od,
                            "--prefix", "run1", "--times", "0.1,0.4", "--stations",
                            f"{2.5 * DX!r},{10 * DX!r}")
        expect(rc == 0, f"exit {rc}", out + err)
        for f in ("run1_centreline.csv", "run1_profiles.csv", "run1_centreline.png",
                  "run1_profiles.png"):
            expect(f"wrote {os.path.join(od, f)}" in out, f"{f} not reported", out)
            expect(os.path.getsize(os.path.join(od, f)) > 0, f"{f} empty")
        # summary: one line per station and time with rows, particles and counts
        expect(re.search(r"\n\s+6\.25e-05\s+0\.1\s+000001\s+40\s+40\s+1\s", out),
               "summary line for x = 2.5 dx, t = 0.1", out)
        expect(re.search(r"\n\s+0\.00025\s+0\.4\s+000004\s+40\s+80\s+2\s", out),
               "summary line for x = 10 dx, t = 0.4", out)

    @t
    def profiles_errors():
        def bad(args, rc_expected, needle):
            rc, out, err = tool("startup_channel_profiles.py", *args, "--out-dir",
                                os.path.join(tmp, "prof_err"), "--no-png")
            expect(rc == rc_expected, f"{args}: exit {rc}, expected {rc_expected}", out + err)
            expect(needle in err, f"{args}: message {needle!r} missing", out + err)

        bad([os.path.join(tmp, "nonexistent.h5")], 1, "no such file")
        txt = os.path.join(tmp, "not_hdf5.h5")
        with open(txt, "w") as fh:
            fh.write("hello\n")
        bad([txt], 1, "is not an HDF5 file")
        other = os.path.join(tmp, "other.h5")
        with h5py.File(other, "w") as f:
            f["data"] = np.zeros(3)
        bad([other], 1, "is not a vesph output: root attribute 'format' is missing")
        h5, _ = write_startup_case(os.path.join(tmp, "su_nofluid"), no_fluid=True)
        bad([h5], 1, "has no fluid particles")
        bad([h5_su, "--stations", repr(30 * DX)], 2,
            "station x = 0.00075 m is outside the channel, x in [0, 0.0005] m")
        bad([h5_su, "--stations=-1e-5"], 2, "is outside the channel")
        bad([h5_su, "--times", "0.5"], 2, "time 0.5 s is outside the output range [0, 0.4] s")
        bad([h5_su, "--stations", "a,b"], 2, "expected comma-separated numbers")
        bad([h5_su, "--times", "0.1", "--all-times"], 2, "not allowed with argument")
        bad([h5_su, "--bin-width", "0"], 2, "--bin-width must be > 0")
    return T


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_profiles_tests)
