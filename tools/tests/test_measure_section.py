"""section (vesph.measure.section) on a synthetic 3D lattice with known fields: which particles
lie within one spacing of the plane, their in-plane coordinates and values, oblique planes, the
PNG, and the errors and exit codes."""
import csv
import os
import subprocess

import numpy as np

from support import PY, SCENE_3D, Checks, expect, load_tests_of, write_h5, write_channel_case
from vesph import tool_environment
from vesph.measure.section import plane_basis

SPACING = 1.0e-3  # m, the synthetic lattice's spacing (the file's dx attribute)
NSIDE = 8


def section(*args):
    p = subprocess.run([PY, "-m", "vesph", "section", *map(str, args)], capture_output=True,
                       text=True, env=tool_environment())
    return p.returncode, p.stdout, p.stderr


def lattice():
    g = (np.arange(NSIDE) + 0.5) * SPACING
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


def write_lattice(path, walls=True):
    """An 8^3 lattice (the z = 0.5 dx layer walls when asked) with velocity (x, 2y, -z) / s and
    extra stress components 1..6 times (1 + x/m)."""
    pos = lattice()
    N = len(pos)
    kind = np.where(pos[:, 2] < SPACING, 1, 0).astype(np.uint8) if walls else np.zeros(N, np.uint8)
    stress = np.outer(1.0 + pos[:, 0], np.arange(1.0, 7.0))
    frames = [{"time": t, "step": 10 * i, "id": np.arange(N, dtype=np.uint64), "kind": kind,
               "position": pos, "velocity": pos * np.array([1.0, 2.0, -1.0]) * (1 + t),
               "density": np.full(N, 1000.0), "mass": np.full(N, 1e-6), "pressure": pos[:, 1] * 10,
               "extra_stress": stress}
              for i, t in enumerate([0.0, 0.5, 1.0])]
    write_h5(path, SCENE_3D, 3, frames, extra_root={"dx": np.float64(SPACING)})
    return path


