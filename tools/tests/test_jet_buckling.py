"""jet_buckling_measure (vesph.measure.jet_buckling) on synthetic jet-buckling outputs: a straight
jet on a mound (no buckling), a lopsided mound under a straight jet (no buckling), a jet whose
lower part coils (the onset, the coiling and oscillation frequencies), a jet folding in a
plane, a void inside the mound, the checks' exit codes and the errors."""
import csv
import math
import os
import subprocess

import numpy as np

from support import PY, Checks, expect, load_tests_of
from vesph import tool_environment

import h5py

DX = 5.0e-4          # m
D = 4.0e-3           # the nozzle's diameter, 8 dx
H = 40.0e-3          # the nozzle's height above the plate (y = 0), H/D = 10
U = 0.5              # m/s
RHO = 1000.0

SCENE = """\
name = "{name}"
dimension = {dim}
[domain]
min = [-12.0e-3, -1.5e-3, -12.0e-3]
max = [12.0e-3, 41.5e-3, 12.0e-3]
[particles]
spacing = 5.0e-4
kernel = "wendland_c2"
smoothing_ratio = 1.3
[fluid]
density = 1000.0
viscosity = 4.0
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [0.0, 22.0e-3, 0.0]
axis = [0.0, 1.0, 0.0]
diameter = 4.0e-3
length = 36.0e-3
[[blocks]]
kind = "wall"
min = [-12.0e-3, -1.5e-3, -12.0e-3]
max = [12.0e-3, 0.0, 12.0e-3]
{inflow}"""

INFLOW = """\
[inflow]
min = [-2.0e-3, 40.0e-3, -2.0e-3]
max = [2.0e-3, 41.5e-3, 2.0e-3]
{radius}
direction = [0.0, -1.0, 0.0]
profile = "uniform"
mean_velocity = 0.5
"""


def disc(radius):
    """Lattice offsets (x, z) within radius of the axis (R = 4 dx: 49 points)."""
    n = int(radius / DX) + 1
    i, j = np.meshgrid(np.arange(-n, n + 1), np.arange(-n, n + 1), indexing="ij")
    keep = (i * i + j * j) * DX * DX <= radius * radius * (1 + 1e-9)
    return np.column_stack([i[keep] * DX, j[keep] * DX])


def column(offset, radius, y0, y1):
    """A vertical column of lattice discs of radius about (x, z) = offset, its slabs from y0 to y1
    (slab centres (k + 1/2) dx)."""
    xz = disc(radius) + np.asarray(offset, dtype=float)
    ys = y0 + (np.arange(int(round((y1 - y0) / DX))) + 0.5) * DX
    return np.column_stack([np.repeat(xz[:, 0][None, :], len(ys), 0).ravel(),
                            np.repeat(ys, len(xz)),
                            np.repeat(xz[:, 1][None, :], len(ys), 0).ravel()])


def jet(pile, band_offset, hole=False, mound_offset=(0.0, 0.0)):
    """A mound of radius 2.5 R up to y = pile, the jet's lower 2 D displaced by band_offset
    (x, z), the rest of the jet up to the nozzle on the axis. hole: an empty ball of radius
    2 dx removed from the mound's middle; mound_offset: the mound's axis (x, z)."""
    R = 0.5 * D
    parts = []
    if pile > 0:
        mound = column(mound_offset, 2.5 * R, 0.0, pile)
        if hole:
            c = np.array([0.0, 0.5 * pile, 0.0])
            mound = mound[np.linalg.norm(mound - c, axis=1) > 2.0 * DX]
        parts.append(mound)
    top = pile + 2 * D
    parts.append(column(band_offset, R, pile, top))
    parts.append(column((0.0, 0.0), R, top, H))
    return np.vstack(parts)


