"""Hagen-Poiseuille start-up in a pipe (vesph.analytic pipe_*; the check vesph.checks.pipe):
the Fourier-Bessel coefficients (the series cancels the steady profile at t = 0), the Newtonian
and the Oldroyd-B series against a direct method-of-lines solution of the radial equations
(velocity at several times, through the Oldroyd-B overshoot; the steady polymer shear stress
and N1), the Newtonian limit of the Oldroyd-B series, the mode's rate; and pipe_check on
synthetic 3D pipe outputs (exact fields pass; a 3 % velocity error, an unsteady last frame and
a wrong N1 fail)."""

import os

import h5py
import numpy as np

from support import Checks, PY, TOOLS, expect, load_tests_of, read_text  # noqa: F401

R, RHO, G = 5e-4, 1000.0, 4e-4
ETA_S, ETA_P, LAM = 5e-4, 5e-4, 0.125
UC = G * R * R * RHO / (4 * (ETA_S + ETA_P))     # 2.5e-5 m/s


def make_pipe_analytic_tests(tmp):
    from vesph import analytic as X

    T = Checks()
    t = T.add

    @t
    def pipe_series_cancels_the_steady_profile_at_t0():
        j, c = X.pipe_modes()
        from scipy import special
        x = np.linspace(0.0, 1.0, 57)
        series = special.j0(np.outer(x, j)) @ c
        expect(np.max(np.abs(series - (1 - x * x))) < 1e-8, "sum c_k J0(j_k x) != 1 - x^2")
        expect(abs(c[0] - 8 / (j[0] ** 3 * special.j1(j[0]))) < 1e-15 and abs(j[0] - 2.404825557695773) < 1e-12,
               "first mode")
        # the brief's form of the k-th term, 2 g R^2/(nu j^3 J1(j)), is u_c c_k with u_c = g R^2/(4 nu)
        nu = 1e-6
        expect(abs(G * R * R / (4 * nu) * c[3] - 2 * G * R * R / (nu * j[3] ** 3 * special.j1(j[3]))) < 1e-18,
               "term amplitude")
        expect(np.all(X.pipe_newtonian_startup(x * R, 0.0, G, nu, R) == 0), "u(r, 0) != 0")

    @t
    def pipe_newtonian_walls_limits_and_radial_solution():
        nu = (ETA_S + ETA_P) / RHO
        for tt in (1e-3, 0.02, 0.2):
            expect(abs(X.pipe_newtonian_startup(R, tt, G, nu, R)) < 1e-9 * UC, f"wall velocity at t = {tt}")
        expect(abs(X.pipe_newtonian_startup(0.0, 1e-4, G, nu, R) - G * 1e-4) < 1e-6 * G * 1e-4,
               "short-time limit u = g t on the axis")
        rr = np.linspace(0, R, 11)
        expect(np.max(np.abs(X.pipe_newtonian_startup(rr, 20.0, G, nu, R) - UC * (1 - (rr / R) ** 2))) < 1e-9 * UC,
               "steady limit")
        expect(isinstance(X.pipe_newtonian_startup(1e-4, 0.01, G, nu, R), float), "scalar gives a float")
        times = [0.005, 0.02, 0.0625, 0.25]
        rc, u, *_ = X.pipe_startup_radial(G, RHO, ETA_S + ETA_P, 0.0, 0.0, R, times, n=100)
        for k, tt in enumerate(times):
            e = np.max(np.abs(u[k] - X.pipe_newtonian_startup(rc, tt, G, nu, R))) / UC
            expect(e < 1e-4, f"Newtonian series against the radial solution at t = {tt}: {e:.2e} of u_c")
        # the Oldroyd-B series without polymer is the Newtonian one
        expect(np.max(np.abs(X.pipe_oldroyd_b_startup(rc, 0.03, G, RHO, 1e-3, 0.0, LAM, R)
                             - X.pipe_newtonian_startup(rc, 0.03, G, nu, R))) == 0, "eta_p = 0")

    @t
    def pipe_oldroyd_b_against_the_radial_solution():
        # E = lambda nu0/R^2 = 0.5, beta = 0.5 (the channel's section 6 values): 1.28 u_c on the axis
        # at t = lambda (the peak, 1.30, at 1.2 lambda); and a more elastic, less retarded fluid (E = 2, beta = 0.1)
        for eta_s, eta_p, lam in ((ETA_S, ETA_P, LAM), (1e-4, 9e-4, 4 * LAM)):
            times = [0.01, 0.05, lam, 2 * lam, 4 * lam, 12 * lam / (1 if lam == LAM else 0.5)]
            rc, u, rf, trz, tzz = X.pipe_startup_radial(G, RHO, eta_s, eta_p, lam, R, times, n=100)
            for k, tt in enumerate(times):
                ua = X.pipe_oldroyd_b_startup(rc, tt, G, RHO, eta_s, eta_p, lam, R)
                e = np.max(np.abs(u[k] - ua)) / UC
                # the radial solution's error (second order in R/n) dominates: 1.9e-4 of u_c
                # (beta = 0.5), 3.7e-4 at t = 0.01 s (beta = 0.1; 9.5e-5 at n = 200)
                expect(e < 5e-4, f"lambda {lam}, beta {eta_s / (eta_s + eta_p)}: series against the "
                                 f"radial solution at t = {tt}: {e:.2e} of u_c")
            if lam == LAM:
                peak = X.pipe_oldroyd_b_startup(0.0, lam, G, RHO, eta_s, eta_p, lam, R) / UC
                expect(1.2 < peak < 1.35, f"no overshoot on the axis at t = lambda: {peak}")
            st = X.pipe_steady_stresses(rf, G, RHO, eta_s, eta_p, lam)
            e_t = np.max(np.abs(trz[-1] - st["tau_rz"])) / abs(st["tau_rz"][-1])
            e_n = np.max(np.abs(tzz[-1] - st["N1"])) / st["N1"][-1]
            expect(e_t < 1e-4 and e_n < 1e-4, f"steady tau_rz {e_t:.2e}, N1 {e_n:.2e}")
            expect(np.allclose(st["T_rz"], -RHO * G * rf / 2, rtol=1e-14), "T_rz = -rho g r/2")
            expect(np.allclose(st["tau_rz"] + st["solvent_rz"], st["T_rz"], rtol=1e-14), "split")

    @t
    def startup_mode_rate_is_the_derivative():
        for alpha in (0.05, 1.0, 4.0 / 0.25, 300.0):   # over- and under-damped
            for beta in (0.0, 0.1, 0.5):
                for T_ in (0.0, 0.3, 2.0):
                    h = 1e-6
                    fd = (X.startup_mode(T_ + h, alpha, beta) - X.startup_mode(max(T_ - h, 0), alpha, beta)) / (
                        T_ + h - max(T_ - h, 0))
                    d = X.startup_mode_rate(T_, alpha, beta)
                    expect(abs(d - fd) < 1e-4 * max(1.0, alpha), f"alpha {alpha} beta {beta} T {T_}: {d} vs {fd}")
                expect(abs(X.startup_mode(0.0, alpha, beta) - 1) < 1e-14
                       and abs(X.startup_mode_rate(0.0, alpha, beta) + alpha) < 1e-9 * alpha, "initial values")
    return T


