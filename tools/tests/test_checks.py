"""The validation checks against analytic solutions: poiseuille_check (exact profile, --times,
CSV/PNG, perturbed velocity, mass drift, missing time, fixed-length strings) and
xpp_steady_shear check (passes on the 1-D start-up, fails on a wrong tau_zz, an oscillating
start-up, before the steady state, without an XPP) and circular_couette_check (the exact profile
passes with its plot, a perturbed ring and a mass drift fail, a scene without a fluid tube is
refused)."""
import os
import re

import h5py

import numpy as np

from support import (TOOLS, U_CENTRE, Checks, expect, load_tests_of, read_text, tool, write_channel_case,
                     write_h5, write_xpp_channel)


def make_poiseuille_tests(tmp):
    T = Checks()
    t = T.add

    # ---- poiseuille_check
    good = os.path.join(tmp, "good2d")
    h5_good = write_channel_case(good)

    @t
    def poiseuille_exact_profile_passes():
        csv_path = os.path.join(tmp, "p.csv")
        png = os.path.join(tmp, "p.png")
        rc, out, err = tool("poiseuille_check.py", h5_good, "--csv", csv_path, "--png", png)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("RESULT: PASS" in out, "no PASS line", out)
        rows = read_text(csv_path).strip().splitlines()
        expect(rows[0].startswith("frame,time_s,step,n_fluid,error_percent,"
                                  "max_density_deviation,fluid_mass,mass_drift"), rows[0])
        expect(len(rows) == 1 + 4, f"{len(rows) - 1} CSV rows, expected 4 (t > 0)")
        for r in rows[1:]:
            c = r.split(",")
            expect(float(c[4]) < 1e-9, f"error {c[4]} % not ~0")
            expect(abs(float(c[7])) < 1e-15, f"mass drift {c[7]}")
            expect(4e-5 < float(c[5]) < 1e-3, f"density deviation {c[5]}")
        with open(png, "rb") as fh:
            expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", "PNG not written")

    @t
    def fixed_length_string_attributes():
        d = os.path.join(tmp, "fixedstr")
        h5 = write_channel_case(d, fixed_strings=True)
        with h5py.File(h5, "r") as f:
            expect(isinstance(f.attrs["scene"], bytes), "test setup: scene not fixed-length")
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 0, f"poiseuille_check exit {rc}", out + err)
        rc, out, err = tool("check_output.py", d)
        expect(rc == 0, f"check_output exit {rc}", out + err)

    @t
    def poiseuille_times_selection():
        csv_path = os.path.join(tmp, "p2.csv")
        rc, out, err = tool("poiseuille_check.py", h5_good, "--times", "0.045", "0.5",
                            "--csv", csv_path)
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_text(csv_path).strip().splitlines()[1:]
        times = sorted(float(r.split(",")[1]) for r in rows)
        expect(times == [0.045, 0.5], f"checked times {times}")

    @t
    def poiseuille_missing_time_fails():
        rc, out, err = tool("poiseuille_check.py", h5_good, "--times", "0.3")
        expect(rc == 1 and "no frame at requested time 0.3" in err, f"exit {rc}", out + err)

    @t
    def poiseuille_velocity_error_detected():
        d = os.path.join(tmp, "perturbed")
        h5 = write_channel_case(d, perturb=(3, 0.03 * U_CENTRE))   # 3 % at frame 000003
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 1, f"exit {rc}", out + err)
        expect("frame 000003" in err and "velocity error 3" in err, "frame not named", err)
        expect(err.count("FAIL: frame") == 1, "only frame 000003 should fail", err)
        rc, out, err = tool("poiseuille_check.py", h5, "--tolerance", "0.05")
        expect(rc == 0, f"3 % error must pass a 5 % tolerance (exit {rc})", out + err)

    @t
    def poiseuille_mass_drift_detected():
        d = os.path.join(tmp, "massdrift")
        h5 = write_channel_case(d, mass_change=(2, 1e-6))
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 1 and "frame 000002" in err and "mass drift" in err, f"exit {rc}",
               out + err)
    return T


def make_xpp_check_tests(tmp):
    T = Checks()
    t = T.add


    good = os.path.join(tmp, "xpp_good.h5")

    @t
    def xpp_check_passes_on_the_1d_startup():
        write_xpp_channel(good)
        rc, out, err = tool("xpp_steady_shear.py", "check", good, "--transient", "--n1d", "32",
                            "--csv", good + ".csv", "--png", good + ".png",
                            "--transient-csv", good + ".t.csv", "--transient-png", good + ".t.png")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        for f_ in (".csv", ".png", ".t.csv", ".t.png"):
            expect(os.path.getsize(good + f_) > 0, f"no {f_}")
        expect("tau_zz" in out and "N2" in out, "tau_zz/N2 not compared", out)

    @t
    def xpp_check_fails_on_a_wrong_tau_zz():
        def bad(k, n, fr):
            if k == n - 1:
                fr["extra_stress_zz"] *= 1.05
        path = write_xpp_channel(os.path.join(tmp, "xpp_zz.h5"), perturb=bad)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 1 and re.search(r"tau_zz .*FAIL", out) is not None, f"exit {rc}", out + err)

    @t
    def xpp_check_fails_on_an_oscillating_startup():
        def bad(k, n, fr):
            if 2 <= k < n - 1:
                fr["velocity"][:, 0] *= 1.0 + 0.01 * (-1) ** k
        path = write_xpp_channel(os.path.join(tmp, "xpp_osc.h5"), perturb=bad)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--transient", "--n1d", "32")
        expect(rc == 1 and re.search(r"centreline velocity .*FAIL", out) is not None, f"exit {rc}", out + err)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 0, "the steady check alone should pass", out + err)

    @t
    def xpp_check_fails_before_the_steady_state():
        path = write_xpp_channel(os.path.join(tmp, "xpp_early.h5"), t_end=1.0)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 1 and "not steady" in out, f"exit {rc}", out + err)

    @t
    def xpp_check_rejects_a_scene_without_xpp():
        h5 = write_channel_case(os.path.join(tmp, "xpp_newtonian"))
        rc, out, err = tool("xpp_steady_shear.py", "check", h5)
        expect(rc == 2 and "effects.xpp" in out, f"exit {rc}", out + err)
    return T