def write_jet(path, frames, name="jet_synth", dim=3, radius=True, nozzle=True):
    """frames: list of (time [s], fluid positions [n, 3]) or (time, positions, fluid ids [n]:
    default 0 .. n-1); the plate: one row of wall particles at y = -dx/2 (ids from 10^6)."""
    wx = (np.arange(-16, 16) + 0.5) * DX
    X, Z = np.meshgrid(wx, wx)
    wall = np.column_stack([X.ravel(), np.full(X.size, -0.5 * DX), Z.ravel()])
    inflow = INFLOW.format(radius="radius = 2.0e-3" if radius else "profile_axis = 0") if nozzle else ""
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(dim)
        f.attrs["scene"] = SCENE.format(name=name, dim=dim, inflow=inflow)
        f.attrs["dx"] = np.float64(DX)
        for i, (t, fl, *ids) in enumerate(frames):
            n, nw = len(fl), len(wall)
            fluid_ids = np.asarray(ids[0], dtype=np.uint64) if ids else np.arange(n, dtype=np.uint64)
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(t)
            g.attrs["step"] = np.int64(10 * i)
            g.create_dataset("position", data=np.vstack([fl, wall]))
            g.create_dataset("velocity", data=np.zeros((n + nw, 3)))
            g.create_dataset("kind", data=np.concatenate([np.zeros(n, np.uint8), np.ones(nw, np.uint8)]))
            g.create_dataset("id", data=np.concatenate([fluid_ids, 10 ** 6 + np.arange(nw, dtype=np.uint64)]))
            g.create_dataset("density", data=np.full(n + nw, RHO))
            g.create_dataset("mass", data=np.full(n + nw, RHO * DX ** 3))
    return path


def measure(path, *args):
    p = subprocess.run([PY, "-m", "vesph", "jet_buckling_measure", path, *map(str, args)],
                       capture_output=True, text=True, env=tool_environment())
    return p.returncode, p.stdout, p.stderr


def rows_of(csv_path):
    with open(csv_path) as fh:
        return list(csv.DictReader(fh))


