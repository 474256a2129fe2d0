#!/usr/bin/python3
"""Benchmark of the ISPH projection (issues 6 and 31): time per projection (assembly and solve
separately) and per step, and Krylov iterations, for a hydrostatic tank of N x N fluid
particles, for each linear solver and thread count. Prints a table (and --csv FILE, --png
FILE); timings are measured, never asserted: run it on a quiet machine and compare ratios from
one run (the solvers and thread counts alternate within each size).

Usage
-----
    /usr/bin/python3 tools/isph_bench.py [--vesph build/vesph] [--sizes 100,200,400]
        [--steps 5] [--solvers umfpack,klu,bicgstab+diagonal,bicgstab+ilut,bicgstab+amg]
        [--threads 1[,2]] [--dimension 2|3] [--csv FILE] [--png FILE]

A solver is `umfpack`, `klu`, or KRYLOV+PRECONDITIONER (`bicgstab`, `cg`, `gmres` with
`diagonal`, `ilut`, `amg`); `bicgstab+amg:K` keeps each multigrid hierarchy for K solves
(`solver.amg_setup_interval`). The solve time includes the AMG set-up.

The scene is cases/hydrostatic_tank_isph.toml scaled: N particles across the 0.1 m depth and
width (dx = 0.1/N), walls 5 layers thick, a fixed step of 1e-3 s (the solve does not depend on
it), water viscosity so that the step stays below the stability limits at every size; the
figures are the means over the steps (the first step's symbolic analysis included).
`--dimension 3` runs the same tank as a cube of N^3 fluid particles with Wendland C2 (h = 1.3 dx,
support 2.6 dx: about 74 neighbours, where the 2D tank's quintic with h = 1.6 dx would give 460
in 3D) and walls 3 layers thick on the floor and the four sides.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

from vesph.catalogue import DEFAULT_VESPH
from vesph.output import Output

SCENE = """name = "isph_bench"
dimension = 2
[domain]
min = [{lo}, {lo}]
max = [{hi}, {top}]
[particles]
spacing = {dx}
kernel = "quintic"
smoothing_ratio = 1.6
[fluid]
density = 1000.0
viscosity = 1.0e-3
[[blocks]]
kind = "fluid"
min = [0.0, 0.0]
max = [0.1, 0.1]
[[blocks]]
kind = "wall"
min = [{lo}, {lo}]
max = [{hi}, 0.0]
[[blocks]]
kind = "wall"
min = [{lo}, 0.0]
max = [0.0, {top}]
[[blocks]]
kind = "wall"
min = [0.1, 0.0]
max = [{hi}, {top}]
"""


SCENE_3D = """name = "isph_bench"
dimension = 3
[domain]
min = [{lo}, {lo}, {lo}]
max = [{hi}, {hi}, {top}]
[particles]
spacing = {dx}
kernel = "wendland_c2"
smoothing_ratio = 1.3
[fluid]
density = 1000.0
viscosity = 1.0e-3
[[blocks]]
kind = "fluid"
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[[blocks]]
kind = "wall"
min = [{lo}, {lo}, {lo}]
max = [{hi}, {hi}, 0.0]
[[blocks]]
kind = "wall"
min = [{lo}, {lo}, 0.0]
max = [0.0, {hi}, {top}]
[[blocks]]
kind = "wall"
min = [0.1, {lo}, 0.0]
max = [{hi}, {hi}, {top}]
[[blocks]]
kind = "wall"
min = [0.0, {lo}, 0.0]
max = [0.1, 0.0, {top}]
[[blocks]]
kind = "wall"
min = [0.0, 0.1, 0.0]
max = [0.1, {hi}, {top}]
"""


# What the 2D and 3D tanks share: the ISPH scheme with the solver under test, gravity along
# the last axis, a fixed step of 1 ms.
TAIL = """[solver]
scheme = "isph"
{solver}
[effects.pressure_gradient]
form = "renormalised"
[effects.viscosity]
[effects.body_force]
acceleration = {gravity}
[effects.free_surface]
threshold = 0.97
[integrator]
type = "leapfrog"
step = 1e-3
[time]
end = {end}
"""


def is_direct(name):
    return name in ("umfpack", "klu")


def solver_keys(name):
    if is_direct(name):
        return f'linear_solver = "{name}"'
    krylov, _, pc = name.partition("+")
    pc, _, interval = (pc or "ilut").partition(":")
    keys = f'linear_solver = "{krylov}"\npreconditioner = "{pc}"\ntolerance = 1e-8\nmax_iterations = 10000'
    if interval:
        keys += f"\namg_setup_interval = {int(interval)}"
    return keys


def plot(rows, path, dimension=2):
    """Left: the cold solve (from a zero guess, AMG set-up included) and the steps' warm-started
    solve against size; right: their Krylov iterations."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_t, ax_i) = plt.subplots(1, 2, figsize=(11, 4.2))
    for n, key in enumerate(sorted({(r[1], r[8]) for r in rows})):
        sel = sorted((r for r in rows if (r[1], r[8]) == key), key=lambda r: r[2])
        label = f"{key[0]}, {key[1]} thread{'s' if key[1] > 1 else ''}"
        colour = f"C{n}"
        x = [r[2] for r in sel]
        ax_t.loglog(x, [r[9] for r in sel], "-", color=colour, marker="o", label=f"{label}: cold")
        ax_t.loglog(x, [r[4] for r in sel], ":", color=colour, marker=".", label=f"{label}: warm (per step)")
        if not is_direct(key[0]):
            ax_i.semilogx(x, [r[10] for r in sel], "-", color=colour, marker="o", label=f"{label}: cold")
            ax_i.semilogx(x, [r[7] for r in sel], ":", color=colour, marker=".", label=f"{label}: warm")
    ax_t.set_xlabel("unknowns")
    ax_t.set_ylabel("pressure solve [s]")
    ax_t.grid(True, which="both", alpha=0.3)
    ax_t.legend(fontsize=6)
    ax_i.set_xlabel("unknowns")
    ax_i.set_ylabel("Krylov iterations per solve")
    ax_i.set_yscale("symlog", linthresh=1)
    ax_i.grid(True, which="both", alpha=0.3)
    ax_i.legend(fontsize=6)
    fig.suptitle(f"ISPH hydrostatic tank ({dimension}D): pressure solve against size "
                 "(cold: from a zero guess; warm: the steps', from the last pressure)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def read_csv(path):
    """The rows of a --csv file, as main() builds them (for replotting)."""
    import csv
    rows = []
    with open(path) as f:
        for d in csv.DictReader(f):
            rows.append((int(d["fluid_particles"]), d["solver"], int(d["unknowns"]), float(d["assembly_s"]),
                         float(d["solve_s"]), float(d["projection_s"]), float(d["step_s"]), float(d["iterations"]),
                         int(d["threads"]), float(d["cold_solve_s"]), int(d["cold_iterations"]), float(d["peak_GiB"])))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(prog="isph_bench.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--vesph", default=DEFAULT_VESPH)
    ap.add_argument("--sizes", default="100,200,400", help="particles across the tank (N: N^D fluid particles)")
    ap.add_argument("--dimension", type=int, choices=(2, 3), default=2,
                    help="2: the square tank (quintic, walls 5 layers); 3: the cube (Wendland C2, walls 3 layers)")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--solvers", default="umfpack,klu,bicgstab+diagonal,bicgstab+ilut,bicgstab+amg")
    ap.add_argument("--threads", default="1", help="comma-separated thread counts (OMP_NUM_THREADS)")
    ap.add_argument("--direct-up-to", type=int, default=200, metavar="N",
                    help="run the direct solvers only up to N particles across (default 200: at 400 a "
                         "UMFPACK solve takes minutes)")
    ap.add_argument("--unpreconditioned-up-to", type=int, default=400, metavar="N",
                    help="run the Krylov solvers without amg only up to N particles across (default 400: "
                         "their iterations grow like N)")
    ap.add_argument("--png", metavar="FILE", help="plot of solve time and iterations against size")
    ap.add_argument("--csv", metavar="FILE")
    a = ap.parse_args(argv)
    if not os.path.exists(a.vesph):
        ap.error(f"{a.vesph}: no such file (build vesph first, or give --vesph)")
    rows = []
    print(f"{'N_fluid':>8} {'solver':>18} {'thr':>3} {'unknowns':>9} {'assembly_s':>11} {'solve_s':>10} "
          f"{'projection_s':>13} {'step_s':>9} {'iterations':>10} {'cold_solve_s':>12} {'cold_iter':>9} {'peak_GiB':>8}")
    with tempfile.TemporaryDirectory() as work:
        for n in (int(s) for s in a.sizes.split(",")):
            dx = 0.1 / n
            layers = 5 if a.dimension == 2 else 3
            lo, hi, top = -layers * dx, 0.1 + layers * dx, 0.1 + 8 * dx
            n_fluid = n ** a.dimension
            template = (SCENE if a.dimension == 2 else SCENE_3D) + TAIL
            gravity = "[0.0, -9.81]" if a.dimension == 2 else "[0.0, 0.0, -9.81]"
            for solver, threads in ((s, int(t)) for s in a.solvers.split(",") for t in a.threads.split(",")):
                env = dict(os.environ, OMP_NUM_THREADS=str(threads))
                if is_direct(solver) and n > a.direct_up_to:
                    print(f"{n_fluid:8d} {solver:>18} skipped (--direct-up-to {a.direct_up_to})")
                    continue
                if not is_direct(solver) and "+amg" not in solver and n > a.unpreconditioned_up_to:
                    print(f"{n_fluid:8d} {solver:>18} skipped (--unpreconditioned-up-to {a.unpreconditioned_up_to})")
                    continue
                scene = os.path.join(work, "bench.toml")
                with open(scene, "w") as f:
                    f.write(template.format(lo=repr(lo), hi=repr(hi), top=repr(top), dx=repr(dx), gravity=gravity,
                                         solver=solver_keys(solver), end=repr(a.steps * 1e-3)))
                out = os.path.join(work, "out")
                # /usr/bin/time -f %M: the run's peak resident memory (KiB), for the memory target
                timed = ["/usr/bin/time", "-f", "%M"] if os.path.exists("/usr/bin/time") else []
                r = subprocess.run(timed + [a.vesph, "run", scene, "-o", out, "--quiet"], env=env,
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    print(f"{n_fluid:8d} {solver:>18} {threads:3d} failed (exit {r.returncode}): {r.stderr.strip()[-300:]}")
                    continue
                with open(os.path.join(out, "summary.json")) as f:
                    s = json.load(f)
                i = s["isph"]
                k = max(i["solves"], 1)
                with Output(os.path.join(out, "isph_bench.h5")) as h:
                    unknowns = int(h.diagnostics("pressure_unknowns")[0][-1])
                cold = i.get("initial_solve", {})
                try:
                    peak_gib = int(r.stderr.strip().splitlines()[-1]) / 2**20 if timed else float("nan")
                except (ValueError, IndexError):
                    peak_gib = float("nan")
                row = (n_fluid, solver, unknowns, i["assembly_seconds"] / k, i["solve_seconds"] / k,
                       (i["assembly_seconds"] + i["solve_seconds"] + i["correction_seconds"]) / k,
                       s["wall_seconds"] / max(s["steps"], 1), i["iterations_mean"], threads,
                       cold.get("solve_seconds", float("nan")), cold.get("iterations", -1), peak_gib)
                rows.append(row)
                print(f"{row[0]:8d} {row[1]:>18} {threads:3d} {row[2]:9d} {row[3]:11.4f} {row[4]:10.4f} "
                      f"{row[5]:13.4f} {row[6]:9.4f} {row[7]:10.1f} {row[9]:12.4f} {row[10]:9d} {row[11]:8.2f}")
                sys.stdout.flush()
    print(f"# means over {a.steps} steps (warm-started from the previous pressure); cold = the initial "
          "pressure solve from a zero guess (its set-up included); Krylov tolerance 1e-8 (relative residual); "
          "peak = the run's peak resident memory")
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("fluid_particles,solver,unknowns,assembly_s,solve_s,projection_s,step_s,iterations,threads,"
                    "cold_solve_s,cold_iterations,peak_GiB\n")
            for r in rows:
                f.write(",".join(str(x) for x in r) + "\n")
    if a.png and rows:
        plot(rows, a.png, a.dimension)
    return 0


if __name__ == "__main__":
    sys.exit(main())
