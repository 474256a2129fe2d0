"""rod_climbing_check (vesph.checks.rod_climbing) on synthetic 3D rod-climbing outputs: columns of
particles on rings about the rod, their tops raised by a chosen surface profile, moving on the
Couette profile. The second-order profile tends to Joseph & Fosdick's h(a) - h(inf) in a wide
container; the exact Oldroyd-B and Newtonian surfaces pass (with the CSV and PNG); a dip 30 %
short, a surface still rising, a flow still spinning up (the Couette start-up), a void and a 2D
scene fail; --until judges a plateau before a late drift; --rest measures from the surface at rest; --measure profile
fits the profile away from the rod's annulus; several files give the table of the
rise against omega^2."""

import os

import numpy as np

from support import Checks, PY, TOOLS, expect, load_tests_of, read_text, write_h5  # noqa: F401

DX = 5e-4
A, R, D = 1e-3, 8e-3, 3.5e-3
RHO, G = 1000.0, 0.6


def scene(omega=10.0, model="oldroyd_b", dim=3, viscosity=0.05):
    effects = {"oldroyd_b": "[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.05\n"
                            "polymer_viscosity = 0.01\n[effects.stress_divergence]\n",
               "newtonian": ""}[model]
    return f"""name = "rod_synth"
dimension = {dim}
[domain]
min = [-0.0095, -0.0015, -0.0095]
max = [0.0095, 0.008, 0.0095]
[particles]
spacing = {DX}
kernel = "wendland_c2"
smoothing_ratio = 1.5
[fluid]
density = {RHO}
viscosity = {viscosity}
[[blocks]]
kind = "fluid"
shape = "tube"
centre = [0.0, {D / 2}, 0.0]
axis = [0.0, 1.0, 0.0]
inner_diameter = {2 * A}
outer_diameter = {2 * R}
length = {D}
[[blocks]]
kind = "wall"
shape = "cylinder"
centre = [0.0, 0.003, 0.0]
axis = [0.0, 1.0, 0.0]
diameter = {2 * A}
length = 0.006
angular_velocity = [0.0, {omega}, 0.0]
axis_point = [0.0, 0.0, 0.0]
[[blocks]]
kind = "wall"
shape = "tube"
centre = [0.0, 0.003, 0.0]
axis = [0.0, 1.0, 0.0]
inner_diameter = {2 * R}
outer_diameter = {2 * R + 6 * DX}
length = 0.006
[effects.continuity]
[effects.equation_of_state]
sound_speed = 0.3
[effects.pressure_gradient]
[effects.viscosity]
{effects}[effects.body_force]
acceleration = [0.0, {-G}, 0.0]
"""


def particles(profile, omega, void=False):
    """Fluid particles on rings k (r = a + (k + 1/2) dx, round(2 pi r/dx) each) in layers
    (j + 1/2) dx, each column's heights stretched so that its top rises by profile(k)."""
    pos, vel = [], []
    n_layers = int(round(D / DX))
    Acoef = -omega * A * A / (R * R - A * A)
    Bcoef = omega * A * A * R * R / (R * R - A * A)
    for k in range(int(round((R - A) / DX))):
        r = A + (k + 0.5) * DX
        n = int(round(2 * np.pi * r / DX))
        th = 2 * np.pi * (np.arange(n) + 0.5 * (k % 2)) / n
        y = (np.arange(n_layers) + 0.5) * DX
        y = y * (1 + profile[k] / (D - 0.5 * DX))
        for j, yy in enumerate(y):
            if void and 4 <= k <= 6 and 2 <= j <= 4:
                continue
            x = np.stack([r * np.cos(th), np.full(n, yy), r * np.sin(th)], axis=1)
            v = Acoef * r + Bcoef / r
            # omega about +y: v = omega x r = (omega z, 0, -omega x) direction
            u = np.stack([v * np.sin(th), np.zeros(n), -v * np.cos(th)], axis=1)
            pos.append(x)
            vel.append(u)
    pos, vel = np.concatenate(pos), np.concatenate(vel)
    return pos, vel