def read_rows(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def make_section_tests(tmp):
    T = Checks()
    t = T.add
    h5 = write_lattice(os.path.join(tmp, "lattice.h5"))
    pos = lattice()

    @t
    def basis_follows_the_axes():
        for normal, e1, e2 in (((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
                               ((1, 0, 0), (0, 1, 0), (0, 0, 1)), ((0, 0, -3), (1, 0, 0), (0, 1, 0))):
            n, b1, b2 = plane_basis(np.array(normal, float))
            expect(np.allclose(b1, e1) and np.allclose(b2, e2), f"normal {normal}: e1 {b1}, e2 {b2}")
        n, b1, b2 = plane_basis(np.array([1.0, 2.0, 3.0]))
        m = np.array([n, b1, b2])
        expect(np.allclose(m @ m.T, np.eye(3), atol=1e-14), f"oblique basis not orthonormal: {m}")

    @t
    def axis_plane_takes_one_layer():
        # the plane z = 3.5 dx through a layer: |d| < dx takes that layer alone (64 particles),
        # u, v = x - 4 dx, y - 4 dx about the point, value = speed
        out_csv, png = os.path.join(tmp, "z.csv"), os.path.join(tmp, "z.png")
        point = f"{4 * SPACING!r},{4 * SPACING!r},{3.5 * SPACING!r}"
        rc, out, err = section(h5, "--point", point, "--normal", "0,0,1", "--csv", out_csv, "--png", png,
                               "--time", "0.6")
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_rows(out_csv)
        expect(len(rows) == NSIDE * NSIDE, f"{len(rows)} particles, expected {NSIDE * NSIDE}", out)
        for r in rows:
            x, y, z = (float(r[c]) for c in "xyz")
            expect(abs(z - 3.5 * SPACING) < 1e-12, f"z = {z} is not the layer's")
            expect(abs(float(r["u"]) - (x - 4 * SPACING)) < 1e-12 and abs(float(r["v"]) - (y - 4 * SPACING)) < 1e-12,
                   f"in-plane coordinates {r['u']}, {r['v']} of ({x}, {y})")
            speed = 1.5 * np.linalg.norm([x, 2 * y, -z])  # the frame at t = 0.5 (nearest 0.6)
            expect(abs(float(r["value"]) - speed) < 1e-12 * speed, f"speed {r['value']} != {speed}")
        expect("t = 0.5 s" in out and "64 in the section (64 fluid)" in out, "summary", out)
        with open(png, "rb") as fh:
            expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", "the PNG is not a PNG")

    @t
    def half_width_widens_the_slab():
        out_csv = os.path.join(tmp, "wide.csv")
        rc, out, err = section(h5, "--point", f"0,0,{3.5 * SPACING!r}", "--half-width", f"{1.01 * SPACING!r}",
                               "--csv", out_csv, "--png", os.path.join(tmp, "wide.png"))
        expect(rc == 0 and len(read_rows(out_csv)) == 3 * NSIDE * NSIDE, f"exit {rc}: three layers expected", out + err)

    @t
    def oblique_plane_and_stress_component():
        # the plane x + y = 7 dx (normal (1,1,0)): the selection is every particle within dx of
        # it, computed here independently; the value is extra_stress_yz = 5 (1 + x/m)
        out_csv = os.path.join(tmp, "oblique.csv")
        point = f"{3.5 * SPACING!r},{3.5 * SPACING!r},0"
        rc, out, err = section(h5, "--point", point, "--normal", "1,1,0", "--field", "extra_stress_yz",
                               "--csv", out_csv, "--png", os.path.join(tmp, "oblique.png"))
        expect(rc == 0, f"exit {rc}", out + err)
        d = (pos - np.array([3.5, 3.5, 0.0]) * SPACING) @ (np.array([1.0, 1.0, 0.0]) / np.sqrt(2))
        want = set(np.flatnonzero(np.abs(d) < SPACING).tolist())
        rows = read_rows(out_csv)
        got = {int(r["id"]) for r in rows}
        expect(got == want and len(want) > 0, f"ids {sorted(got)} != {sorted(want)}")
        for r in rows:
            expect(abs(float(r["d"])) < SPACING, f"d = {r['d']} beyond dx")
            expect(abs(float(r["value"]) - 5 * (1 + float(r["x"]))) < 1e-12, f"T_yz {r['value']}")
            expect(abs(float(r["v"]) - float(r["z"])) < 1e-12, "v is z for a normal in the x-y plane")

    @t
    def walls_kept_or_left_out():
        # the plane x = 4.5 dx: 64 particles, 8 of them walls (z = 0.5 dx)
        c1, c2 = os.path.join(tmp, "w1.csv"), os.path.join(tmp, "w2.csv")
        args = ("--point", f"{4.5 * SPACING!r},0,0", "--normal", "1,0,0", "--png", os.path.join(tmp, "w.png"))
        rc, out, err = section(h5, *args, "--csv", c1)
        rows = read_rows(c1)
        expect(rc == 0 and len(rows) == 64 and sum(r["kind"] == "1" for r in rows) == 8, f"exit {rc}", out + err)
        rc, out, err = section(h5, *args, "--csv", c2, "--fluid-only")
        expect(rc == 0 and len(read_rows(c2)) == 56, f"--fluid-only: exit {rc}", out + err)

    @t
    def errors():
        rc, out, err = section(h5, "--normal", "0,0,0")
        expect(rc == 2 and "zero vector" in err, f"zero normal: exit {rc}", out + err)
        rc, out, err = section(h5, "--point", "1,1,1")
        expect(rc == 1 and "no particle" in err, f"a plane outside the particles: exit {rc}", out + err)
        rc, out, err = section(h5, "--field", "vorticity")
        expect(rc == 2 and "invalid choice" in err, f"unknown field: exit {rc}", out + err)
        h2 = write_channel_case(os.path.join(tmp, "channel2d"))
        rc, out, err = section(h2)
        expect(rc == 2 and "needs a 3D run" in err, f"a 2D run: exit {rc}", out + err)
        nostress = os.path.join(tmp, "nostress.h5")
        write_h5(nostress, SCENE_3D, 3, [{"time": 0.0, "step": 0, "id": np.arange(len(pos), dtype=np.uint64),
                                          "kind": np.zeros(len(pos), np.uint8), "position": pos,
                                          "velocity": np.zeros_like(pos), "density": np.full(len(pos), 1000.0),
                                          "mass": np.full(len(pos), 1e-6)}],
                 extra_root={"dx": np.float64(SPACING)})
        rc, out, err = section(nostress, "--field", "extra_stress_xx")
        expect(rc == 1 and "no dataset 'extra_stress'" in err, f"no stress: exit {rc}", out + err)

    return T


# unittest collects the group above through load_tests
load_tests = load_tests_of(make_section_tests)
