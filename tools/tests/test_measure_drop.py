"""drop_measure (vesph.measure.drop) on synthetic drop-impact outputs: the measured columns, the
cluster / void / crack / nearest-neighbour indicators, the checks' exit codes and the errors.
The interior summation density uses the kernels of the vesph binary (VESPH)."""
import math
import os
import re
import shutil

import numpy as np

from support import (DROP_DX, Checks, drop_lattice, drop_scene, expect,
                     expect_unreadable_files_fail, load_tests_of, read_csv_rows, tool, write_drop)


def make_drop_tests(tmp):
    T = Checks()
    t = T.add

    d = os.path.join(tmp, "drop")
    os.makedirs(d, exist_ok=True)
    dx = DROP_DX
    disk, K = drop_lattice()                 # R = 10 dx: 317 particles, width 20 dx = D
    N = len(disk)

    def measure(path, *args):
        """Run the tool (no PNG unless "--png" is among args); (rc, out, err, CSV rows)."""
        png = "--png" in args
        args = [x for x in args if x != "--png"] + ([] if png else ["--no-png"])
        rc, out, err = tool("drop_measure.py", path, "--out-dir", d, "--prefix",
                            os.path.splitext(os.path.basename(path))[0], *args)
        csvp = os.path.join(d, os.path.splitext(os.path.basename(path))[0] + "_drop.csv")
        rows = read_csv_rows(csvp) if rc in (0, 1) and os.path.exists(csvp) else []
        return rc, out, err, rows

    def near(v, ref, tol=1e-9):
        return abs(float(v) - ref) <= tol * max(1.0, abs(ref))

    @t
    def drop_lattice_disk_width_height_area():
        # frame 0: the disk; 1: translated down by V t; 2: a flattened blob on the wall, bottom
        # row of 30 particles at 0.6 dx, 5 rows of 40 above (contact 29 dx, width 39 dx)
        blob = [np.column_stack([(np.arange(30) - 14.5) * dx, np.full(30, 0.6 * dx)])]
        for j in range(1, 6):
            blob.append(np.column_stack([(np.arange(40) - 19.5) * dx,
                                         np.full(40, (0.6 + j) * dx)]))
        blob = np.vstack(blob)
        h5 = write_drop(os.path.join(d, "lattice.h5"),
                        [(0.0, disk), (0.003, disk - [0.0, 0.003]), (0.0125, blob)])
        rc, out, err, rows = measure(h5, "--png")
        expect(rc == 0 and len(rows) == 3, f"exit {rc}, {len(rows)} rows", out + err)
        r0, r1, r2 = rows
        for r, tvd in zip(rows, (0.0, 0.15, 0.625)):
            expect(near(r["tV_over_D"], tvd), f"tV/D {r['tV_over_D']} != {tvd}")
        expect(near(r0["width_m"], 0.02) and near(r0["width_over_D"], 1.0), f"width {r0}")
        expect(near(r0["height_m"], 0.025) and near(r0["height_over_D"], 1.25), f"height {r0}")
        expect(near(r1["height_over_D"], 1.1) and near(r1["width_over_D"], 1.0)
               and r1["n_contact"] == "0", f"frame 1 {r1}")
        area = N * dx * dx
        expect(near(r0["volume_m2"], area), f"area {r0['volume_m2']} != {area}")
        expect(near(r0["volume_rel_err_disk"], area / (math.pi * 1e-4) - 1, 1e-7),
               f"error vs the disk {r0['volume_rel_err_disk']}")
        expect(float(r0["volume_rel_err_first"]) == 0.0, "error vs the first frame")
        expect(r0["n_contact"] == "0" and float(r0["contact_width_m"]) == 0.0, "contact at t=0")
        expect(r0["clusters"] == "1" and r0["detached"] == "0" and r0["fractured"] == "0",
               f"clusters {r0}")
        expect(near(r0["max_nn_gap_over_dx"], 1.0) and float(r0["void_gap_over_dx"]) <= 1.5,
               f"gaps {r0}")
        expect(near(r2["width_m"], 39 * dx) and near(r2["contact_width_m"], 29 * dx)
               and r2["n_contact"] == "30", f"blob widths {r2}")
        expect(near(r2["height_m"], 5.6 * dx), f"blob height {r2['height_m']}")
        expect(near(r2["volume_rel_err_first"], 230 / N - 1), "blob volume error")
        expect(os.path.getsize(os.path.join(d, "lattice_drop.png")) > 0, "no PNG")
        expect("first wall contact: t V/D = 0.625" in out, "contact time", out)

    @t
    def drop_bulk_width_leaves_out_stranded_particles():
        # a retracted blob (5 rows of 40) and two particles the rim left behind on the wall at
        # x = -/+30 dx: the width of all fluid reaches them, the bulk width is the blob's
        blob = np.vstack([np.column_stack([(np.arange(40) - 19.5) * dx, np.full(40, (0.6 + j) * dx)])
                          for j in range(5)])
        stranded = np.array([[-30 * dx, 0.6 * dx], [30 * dx, 0.6 * dx]])
        h5 = write_drop(os.path.join(d, "stranded.h5"), [(0.0, disk), (0.01, np.vstack([blob, stranded]))])
        rc, out, err, rows = measure(h5)
        r0, r1 = rows
        expect(rc == 0 and near(r0["bulk_width_m"], float(r0["width_m"])), f"intact disk {r0}", out + err)
        expect(near(r1["width_m"], 60 * dx) and near(r1["bulk_width_m"], 39 * dx)
               and near(r1["bulk_width_over_D"], 39 / 20) and r1["detached"] == "2",
               f"stranded frame {r1}")

    @t
    def drop_3d_spread_retraction_and_release_clock():
        # a 3D sphere (R = 4 dx, D = 8 dx), then a one-layer pancake of radius 8 dx in the x-z
        # plane, then one of radius 6 dx: spread (footprint diameter) 16 dx = 2 D, then 12 dx =
        # 1.5 D, a retraction of 25 %. --time-offset 0.002 s and --speed 2 m/s put the frames at
        # t V/D = (t + 0.002) 2/0.008 = 0.5, 1.5, 2.5.
        sphere, _ = drop_lattice(R=4, centre=(0.0, 0.006, 0.0), dim=3)

        def pancake(R):
            k = np.arange(-R, R + 1)
            I, K = np.meshgrid(k, k, indexing="ij")
            keep = I * I + K * K <= R * R
            return np.column_stack([I[keep] * dx, np.full(keep.sum(), 0.6 * dx), K[keep] * dx])

        h5 = write_drop(os.path.join(d, "spread3d.h5"),
                        [(0.0, sphere), (0.004, pancake(8)), (0.008, pancake(6))], dim=3)
        base = ("--time-offset", "0.002", "--speed", "2")
        rc, out, err, rows = measure(h5, *base, "--min-spread", "1.9", "--expect-retraction", "0.2")
        expect(rc == 0 and len(rows) == 3, f"exit {rc}, {len(rows)} rows", out + err)
        for r, tvd in zip(rows, (0.5, 1.5, 2.5)):
            expect(near(r["tV_over_D"], tvd), f"tV/D {r['tV_over_D']} != {tvd}")
        expect(near(rows[0]["spread_over_D"], 1.0) and near(rows[1]["spread_over_D"], 2.0)
               and near(rows[2]["spread_over_D"], 1.5) and near(rows[1]["spread_m"], 0.016),
               f"spreads {[r['spread_over_D'] for r in rows]}")
        expect("retraction 25 %" in out and "check retraction" in out and "RESULT: PASS" in out,
               "summary", out)
        rc, out, err, _ = measure(h5, *base, "--min-spread", "2.1")
        expect(rc == 1 and "check max spread/D 2 (t V/D = 1.5) >= 2.1: FAIL" in out,
               f"min spread fails: exit {rc}", out + err)
        rc, out, err, _ = measure(h5, *base, "--expect-retraction", "0.3")
        expect(rc == 1 and "RESULT: FAIL" in out, f"retraction 25 % < 30 %: exit {rc}", out + err)
        rc, out, err, _ = measure(h5, "--speed", "0")
        expect(rc == 2 and "--speed must be a positive number" in err, f"bad speed: exit {rc}", err)
        rc, out, err, _ = measure(h5, "--expect-retraction", "1.5")
        expect(rc == 2 and "--expect-retraction must be in (0, 1)" in err, f"exit {rc}", err)

    @t
    def drop_interior_summation_density_sees_compression():
        # the disk squeezed uniformly to 0.99 of its size about its centre, the densities in the
        # file unchanged (as in ISPH): sum m/rho sees nothing, the interior summation density
        # sees the area shrink by 0.99^2 (+2.03 %)
        c = np.array([0.0, 0.015])
        h5 = write_drop(os.path.join(d, "squeezed.h5"), [(0.0, disk), (0.002, c + 0.99 * (disk - c))])
        rc, out, err, rows = measure(h5)
        r0, r1 = rows
        expect(rc == 0 and float(r1["volume_rel_err_first"]) == 0.0, f"sum m/rho {r1}", out + err)
        # full support (3 dx) inside a disk of radius 10 dx: the particles more than about
        # 2.25 dx inside the outer row (the open region begins 0.75 dx beyond it), radius ~7.5 dx
        expect(0.4 * N < int(r0["n_interior"]) < 0.7 * N, f"interior particles {r0['n_interior']} of {N}")
        expect(float(r0["interior_density_rel_err"]) == 0.0, "first frame")
        e = float(r1["interior_density_rel_err"])
        expect(abs(e - (1 / 0.99 ** 2 - 1)) < 2e-3, f"interior density error {e}, expected 0.0203")
        expect("interior summation density vs the first frame" in out, "summary line", out)

    @t
    def drop_pictures_of_chosen_frames():
        h5 = write_drop(os.path.join(d, "pics.h5"), [(0.0, disk), (0.003, disk - [0.0, 0.003])])
        png = os.path.join(d, "pics_frames.png")
        rc, out, err, rows = measure(h5, "--pictures", "0,0.14")
        expect(rc == 0 and os.path.getsize(png) > 0 and png in out, f"exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", h5, "--no-png", "--pictures", "soon")
        expect(rc == 2 and "--pictures" in err and "numbers" in err, f"--pictures soon: exit {rc}", err)
        rc, out, err = tool("drop_measure.py", h5, "--no-png", "--pictures", "-1")
        expect(rc == 2 and ">= 0" in err, f"--pictures -1: exit {rc}", err)

    @t
    def drop_split_disk_two_clusters():
        half = disk[np.abs(K[:, 0]) > 1]            # columns -1, 0, 1 removed: gap 4 dx
        h5 = write_drop(os.path.join(d, "split.h5"), [(0.0, disk), (0.01, half)])
        rc, out, err, rows = measure(h5)
        r = rows[1]
        expect(r["clusters"] == "2" and r["fragments"] == "2" and r["detached"] == "0"
               and r["fractured"] == "1", f"split frame {r}", out + err)
        expect(near(r["largest_cluster_fraction"], 0.5), f"largest {r['largest_cluster_fraction']}")
        expect(rows[0]["clusters"] == "1", "intact frame")
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1 and "2 fragments" in out and "RESULT: FAIL" in out, f"exit {rc}", out + err)
        rc, out, err, _ = measure(h5, "--expect-fracture")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        # a link longer than the gap joins the halves again
        rc, out, err, rows = measure(h5, "--link", "4.5", "--max-gap", "10")
        expect(rows[1]["clusters"] == "1", f"link 4.5: {rows[1]['clusters']} clusters")

    @t
    def drop_hole_void_gap():
        holed = disk[np.sum(K * K, axis=1) > 16]    # hole of radius 4 dx
        one = disk[np.any(K != 0, axis=1)]          # one missing particle
        h5 = write_drop(os.path.join(d, "hole.h5"), [(0.0, disk), (0.005, one), (0.01, holed)])
        rc, out, err, rows = measure(h5)
        r1, r2 = rows[1], rows[2]
        # the nearest particle to the centre is at sqrt(17) dx: empty circle 2 sqrt(17) dx
        expect(abs(float(r2["void_gap_over_dx"]) - 2 * math.sqrt(17)) < 0.3,
               f"void {r2['void_gap_over_dx']} != {2 * math.sqrt(17):.3f}", out)
        expect(r2["clusters"] == "1" and r2["fractured"] == "1", f"hole frame {r2}")
        expect(near(r2["max_nn_gap_over_dx"], 1.0), "a clean hole leaves the NN gap at 1")
        expect(abs(float(r1["void_gap_over_dx"]) - 2.0) < 0.1 and r1["fractured"] == "0",
               f"one missing particle: {r1}")
        # void fraction: 0 intact; the hole (49 particles removed, 49 dx^2) less a rim of
        # about 0.75 dx: ~ pi 3.4^2 dx^2 of the first frame's N dx^2
        vf = float(r2["void_fraction"])
        expect(float(rows[0]["void_fraction"]) == 0.0 and 30 / N < vf < 49 / N,
               f"void fraction {vf * N:.1f} dx^2 not in (30, 49)")
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1 and "void gap" in out, f"exit {rc}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--max-gap", "9")
        expect(rc == 0, f"--max-gap 9: exit {rc}", out + err)
        expect(float(r2["crack_fraction"]) == float(rows[0]["crack_fraction"]),
               "an enclosed hole is no crack")

    @t
    def drop_open_crack_crack_fraction():
        # a slot 3 columns wide from the top down to row -6: open to the outside, so no
        # cluster split and no enclosed void; the closing (radius 3 dx) fills about
        # 2.5 dx x 17 dx + the mouth ~ 47 dx^2, 15 % of the disk (the intact disk: 3 %)
        slot = disk[~((np.abs(K[:, 0]) <= 1) & (K[:, 1] >= -6))]
        h5 = write_drop(os.path.join(d, "slot.h5"), [(0.0, disk), (0.01, slot)])
        rc, out, err, rows = measure(h5, "--no-fracture")
        r0, r1 = rows
        c0, c1 = float(r0["crack_fraction"]), float(r1["crack_fraction"])
        expect(0.02 < c0 < 0.04 and r0["fractured"] == "0", f"intact disk: crack {c0}", out)
        expect(0.12 < c1 < 0.18 and r1["clusters"] == "1"
               and float(r1["void_gap_over_dx"]) <= 1.5 and r1["fractured"] == "1",
               f"slot: {r1}", out)
        expect(rc == 1 and "crack fraction" in out, f"--no-fracture: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--no-fracture", "--max-crack", "0.2")
        expect(rc == 0, f"--max-crack 0.2: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--crack-radius", "1")
        expect(float(rows[1]["crack_fraction"]) < 0.5 * c1,
               f"a 1 dx closing does not fill the 2.5 dx slot: {rows[1]['crack_fraction']}")

    @t
    def drop_detached_particles():
        singles = np.array([[0.040, 0.003], [0.045, 0.003], [0.052, 0.003]])   # NN 5, 5, 7 dx
        pair = np.array([[-0.040, 0.003], [-0.039, 0.003]])                    # a 2-particle drop
        h5 = write_drop(os.path.join(d, "detached.h5"),
                        [(0.0, disk), (0.01, np.vstack([disk, singles])),
                         (0.02, np.vstack([disk, singles, pair]))])
        rc, out, err, rows = measure(h5)
        r1, r2 = rows[1], rows[2]
        expect(r1["clusters"] == "1" and r1["detached"] == "3" and r1["fractured"] == "0",
               f"singles: {r1}", out + err)
        expect(near(r1["largest_cluster_fraction"], N / (N + 3)), "largest fraction")
        expect(near(r1["max_nn_gap_over_dx"], 7.0), f"NN gap {r1['max_nn_gap_over_dx']}")
        # the 2-particle drop is a cluster, but no fragment (< 1 % of the particles): a
        # droplet off the rim is no fracture; with --min-fragment 0 every cluster counts
        expect(r2["clusters"] == "2" and r2["fragments"] == "1" and r2["detached"] == "3"
               and r2["fractured"] == "0", f"the 2-particle drop is a cluster: {r2}")
        rc, out, err, rows = measure(h5, "--min-fragment", "0")
        expect(rows[2]["fragments"] == "2" and rows[2]["fractured"] == "1",
               f"--min-fragment 0: {rows[2]}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--until", "0.75")
        expect(rc == 0, f"detached particles alone are no fracture: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--min-cluster", "3", "--no-fracture")
        r2 = rows[2]
        expect(rc == 0 and r2["clusters"] == "1" and r2["detached"] == "5"
               and r2["fractured"] == "0", f"--min-cluster 3: exit {rc}, {r2}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--until", "0.75", "--max-nn-gap", "3")
        expect(rc == 1 and "NN gap 7" in out, f"--max-nn-gap: exit {rc}", out + err)

    @t
    def drop_volume_error_and_until():
        split = disk[np.abs(K[:, 0]) > 1]
        h5 = write_drop(os.path.join(d, "volume.h5"),
                        [(0.0, disk), (0.01, disk, 1 / 1.02), (0.02, split)])
        rc, out, err, rows = measure(h5)
        expect(near(rows[1]["volume_rel_err_first"], 0.02, 1e-9),
               f"volume error {rows[1]['volume_rel_err_first']}", out)
        rc, out, err, _ = measure(h5, "--max-volume-error", "0.01", "--until", "0.5")
        expect(rc == 1 and re.search(r"max 2 % at t V/D = 0\.5 .*FAIL", out) is not None,
               f"exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--max-volume-error", "0.03", "--no-fracture",
                                     "--until", "0.75")
        expect(rc == 0 and len(rows) == 2, f"--until 0.75: exit {rc}, {len(rows)} rows",
               out + err)
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1, f"the split at t V/D = 1 is checked without --until: exit {rc}", out)
        rc, out, err, _ = measure(h5, "--expect-fracture", "--until", "0.75")
        expect(rc == 1 and "no fractured frame" in out, f"exit {rc}", out + err)

    @t
    def drop_sphere_3d():
        ball, _ = drop_lattice(R=4, centre=(0.0, 0.006, 0.0), dim=3)
        h5 = write_drop(os.path.join(d, "ball.h5"), [(0.0, ball)],
                        scene=drop_scene("ball", dim=3), dim=3)
        # the staircase of a sphere of 8 dx fills 12 % under the crack closing
        rc, out, err, rows = measure(h5, "--max-crack", "0.2")
        r = rows[0]
        expect(rc == 0 and near(r["width_over_D"], 1.0) and near(r["height_m"], 0.010),
               f"3D: {r}", out + err)
        vol = len(ball) * dx ** 3
        expect(near(r["volume_m3"], vol)
               and near(r["volume_rel_err_disk"], vol / (math.pi * 0.008 ** 3 / 6) - 1, 1e-7),
               f"3D volume {r}")
        expect(r["clusters"] == "1" and r["fractured"] == "0", f"3D clusters {r}")
        # the cube centres of an intact lattice (sqrt(3)/2 dx from the particles) are no void
        expect(float(r["void_fraction"]) == 0.0 and float(r["void_gap_over_dx"]) < 1.9,
               f"3D void {r['void_gap_over_dx']}, fraction {r['void_fraction']}")

    @t
    def drop_compare_several_runs():
        a = write_drop(os.path.join(d, "run_a.h5"), [(0.0, disk), (0.01, disk - [0, 0.01])],
                       scene=drop_scene("drop_alpha"))
        b = write_drop(os.path.join(d, "run_b.h5"),
                       [(0.0, disk), (0.01, disk[np.abs(K[:, 0]) > 1])],
                       scene=drop_scene("drop_beta"))
        cd = os.path.join(d, "cmp")
        rc, out, err = tool("drop_measure.py", a, "--compare", b, "--out-dir", cd, "--no-fracture")
        expect(rc == 1 and "drop_alpha" in out and "drop_beta" in out, f"exit {rc}", out + err)
        for f_ in ("drop_alpha_drop.csv", "drop_beta_drop.csv", "compare_drop.png"):
            expect(os.path.getsize(os.path.join(cd, f_)) > 0, f"no {f_}")
        expect(len(read_csv_rows(os.path.join(cd, "drop_beta_drop.csv"))) == 2, "beta rows")
        # the same scene name twice: the directory name is appended, then _2
        os.makedirs(os.path.join(d, "eps0"), exist_ok=True)
        a2 = shutil.copy(a, os.path.join(d, "eps0", "run_a.h5"))
        rc, out, err = tool("drop_measure.py", a, a2, a, "--out-dir", cd, "--prefix", "same")
        for f_ in ("drop_alpha_drop_drop.csv", "drop_alpha_eps0_drop.csv",
                   "drop_alpha_drop_2_drop.csv", "same_drop.png"):
            expect(rc == 0 and os.path.exists(os.path.join(cd, f_)), f"exit {rc}, no {f_}",
                   out + err)

    @t
    def drop_errors():
        expect_unreadable_files_fail("drop_measure.py", d, {"dim": 2})
        box = write_drop(os.path.join(d, "box.h5"), [(0.0, disk)], scene=drop_scene(shape="box"))
        rc, out, err = tool("drop_measure.py", box)
        expect(rc == 1 and "no disk fluid block" in err, f"box: exit {rc}", out + err)
        nowall = write_drop(os.path.join(d, "nowall.h5"), [(0.0, disk)],
                            scene=drop_scene(wall=False))
        rc, out, err = tool("drop_measure.py", nowall, "--no-png")
        expect(rc == 1 and "--wall-y" in err, f"no wall: exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", nowall, "--no-png", "--wall-y", "0.005")
        expect(rc == 0, f"--wall-y: exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(d, "drop_synth_drop.csv"))
        expect(near(rows[0]["height_m"], 0.02), f"--wall-y height {rows[0]['height_m']}")
        rc, out, err = tool("drop_measure.py")
        expect(rc == 2, f"no file: exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", box, "--no-fracture", "--expect-fracture")
        expect(rc == 2, f"exclusive checks: exit {rc}", out + err)

    return T


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_drop_tests)