CC_SCENE = """name = "cc"
dimension = 2
[fluid]
density = 1000.0
viscosity = 1.0e-3
[[blocks]]
kind = "fluid"
shape = "tube"
centre = [0.1, -0.2]
inner_diameter = 1.0
outer_diameter = 2.0
[[blocks]]
kind = "wall"
shape = "cylinder"
centre = [0.1, -0.2]
diameter = 1.0
angular_velocity = 4.0
axis_point = [0.1, -0.2]
[[blocks]]
kind = "wall"
shape = "tube"
centre = [0.1, -0.2]
inner_diameter = 2.0
outer_diameter = 2.5
"""


def write_circular_couette(path, perturb=0.0, mass_drift=0.0, scene=CC_SCENE):
    """Rings of fluid between R1 = 0.5 and R2 = 1 about (0.1, -0.2) moving with A r + B/r
    (omega1 = 4, omega2 = 0), the third ring's speed times (1 + perturb); a few wall particles."""
    from vesph.analytic import circular_couette
    c = np.array([0.1, -0.2])
    r = np.repeat(0.5 + (np.arange(20) + 0.5) * 0.025, 60)
    th = np.tile(np.linspace(0, 2 * np.pi, 60, endpoint=False), 20)
    x = c + np.column_stack([r * np.cos(th), r * np.sin(th)])
    v = circular_couette(r, 0.5, 1.0, 4.0)[:, None] * np.column_stack([-np.sin(th), np.cos(th)])
    v[120:180] *= 1 + perturb
    xw = c + np.array([[0.4, 0.0], [1.1, 0.0]])
    frames = []
    for k, t in enumerate((0.0, 1.0)):
        n = len(x)
        frames.append({"time": t, "step": k, "position": np.vstack([x, xw]),
                       "velocity": np.vstack([v if t > 0 else 0 * v, [[0.0, 1.6], [0.0, 0.0]]]),
                       "kind": np.concatenate([np.zeros(n, np.uint8), np.ones(2, np.uint8)]),
                       "mass": np.concatenate([np.full(n, 1.0 + (mass_drift if t > 0 else 0.0)), [1.0, 1.0]]),
                       "id": np.arange(n + 2, dtype=np.uint64)})
    write_h5(path, scene, 2, frames)
    return path


def post(*args):
    """tools/vesph-post ARGS: (exit status, stdout, stderr)."""
    import subprocess
    p = subprocess.run(["sh", os.path.join(TOOLS, "vesph-post"), *map(str, args)], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def make_circular_couette_tests(tmp):
    T = Checks()
    t = T.add

    @t
    def circular_couette_exact_profile_passes():
        png = os.path.join(tmp, "cc.png")
        rc, out, err = post("circular_couette_check",
                            write_circular_couette(os.path.join(tmp, "cc.h5")), "--plot", png)
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        expect(os.path.getsize(png) > 0, "no plot")

    @t
    def circular_couette_perturbed_ring_fails():
        # the third ring (r = 0.5625, v = 1.62) 3 % too fast: 2.43 % of omega R1 = 2
        rc, out, err = post("circular_couette_check",
                            write_circular_couette(os.path.join(tmp, "cc_bad.h5"), perturb=0.03))
        expect(rc == 1 and "azimuthal velocity error 2.43" in err, f"exit {rc}", out + err)
        rc, out, err = post("circular_couette_check", os.path.join(tmp, "cc_bad.h5"),
                            "--tolerance", "0.03")
        expect(rc == 0, f"exit {rc} with a 3 % tolerance", out + err)

    @t
    def circular_couette_mass_drift_fails():
        rc, out, err = post("circular_couette_check",
                            write_circular_couette(os.path.join(tmp, "cc_mass.h5"), mass_drift=1e-9))
        expect(rc == 1 and "mass drift" in err, f"exit {rc}", out + err)

    @t
    def circular_couette_needs_a_fluid_tube():
        scene = CC_SCENE.replace('shape = "tube"\ncentre = [0.1, -0.2]\ninner_diameter = 1.0',
                                 'shape = "disk"\ncentre = [0.1, -0.2]\ninner_diameter = 1.0', 1)
        rc, out, err = post("circular_couette_check",
                            write_circular_couette(os.path.join(tmp, "cc_disk.h5"), scene=scene))
        expect(rc == 1 and "one fluid block of shape = \"tube\"" in err, f"exit {rc}", out + err)
    return T


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_poiseuille_tests, make_xpp_check_tests, make_circular_couette_tests)