def write_case(path, omega=10.0, model="oldroyd_b", scale=1.0, growing=False, void=False, dim=3, viscosity=0.05,
               late_drift=False, first_annulus_offset=0.0):
    """The synthetic output; viscosity (Pa s) sets the Couette start-up the check asks for: at the
    default 0.05 its spin-up time (R - a)^2/(pi^2 nu0) is 0.1 s or less, well before the frames.
    late_drift: the exact surface to t = 0.3 s, 1.5 times it after (steady again).
    first_annulus_offset (m): added to the first ring's surface in every frame after the first
    (a wall's static dip, as the rest run of --rest shows it)."""
    from vesph.checks import rod_climbing as RC

    beta = 0.01 * 0.05 if model == "oldroyd_b" else 0.0
    edges = A + DX * np.arange(int(round((R - A) / DX)) + 1)
    h = lambda r: RC.couette_height(r, omega, A, R, G, RHO, beta)  # noqa: E731
    means = np.array([RC.annulus_mean(h, edges[i], edges[i + 1]) for i in range(len(edges) - 1)])
    means -= RC.annulus_mean(h, 0.5 * R, R - DX)
    frames = []
    times = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5]
    for i, t in enumerate(times):
        amp = 0.0 if i == 0 else (t / times[-1] if growing else 1.5 if late_drift and t > 0.3 else 1.0)
        profile = scale * amp * means
        if i > 0:
            profile = profile + first_annulus_offset * (np.arange(len(means)) == 0)
        pos, vel = particles(profile, omega, void=void and i > 0)
        n = len(pos)
        frames.append({"time": t, "step": 10 * i, "position": pos, "velocity": vel if i else 0 * vel,
                       "kind": np.zeros(n, np.uint8), "id": np.arange(n, dtype=np.uint64),
                       "mass": np.full(n, RHO * DX ** 3), "density": np.full(n, RHO),
                       "pressure": np.zeros(n)})
    write_h5(path, scene(omega, model, dim, viscosity), 3, frames, extra_root={"dx": np.float64(DX), "h": np.float64(1.5 * DX)})
    return path


def run(*args):
    import subprocess
    p = subprocess.run([PY, "-m", "vesph", "rod_climbing_check", *map(str, args)], capture_output=True, text=True,
                       cwd=TOOLS, env=dict(os.environ, PYTHONPATH=TOOLS))
    return p.returncode, p.stdout, p.stderr