PIPE_SCENE = """\
name = "pipe_synth"
dimension = 3
[domain]
min = [0.0, -8.0e-4, -8.0e-4]
max = [5.0e-4, 8.0e-4, 8.0e-4]
periodic = [true, false, false]
[particles]
spacing = {dx!r}
kernel = "quintic"
smoothing_ratio = 1.6
[fluid]
density = 1000.0
viscosity = {eta_s!r}
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [2.5e-4, 0.0, 0.0]
diameter = 1.0e-3
axis = [1.0, 0.0, 0.0]
length = 5.0e-4
[[blocks]]
kind = "wall"
shape = "tube"
centre = [2.5e-4, 0.0, 0.0]
inner_diameter = 1.0e-3
outer_diameter = 1.6e-3
axis = [1.0, 0.0, 0.0]
length = 5.0e-4
[effects.body_force]
acceleration = [4.0e-4, 0.0, 0.0]
{model}
"""


def write_pipe(path, times, eta_p=ETA_P, lam=LAM, scale=1.0, n1_scale=1.0, dx=5e-5):
    """A 3D pipe on the cubic lattice cut by the cylinder, velocities from the analytic start-up
    (times scale), extra_stress the steady total stress T (solvent + polymer) rotated into x, y, z."""
    from vesph.analytic import pipe_oldroyd_b_startup, pipe_steady_stresses
    eta_s = ETA_S if eta_p > 0 else ETA_S + ETA_P
    model = (f"[effects.oldroyd_b]\nrelaxation_time = {lam!r}\npolymer_viscosity = {eta_p!r}"
             if eta_p > 0 else "")
    c = (np.arange(int(round(1.6e-3 / dx))) + 0.5) * dx - 8e-4
    xs = (np.arange(int(round(5e-4 / dx))) + 0.5) * dx
    X_, Y_, Z_ = np.meshgrid(xs, c, c, indexing="ij")
    pos = np.stack([X_.ravel(), Y_.ravel(), Z_.ravel()], 1)
    r = np.hypot(pos[:, 1], pos[:, 2])
    fluid = r < R
    wall = (r >= R) & (r < 8e-4)
    pos = np.concatenate([pos[fluid], pos[wall]])
    kind = np.concatenate([np.zeros(fluid.sum(), np.uint8), np.ones(wall.sum(), np.uint8)])
    r = np.hypot(pos[:, 1], pos[:, 2])
    st = pipe_steady_stresses(r, G, RHO, eta_s, eta_p, lam)
    cos, sin = pos[:, 1] / r, pos[:, 2] / r
    frames = []
    for k, tt in enumerate(times):
        v = np.zeros_like(pos)
        v[:, 0] = np.where(kind == 0, scale * pipe_oldroyd_b_startup(r, tt, G, RHO, eta_s, eta_p, lam, R), 0.0)
        T = np.zeros((len(r), 6))           # xx xy xz yy yz zz; axis x, T_rr = 0, T_xx = N1
        T[:, 0] = n1_scale * st["N1"]
        T[:, 1] = st["T_rz"] * cos
        T[:, 2] = st["T_rz"] * sin
        fr = {"time": tt, "step": 10 * k, "id": np.arange(len(r), dtype=np.uint64), "kind": kind,
              "position": pos, "velocity": v, "density": np.full(len(r), RHO),
              "mass": np.full(len(r), RHO * dx ** 3)}
        if eta_p > 0:
            fr["extra_stress"] = T
        frames.append(fr)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(3)
        f.attrs["scene"] = PIPE_SCENE.format(dx=dx, eta_s=eta_s, model=model)
        f.attrs["dx"] = np.float64(dx)
        f.attrs["h"] = np.float64(1.6 * dx)
        f.attrs["kernel"] = "quintic"
        for i, fr in enumerate(frames):
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(fr.pop("time"))
            g.attrs["step"] = np.int64(fr.pop("step"))
            for name, arr in fr.items():
                g.create_dataset(name, data=arr)