def make_jet_tests(tmp):
    T = Checks()
    t = T.add
    times = [0.005 * k for k in range(41)]          # 0 ... 0.2 s
    f_coil = 10.0                                    # Hz: 18 degrees a frame
    t_on = 0.05

    @t
    def straight_jet_on_a_mound_does_not_buckle():
        h5 = write_jet(os.path.join(tmp, "straight.h5"),
                       [(tt, jet(2 * D if tt > 0 else 0.0, (0.0, 0.0))) for tt in times[:5]])
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "straight", "--expect-no-buckling",
                               "--max-void-gap", "2.5")
        expect(rc == 0 and "RESULT: PASS" in out and "onset: none" in out, f"exit {rc}", out + err)
        rows = rows_of(os.path.join(tmp, "straight_jet.csv"))
        expect(len(rows) == 5, f"{len(rows)} rows")
        expect(float(rows[0]["pile_height_over_D"]) == 0.0, f"pile at t = 0: {rows[0]}")
        expect(abs(float(rows[1]["pile_height_over_D"]) - 2.0) < 1e-9, f"pile {rows[1]}")
        expect(all(float(r["indicator_over_D"]) < 1e-9 for r in rows), "indicator of a straight jet")
        expect(abs(float(rows[1]["tU_over_D"]) - 0.005 * U / D) < 1e-12, "t U/D")
        expect(all(r["buckled"] == "0" and int(r["isolated"]) == 0 for r in rows), "flags")
        expect(all(float(r["void_gap_over_dx"]) <= 1.8 for r in rows), "void gap of a lattice")
        expect("H/D = 10" in out and "Re = U D/nu = 0.5" in out, "header", out)
        for png in ("straight_jet.png", "straight_jet_views.png"):
            expect(os.path.getsize(os.path.join(tmp, png)) > 0, f"no {png}")
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "straight", "--expect-buckling", "--no-png")
        expect(rc == 1 and "CHECK FAILED: --expect-buckling" in out and "RESULT: FAIL" in out,
               f"--expect-buckling on a straight jet: exit {rc}", out + err)

    @t
    def lopsided_mound_under_a_straight_jet_is_not_buckling():
        # the mound 0.6 D off the axis (spread unevenly), the column above it straight
        h5 = write_jet(os.path.join(tmp, "lopsided.h5"),
                       [(0.0, jet(2 * D, (0.0, 0.0))), (0.005, jet(2 * D, (0.0, 0.0), mound_offset=(0.6 * D, 0.0)))])
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "lopsided", "--no-png", "--no-voids",
                               "--expect-no-buckling")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        r = rows_of(os.path.join(tmp, "lopsided_jet.csv"))[1]
        expect(float(r["indicator_over_D"]) < 1e-9, f"indicator {r['indicator_over_D']}")
        expect(abs(float(r["largest_offset_with_pile_over_D"]) - 0.6) < 1e-9, f"with the pile {r}")

    def coil(tt):
        if tt < t_on - 1e-12:
            return (0.0, 0.0)
        ph = 2 * math.pi * f_coil * tt
        return (0.5 * D * math.cos(ph), 0.5 * D * math.sin(ph))

    @t
    def coiling_jet_onset_and_frequency():
        h5 = write_jet(os.path.join(tmp, "coil.h5"), [(tt, jet(2 * D, coil(tt))) for tt in times])
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "coil", "--expect-buckling", "--no-voids",
                               "--pictures", "0,0.1,0.2")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        expect("onset: t = 0.05 s (t U/D = 6.25)" in out, "onset", out)
        rows = rows_of(os.path.join(tmp, "coil_jet.csv"))
        r = rows[20]                                     # t = 0.1 s: phase 2 pi
        expect(abs(float(r["indicator_over_D"]) - 0.5) < 1e-9 and abs(float(r["band_offset_over_D"]) - 0.5) < 1e-9,
               f"offset {r}")
        expect(abs(float(r["band_angle_deg"])) < 1e-6 or abs(abs(float(r["band_angle_deg"])) - 360) < 1e-6,
               f"angle {r['band_angle_deg']}")
        # atan2(z, x): a quarter period later +90 degrees
        expect(abs(float(rows[25]["band_angle_deg"]) - 90.0) < 1e-6, f"angle {rows[25]['band_angle_deg']}")
        expect(2.0 <= float(r["indicator_height_over_D"]) <= 4.0, "indicator height in the band")
        # 0.15 s after the onset at 10 Hz: 1.5 turns, the slope 10 Hz (f D/U = 0.08)
        expect("coiling: +1.50 turns" in out and "frequency 10 Hz (f D/U = 0.08)" in out, "coiling", out)
        m = [ln for ln in out.splitlines() if ln.startswith("oscillation")]
        hz = float(m[0].split(":")[1].split()[0])
        expect(abs(hz - 10.0) < 1.0, f"oscillation {hz} Hz", out)
        expect(os.path.getsize(os.path.join(tmp, "coil_jet_views.png")) > 0, "views")
        # the opposite sense of rotation gives the same frequency
        h5 = write_jet(os.path.join(tmp, "coil_back.h5"),
                       [(tt, jet(2 * D, (coil(tt)[0], -coil(tt)[1]))) for tt in times])
        rc, out, err = measure(h5, "--out-dir", tmp, "--no-png", "--no-voids")
        expect(rc == 0 and "coiling: -1.50 turns" in out and "frequency 10 Hz" in out, "backwards", out + err)
        expect("largest void gap not measured (--no-voids)" in out, "--no-voids says the gap is not measured", out)

    @t
    def folding_jet_oscillates_without_turning():
        fold = lambda tt: (0.5 * D * math.sin(2 * math.pi * f_coil * (tt - t_on)) if tt >= t_on else 0.0, 0.0)  # noqa: E731
        h5 = write_jet(os.path.join(tmp, "fold.h5"), [(tt, jet(2 * D, fold(tt))) for tt in times])
        rc, out, err = measure(h5, "--out-dir", tmp, "--no-png", "--no-voids", "--threshold", "0.2")
        expect(rc == 0, f"exit {rc}", out + err)
        # the first frame after t_on with |sin| > 0.4 (0.2 D): t = 0.055 s (0.5 sin(pi/10) = 0.155 D
        # is below, 0.5 sin(pi/5) = 0.29 D above)
        expect("onset: t = 0.06 s" in out, "onset of folding", out)
        expect("frequency none" in out, "no coiling", out)
        m = [ln for ln in out.splitlines() if ln.startswith("oscillation")]
        hz = float(m[0].split(":")[1].split()[0])
        expect(abs(hz - 10.0) < 1.5, f"folding oscillation {hz} Hz", out)

    @t
    def from_time_leaves_out_the_initial_column():
        # the column bent 0.5 D while it falls (t < t_on), straight after: buckling over the whole
        # run, none from t_on on (--from); the coiling jet's onset moves to the first frame at or
        # after --from
        early = lambda tt: (0.5 * D, 0.0) if tt < t_on - 1e-12 else (0.0, 0.0)  # noqa: E731
        h5 = write_jet(os.path.join(tmp, "early.h5"), [(tt, jet(2 * D, early(tt))) for tt in times[:21]])
        rc, out, err = measure(h5, "--out-dir", tmp, "--no-png", "--no-voids", "--expect-no-buckling")
        expect(rc == 1 and "onset: t = 0 s" in out, f"whole run: exit {rc}", out + err)
        rc, out, err = measure(h5, "--out-dir", tmp, "--no-png", "--no-voids", "--expect-no-buckling",
                               "--from", str(t_on))
        expect(rc == 0 and "RESULT: PASS" in out and "onset: none" in out, f"--from: exit {rc}", out + err)
        expect("largest buckling indicator 0.000 D" in out and "over the whole run 0.500 D" in out,
               "the two largest indicators", out)
        h5 = os.path.join(tmp, "coil.h5")
        if not os.path.exists(h5):
            h5 = write_jet(h5, [(tt, jet(2 * D, coil(tt))) for tt in times])
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "coil_from", "--no-png", "--no-voids",
                               "--from", "0.1")
        expect(rc == 0 and "onset: t = 0.1 s" in out, f"coil --from: exit {rc}", out + err)
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "coil_from", "--no-png", "--no-voids",
                               "--from", "5")
        expect(rc == 1 and "no frame at or after --from 5 s" in err, f"--from past the end: exit {rc}", out + err)
        rc, out, err = measure(h5, "--no-png", "--from", "-1")
        expect(rc == 2 and "--from must be a time >= 0" in err, f"--from -1: exit {rc}", err)

    @t
    def void_in_the_pile_fails_the_void_check():
        h5 = write_jet(os.path.join(tmp, "hole.h5"), [(0.0, jet(2 * D, (0.0, 0.0), hole=True))])
        rc, out, err = measure(h5, "--out-dir", tmp, "--no-png", "--max-void-gap", "2.5")
        expect(rc == 1 and "CHECK FAILED: --max-void-gap" in out, f"exit {rc}", out + err)
        rows = rows_of(os.path.join(tmp, "jet_synth_jet.csv"))
        expect(float(rows[0]["void_gap_over_dx"]) >= 3.0, f"void gap {rows[0]['void_gap_over_dx']}")

    def mound_with(remove):
        """The jet on a mound 2 D high; remove(positions) -> bool mask of the particles taken
        out. (all positions, ids of the kept ones, the kept positions)."""
        full = jet(2 * D, (0.0, 0.0))
        keep = ~remove(full)
        ids = np.arange(len(full))
        return full, ids[keep], full[keep]

    def ball(c, r):
        return lambda x: np.linalg.norm(x - np.asarray(c), axis=1) <= r

    def origin_gaps(name, frames):
        """Measure the frames with --max-opened-gap 2.5: (exit code, output, the file, per frame
        (largest opened void, largest enclosed pocket) / dx)."""
        h5 = write_jet(os.path.join(tmp, name + ".h5"), frames)
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", name, "--no-png", "--max-opened-gap", "2.5")
        rows = rows_of(os.path.join(tmp, name + "_jet.csv"))
        return rc, out + err, h5, [(float(r["opened_void_gap_over_dx"]),
                                    float(r["enclosed_pocket_gap_over_dx"])) for r in rows]

    @t
    def void_opened_in_the_fluid_is_a_rupture_and_keeps_its_origin():
        full, ids, holed = mound_with(ball((0.0, D, 0.0), 2.0 * DX))
        # the particles in another order in the last frame: the ids follow them
        perm = np.random.default_rng(3).permutation(len(ids))
        fr = [(0.0, full), (0.001, holed, ids), (0.002, holed[perm], ids[perm])]
        rc, out, _, got = origin_gaps("opened", fr)
        expect(rc == 1 and "CHECK FAILED: --max-opened-gap" in out, f"exit {rc}", out)
        expect(got[0] == (0.0, 0.0), f"the intact mound: {got[0]}")
        for o, e in got[1:]:
            expect(o >= 3.0 and e == 0.0, f"the hole: opened {o}, enclosed {e}", out)

    @t
    def pocket_closed_over_the_outside_is_enclosed_and_keeps_its_origin():
        # a cavity off the jet's axis, open to the top of the mound through a shaft of radius
        # 1.5 dx (open points: farther than 0.91 dx from every particle), then the shaft is filled
        # by new particles (new ids) on the lattice: the cavity is a pocket the flow closed over
        # the outside air
        c = np.array([6.5 * DX, D - 3.0 * DX, 0.0])
        cavity = ball(c, 2.0 * DX)
        shaft = lambda x: (np.hypot(x[:, 0] - c[0], x[:, 2] - c[2]) <= 1.5 * DX) & (x[:, 1] >= c[1]) \
            & (x[:, 1] <= 2 * D)  # noqa: E731
        full, ids_open, open_top = mound_with(lambda x: cavity(x) | shaft(x))
        _, ids_closed, closed = mound_with(cavity)
        new = ~np.isin(ids_closed, ids_open)
        ids_closed = np.where(new, ids_closed + 10 ** 5, ids_closed)
        fr = [(0.0, open_top, ids_open), (0.001, closed, ids_closed), (0.002, closed, ids_closed)]
        rc, out, h5, got = origin_gaps("pocket", fr)
        expect(rc == 0 and "RESULT: PASS" in out, f"--max-opened-gap: exit {rc}", out)
        expect(got[0] == (0.0, 0.0), f"the open cavity: {got[0]}", out)
        for o, e in got[1:]:
            expect(o == 0.0 and e >= 3.0, f"the pocket: opened {o}, enclosed {e}", out)
        rc, out, err = measure(h5, "--out-dir", tmp, "--prefix", "pocket", "--no-png",
                               "--max-void-gap", "2.5")
        expect(rc == 1 and "CHECK FAILED: --max-void-gap" in out, f"--max-void-gap: exit {rc}", out + err)

    @t
    def errors_and_usage():
        fr = [(0.0, jet(0.0, (0.0, 0.0)))]
        for name, kw, msg in (("planar", {"radius": False}, "no circular nozzle"),
                              ("nonozzle", {"nozzle": False}, "no circular nozzle"),
                              ("flat", {"dim": 2}, "a 2D output")):
            h5 = write_jet(os.path.join(tmp, name + ".h5"), fr, **kw)
            rc, out, err = measure(h5, "--no-png")
            expect(rc == 1 and "jet_buckling_measure: error:" in err and msg in err, f"{name}: exit {rc}", out + err)
        rc, out, err = measure(os.path.join(tmp, "missing.h5"))
        expect(rc == 1 and "no such file" in err, f"missing: exit {rc}", err)
        h5 = write_jet(os.path.join(tmp, "ok.h5"), fr)
        for args, msg in ((("--expect-buckling", "--expect-no-buckling"), "not allowed with"),
                          (("--threshold", "0"), "--threshold must be a positive number"),
                          (("--max-void-gap", "2", "--no-voids"), "not with --no-voids"),
                          (("--max-opened-gap", "2", "--no-voids"), "not with --no-voids"),
                          (("--max-opened-gap", "-1"), "--max-opened-gap must be positive"),
                          (("--pictures", "soon"), "times")):
            rc, out, err = measure(h5, "--no-png", *args)
            expect(rc == 2 and msg in err, f"{args}: exit {rc}", err)
        rc, out, err = measure(h5, "--no-png", "--plate", "-0.001")
        expect(rc == 0 and "H = 0.041 m" in out and "--plate -0.001 m" in out, f"--plate: exit {rc}", out + err)

    return T


load_tests = load_tests_of(make_jet_tests)