def make_rod_climbing_tests(tmp):
    T = Checks()
    t = T.add

    @t
    def wide_container_tends_to_joseph_fosdick():
        from vesph.checks import rod_climbing as RC
        omega, beta = 10.0, 1e-3
        for b in (0.0, beta):
            wide = 1e4 * A
            h = RC.couette_height(np.array([A, 1e3 * A]), omega, A, wide, G, RHO, b)
            jf = omega ** 2 * (2 * b - RHO * A * A / 2) / (RHO * G)
            expect(abs((h[0] - h[1]) / jf - 1) < 1e-5, f"beta {b}: {h[0] - h[1]} against {jf}")

    @t
    def exact_oldroyd_b_surface_passes_with_csv_and_png():
        h5 = write_case(os.path.join(tmp, "ob.h5"))
        csv, png = os.path.join(tmp, "ob.csv"), os.path.join(tmp, "ob.png")
        rc, out, err = run(h5, "--frames", "2", "--csv", csv, "--png", png)
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        expect("measured/theory = 1.000" in out and "measured/reference = 0.99" in out, "not the theory", out)
        rows = read_text(csv).strip().splitlines()
        expect(rows[0].startswith("r_inner_m,r_outer_m,r_mid_m,h_measured_m,h_theory_m"), rows[0])
        expect(len(rows) == 1 + 14, f"{len(rows) - 1} annuli, expected 14")
        first = [float(c) for c in rows[1].split(",")]
        expect(abs(first[3] - first[4]) < 1e-3 * abs(first[4]) and first[4] > 0, f"first annulus {first}")
        with open(png, "rb") as fh:
            expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", "PNG not written")

    @t
    def exact_newtonian_dip_passes_and_a_short_dip_fails():
        h5 = write_case(os.path.join(tmp, "n.h5"), model="newtonian")
        rc, out, err = run(h5, "--frames", "2")
        expect(rc == 0, f"exact dip: exit {rc}", out + err)
        expect("newtonian" in out and "measured/theory = 1.000" in out, "no Newtonian ratio 1", out)
        short = write_case(os.path.join(tmp, "n_short.h5"), model="newtonian", scale=0.7)
        rc, out, err = run(short, "--frames", "2")
        expect(rc == 1 and "error +30 %" in out and "measured/theory = 0.700" in out, f"a 30 % short dip: exit {rc}",
               out + err)

    @t
    def rising_surface_is_not_steady():
        h5 = write_case(os.path.join(tmp, "grow.h5"), growing=True)
        rc, out, err = run(h5, "--frames", "2")
        expect(rc == 1 and "not steady" in err, f"exit {rc}", out + err)

    @t
    def until_judges_the_plateau_before_a_late_drift():
        h5 = write_case(os.path.join(tmp, "late.h5"), late_drift=True)
        rc, out, err = run(h5, "--frames", "1")
        expect(rc == 1 and "measured/theory = 1.500" in out, f"the whole run: exit {rc}", out + err)
        rc, out, err = run(h5, "--frames", "1", "--until", "0.3")
        expect(rc == 0 and "measured/theory = 1.000" in out and "t = 0.3..0.3 s" in out, f"--until 0.3: exit {rc}",
               out + err)
        rc, out, err = run(h5, "--until", "0")
        expect(rc == 2 and "--until" in err, f"--until 0: exit {rc}", out + err)

    @t
    def rest_subtracts_the_surface_at_rest():
        # A static dip of 0.1 dx at the rod in the turning run and in the run at rest: measured
        # from the far level the rise is off, from the surface at rest it is the theory.
        dip = -0.1 * DX
        h5 = write_case(os.path.join(tmp, "dipped.h5"), first_annulus_offset=dip)
        rest = write_case(os.path.join(tmp, "rest.h5"), omega=0.0, first_annulus_offset=dip)
        rc, out, err = run(h5, "--frames", "2")
        expect(rc == 1 and "measured/theory = 1.000" not in out, f"without --rest: exit {rc}", out + err)
        rc, out, err = run(h5, "--frames", "2", "--rest", rest)
        expect(rc == 0 and "measured/theory = 1.000" in out and "at rest (the same container" in out
               and "-0.1000 dx" in out, f"with --rest: exit {rc}", out + err)
        rc, out, err = run(h5, "--frames", "2", "--rest", h5)
        expect(rc == 1 and "must not turn" in err, f"a turning run as the rest: exit {rc}", out + err)

    @t
    def profile_measure_leaves_the_rods_annulus_out():
        # The exact surface with the rod's annulus 0.1 dx low: the rise at the rod fails, the
        # profile measure (second annulus to R/2) finds the amplitude 1; a dip 30 % short is 0.7
        # by both; a surface still rising is not steady in the amplitude either.
        dipped = write_case(os.path.join(tmp, "dipped_n.h5"), model="newtonian", first_annulus_offset=-0.1 * DX)
        rc, out, err = run(dipped, "--frames", "2")
        expect(rc == 1 and "measured/theory = 1.000" not in out, f"the rod's annulus: exit {rc}", out + err)
        rc, out, err = run(dipped, "--frames", "2", "--measure", "profile")
        expect(rc == 0 and "over annuli 2..6" in out and "amplitude 1.000" in out, f"the profile: exit {rc}", out + err)
        short = write_case(os.path.join(tmp, "n_short_p.h5"), model="newtonian", scale=0.7)
        rc, out, err = run(short, "--frames", "2", "--measure", "profile")
        expect(rc == 1 and "amplitude 0.700" in out and "amplitude error -30 %" in out
               and "profile amplitude 0.700" in err, f"a 30 % short dip: exit {rc}", out + err)
        grow = write_case(os.path.join(tmp, "grow_p.h5"), model="newtonian", growing=True)
        rc, out, err = run(grow, "--frames", "2", "--measure", "profile", "--tolerance", "1")
        expect(rc == 1 and "the profile amplitude changed by" in err, f"a rising surface: exit {rc}", out + err)

    @t
    def a_flow_still_spinning_up_is_not_steady():
        # The exact steady surface at t = 0.4-0.5 s of a fluid whose Couette flow takes 2 s to
        # spin up (nu0 = 2.5e-6 m^2/s): the frames do not drift, the start-up says it is early.
        h5 = write_case(os.path.join(tmp, "slow.h5"), model="newtonian", viscosity=0.0025)
        rc, out, err = run(h5, "--frames", "2")
        expect(rc == 1 and "the start-up of the Couette flow has 0." in err and "steady: the mean" in out,
               f"exit {rc}", out + err)
        rc, out, err = run(h5, "--frames", "2", "--startup-tolerance", "1")
        expect(rc == 0, f"with the start-up tolerance lifted: exit {rc}", out + err)

    @t
    def a_void_fails():
        h5 = write_case(os.path.join(tmp, "void.h5"), void=True)
        rc, out, err = run(h5, "--frames", "2")
        expect(rc == 1 and "(a void)" in err, f"exit {rc}", out + err)

    @t
    def a_2d_scene_is_refused():
        h5 = write_case(os.path.join(tmp, "flat.h5"), dim=2)
        rc, out, err = run(h5)
        expect(rc == 1 and "3D scenes" in err, f"exit {rc}", out + err)

    @t
    def several_files_give_the_sweep():
        files = [write_case(os.path.join(tmp, f"w{w}.h5"), omega=w) for w in (5.0, 10.0)]
        csv, png = os.path.join(tmp, "sweep.csv"), os.path.join(tmp, "sweep.png")
        rc, out, err = run(*files, "--frames", "2", "--sweep-csv", csv, "--sweep-png", png)
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_text(csv).strip().splitlines()
        expect(len(rows) == 3 and rows[0].startswith("file,model,omega_rad_s,wi,rise_m,theory_m"), str(rows))
        r5, r10 = (float(r.split(",")[4]) for r in rows[1:])
        expect(abs(r10 / r5 - 4) < 1e-6, f"rise not like omega^2: {r5} {r10}")
        expect(os.path.getsize(png) > 1000, "sweep PNG")

    return T


load_tests = load_tests_of(make_rod_climbing_tests)
