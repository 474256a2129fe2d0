#!/usr/bin/python3
"""vesph's figures on the peers' matched dam break (issue 38; docs/performance.md "Peer
comparison"), in the units DualSPHysics and PySPH report: simulated seconds per wall second,
particle-steps per second (fluid particles x steps / wall s), right-hand sides per step and wall
milliseconds per right-hand side. Builds nothing of the peers: their rows in docs/performance.md
were measured with their own binaries (DualSPHysics 5.4 CPU, PySPH 1.0b1) on the same geometry.

Usage
-----
    tools/vesph-post peer_dam_break [--vesph build/vesph] [--size full|ci] [--end 0.05]
        [--threads 1,2] [--repeat 2] [--integrator leapfrog[,SPEC...]] [--csv FILE]

The scene is cases/dam_break_2d.toml (column 1 m x 2 m in a 4 m tank, Wendland C2, h = sqrt(2)
dx, Tait with c0 = 20 sqrt(g H), alpha = 0.01, hydrostatic start): --size full is dx = 0.01 m
(20 000 fluid particles, the peers' case), --size ci is dx = 0.04 m (1250). Each thread count
runs --repeat times, alternating, and the median wall time is reported (summary.json's
wall_seconds: the integration and output, not the start-up). No frame is written but the first
and the last (output.times = [end]); timings are measured, never asserted: compare ratios from
one run on a quiet machine.

--integrator takes one or more comma-separated specifications TYPE[:TABLE][@CFL]: the
integrator.type, optionally its integrator.table (the ARKODE ones) and integrator.cfl, e.g.
`leapfrog,symplectic,arkode:BOGACKI_SHAMPINE_4_2_3@1`. Within each repetition every
integrator runs at every thread count in turn, so that a change of the machine's load hits all.
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

from vesph import REPO
from vesph.catalogue import DEFAULT_VESPH

CASE = os.path.join(REPO, "cases", "dam_break_2d.toml")
SIZES = {
    "full": [],
    "ci": ["particles.spacing=0.04", "blocks[1].min=[-0.12,-0.12]", "blocks[1].max=[4.12,0.0]",
           "blocks[2].min=[-0.12,0.0]", "blocks[3].max=[4.12,3.0]"],
}
COLUMNS = ["size", "integrator", "threads", "fluid_particles", "steps", "rhs_per_step", "wall_s",
           "sim_s_per_wall_s", "particle_steps_per_s", "ms_per_rhs"]


def parse_integrator(spec):
    """'TYPE[:TABLE][@CFL]' -> the --set assignments of [integrator] (ValueError when malformed)."""
    body, _, cfl = spec.partition("@")
    kind, _, table = body.partition(":")
    if not kind or (":" in body and not table) or ("@" in spec and not cfl):
        raise ValueError(f"integrator specification {spec!r}: expected TYPE[:TABLE][@CFL]")
    sets = [f'integrator.type="{kind}"']
    if table:
        sets.append(f'integrator.table="{table}"')
    if cfl:
        if not float(cfl) > 0:
            raise ValueError(f"integrator specification {spec!r}: the CFL coefficient must be positive")
        sets.append(f"integrator.cfl={float(cfl)!r}")
    return sets


def run_once(vesph, size, end, threads, integrator, workdir):
    sets = SIZES[size] + [f"time.end={end}", f"output.times=[{end}]"] + parse_integrator(integrator)
    out = tempfile.mkdtemp(dir=workdir)
    cmd = [vesph, "run", CASE, "-o", out, "--quiet", "--threads", str(threads)]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"peer_dam_break: {' '.join(cmd)} exited {p.returncode}: {p.stderr[-400:]}")
    with open(os.path.join(out, "summary.json")) as fh:
        return json.load(fh)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="peer_dam_break", description="vesph's figures on the peers' matched dam break")
    ap.add_argument("--vesph", default=DEFAULT_VESPH)
    ap.add_argument("--size", choices=sorted(SIZES), default="full")
    ap.add_argument("--end", type=float, default=0.05, help="simulated time, s (default 0.05, the peers')")
    ap.add_argument("--threads", default="1,2", help="thread counts (default 1,2)")
    ap.add_argument("--repeat", type=int, default=2, help="repetitions per thread count; the median is reported")
    ap.add_argument("--integrator", default="leapfrog",
                    help="comma-separated TYPE[:TABLE][@CFL] (default leapfrog); alternated within each repetition")
    ap.add_argument("--csv", metavar="FILE")
    a = ap.parse_args(argv)
    if not (a.end > 0 and a.repeat >= 1):
        ap.error("--end must be positive and --repeat at least 1")
    threads = [int(t) for t in a.threads.split(",")]
    integrators = [spec.strip() for spec in a.integrator.split(",") if spec.strip()]
    try:
        for spec in integrators:
            parse_integrator(spec)
    except ValueError as e:
        ap.error(str(e))
    runs = [(spec, t) for spec in integrators for t in threads]
    walls = {r: [] for r in runs}
    last = {}
    with tempfile.TemporaryDirectory() as work:
        for _ in range(a.repeat):
            for spec, t in runs:  # alternated, so that a change of the machine's load hits every run
                s = run_once(a.vesph, a.size, a.end, t, spec, work)
                walls[(spec, t)].append(float(s["wall_seconds"]))
                last[(spec, t)] = s
    rows = []
    for spec, t in runs:
        s, wall = last[(spec, t)], statistics.median(walls[(spec, t)])
        steps, rhs, n = int(s["steps"]), int(s["rhs_evals"]), int(s["fluid_particles"])
        rows.append({"size": a.size, "integrator": spec, "threads": t, "fluid_particles": n, "steps": steps,
                     "rhs_per_step": rhs / steps, "wall_s": wall, "sim_s_per_wall_s": float(s["final_time"]) / wall,
                     "particle_steps_per_s": n * steps / wall, "ms_per_rhs": 1e3 * wall / rhs})
    print(f"# cases/dam_break_2d.toml, size {a.size}, t = 0 to {a.end:g} s; median wall of {a.repeat} alternated runs")
    print(" ".join(f"{c:>20}" for c in COLUMNS))
    for r in rows:
        print(" ".join(f"{r[c]:>20.4g}" if isinstance(r[c], float) else f"{r[c]:>20}" for c in COLUMNS))
    if a.csv:
        with open(a.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