def run_check(*args):
    import subprocess
    p = subprocess.run([os.path.join(TOOLS, "vesph-post"), "pipe_check", *args],
                       capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def make_pipe_check_tests(tmp):
    T = Checks()
    t = T.add

    @t
    def pipe_check_passes_exact_fields_and_fails_errors():
        ob = os.path.join(tmp, "ob.h5")
        write_pipe(ob, [0.02, 0.125, 0.25, 1.5])
        rc, out = run_check(ob, "--png", os.path.join(tmp, "ob.png"), "--csv", os.path.join(tmp, "ob.csv"))
        expect(rc == 0 and "RESULT: PASS" in out, "exact Oldroyd-B fields must pass", out)
        expect("N1" in out and "tau_rz (polymer)" in out and os.path.exists(os.path.join(tmp, "ob.png")),
               "stress lines and the plot", out)
        # the bins' means hold the analytic values to round-off; the fitted solvent part is exact
        line = [ln for ln in out.splitlines() if "tau_rz (polymer)" in ln][0]
        expect(float(line.split("error")[1].split("%")[0]) < 1e-6, "polymer shear stress error", out)
        bad = os.path.join(tmp, "ob_slow.h5")
        write_pipe(bad, [0.02, 0.125, 1.5], scale=0.965)
        rc, out = run_check(bad)
        expect(rc == 1 and "binned velocity error above 3 %" in out, "a 3.5 % slower flow must fail", out)
        rc, out = run_check(bad, "--no-stresses", "--criterion", "centreline")
        expect(rc == 1 and "centreline (innermost bin) error above 3 %" in out, "... also on the axis", out)
        rc, out = run_check(ob, "--criterion", "centreline")
        expect(rc == 0 and "centreline (innermost bin) error below 3 %" in out, "exact fields, centreline", out)
        bad = os.path.join(tmp, "ob_n1.h5")
        write_pipe(bad, [1.5], n1_scale=1.06)
        rc, out = run_check(bad)
        expect(rc == 1 and "FAIL: N1 error" in out, "a 6 % N1 error (3.8 % of the wall value at 0.8 R) must fail", out)
        rc, out = run_check(ob, "--times", "0.02", "0.25")
        expect(rc == 1 and "not steady" in out, "stresses at an unsteady frame must fail", out)
        rc, out = run_check(ob, "--times", "0.02", "0.25", "--no-stresses")
        expect(rc == 0, "--no-stresses", out)

    @t
    def pipe_check_newtonian():
        nw = os.path.join(tmp, "nw.h5")
        write_pipe(nw, [0.01, 0.05, 0.25], eta_p=0.0)
        rc, out = run_check(nw)
        expect(rc == 0 and "RESULT: PASS" in out and "Oldroyd-B" not in out, "exact Newtonian fields", out)
        bad = os.path.join(tmp, "nw_bad.h5")
        write_pipe(bad, [0.01, 0.05, 0.25], eta_p=0.0, scale=1.025)
        rc, out = run_check(bad)
        expect(rc == 1 and "above 2 %" in out, "a 2.5 % error must fail the Newtonian 2 %", out)
        rc, out = run_check(bad, "--times", "0.07")
        expect(rc == 1 and "no frame at t = 0.07" in out, "a missing time", out)
    return T


load_tests = load_tests_of(make_pipe_analytic_tests, make_pipe_check_tests)
