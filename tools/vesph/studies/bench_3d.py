#!/usr/bin/python3
"""The 3D performance figures of docs/performance.md (issue 33): the 3D periodic box
(cases/bench_periodic_box_3d.toml) against the 2D box (cases/bench_periodic_box.toml), measured
with `vesph bench` in child processes. Timings are printed, never asserted: the machine may be
shared and noisy, so every comparison alternates its two sides within one run, repeats them
--rounds times and reports the median of the per-round ratios (with the spread), and the load
average is printed before and after.

Usage
-----
    tools/vesph-post bench_3d [--vesph build/vesph] [--rounds 5] [--steps-2d 20] [--steps-3d 20]
        [--memory-sizes 24,46] [--scaling-sizes 22,46,100] [--scaling-steps 4] [--scaling-rounds 3]
        [--parts rate,cpu_rate,threads,memory,scaling] [--json OUT.json]

Parts (--parts, default all five)
    rate     pairs/s on one thread, 3D box against 2D box, alternating (each round: one 2D and
             one 3D `vesph bench --threads 1 --repeat 1`): the 3D rate, the 2D rate and the
             ratio 3D/2D per round; the target is >= 0.8.
    cpu_rate as rate, per CPU second instead of wall second: the CPU time (user + system) of a
             run of --steps-2d/--steps-3d steps minus that of a 2-step run (the scene set-up
             cancels), against the pairs of the difference. The time a process waits for a CPU
             on a busy machine does not count, so this ratio is the least distorted by load.
    threads  the 2-thread speed-up of each box: each round is one `vesph bench --threads 1,2
             --repeat 1` (1 and 2 threads alternate in one process); speed-up = pairs/s with 2
             threads / pairs/s with 1; the target is >= 1.8.
    memory   the peak resident memory (VmHWM, as /usr/bin/time -v reports it) of the 3D box at
             two sizes n^3 (--memory-sizes n1,n2), Newtonian and with an Oldroyd-B stress
             (velocity gradient, oldroyd_b, stress divergence switched on by --set): the slope
             (peak2 - peak1)/(N2 - N1) is the memory per particle without the fixed cost of the
             process; targets <= 1024 bytes Newtonian, <= 2048 with the stress.
    scaling  one thread, the 3D box at n^3 particles for each n of --scaling-sizes, the same
             --scaling-steps at every size (the neighbour-list rebuilds then fall on the same
             steps: they depend on the speed and the spacing, not on N): seconds per
             particle-step, the sizes alternating in --scaling-rounds rounds, the median per
             size against the smallest size's; the target is within 20 %.

Both boxes run the same number of steps by default (20): their particles move the same
distance per step relative to the spacing, so their Verlet lists are rebuilt on the same steps
(about every 12th) and the rates compare like with like.

The box sizes are set with --set domain.max and blocks[0].max = n dx (dx = 1 mm). The
wall time of `vesph bench` is the integration alone (right-hand sides, neighbour lists,
diagnostics; not the scene set-up). Exit status 0, or 1 when a run fails.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys

from vesph import REPO

# build/vesph of this repository (as vesph.catalogue's default; not imported from there so that
# this script needs the Python standard library only, e.g. on a benchmark machine without h5py)
DEFAULT_VESPH = os.path.join(REPO, "build", "vesph")

CASE_2D = os.path.join(REPO, "cases", "bench_periodic_box.toml")
CASE_3D = os.path.join(REPO, "cases", "bench_periodic_box_3d.toml")
OLDROYD_B = ["effects.velocity_gradient={}", "effects.oldroyd_b.relaxation_time=0.02",
             "effects.oldroyd_b.polymer_viscosity=1e-3", "effects.stress_divergence={}"]
SPACING = 1.0e-3  # m, the 3D case's particles.spacing


class BenchError(Exception):
    pass


def size_sets(n):
    side = f"{n * SPACING!r}"
    return [f"domain.max=[{side},{side},{side}]", f"blocks[0].max=[{side},{side},{side}]"]


def bench(vesph, case, steps, threads, sets=(), env=None):
    """One `vesph bench` run (repeat 1): a list of rows, one per thread count, each a dict of
    the table's columns."""
    cmd = [vesph, "bench", case, "--steps", str(steps), "--threads", ",".join(map(str, threads)),
           "--repeat", "1"]
    for s in sets:
        cmd += ["--set", s]
    cpu0 = children_cpu()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    cpu = children_cpu() - cpu0  # the child's CPU time, user + system, scene set-up included
    if p.returncode != 0:
        raise BenchError(f"{' '.join(cmd)} failed (exit {p.returncode}): {p.stderr.strip()[-400:]}")
    rows = []
    keys = ["threads", "particles", "steps", "wall_s", "particle_steps_s", "pairs_s", "median_pairs_s",
            "pairs_rhs", "peak_mib", "bytes_particle"]
    for line in p.stdout.splitlines():
        parts = line.split()
        if len(parts) == len(keys) and parts[0].isdigit():
            rows.append(dict(zip(keys, map(float, parts))))
    if len(rows) != len(threads):
        raise BenchError(f"{' '.join(cmd)}: could not read the table:\n{p.stdout}")
    for r in rows:
        r["cpu_s"] = cpu
        r["pairs"] = r["pairs_s"] * r["wall_s"]
    return rows


def children_cpu():
    """CPU seconds (user + system) of the finished child processes so far."""
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def load():
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def spread(values):
    return f"median {statistics.median(values):.3g} (min {min(values):.3g}, max {max(values):.3g})"


def part_rate(a, res):
    print(f"\n== rate: pairs/s on one thread, 3D box against 2D box, {a.rounds} alternating rounds")
    print(f"{'round':>5} {'2D pairs/s':>12} {'3D pairs/s':>12} {'3D/2D':>7} {'3D pairs/particle':>18}")
    r2, r3, ratio = [], [], []
    for k in range(a.rounds):
        two = bench(a.vesph, CASE_2D, a.steps_2d, [1])[0]
        three = bench(a.vesph, CASE_3D, a.steps_3d, [1])[0]
        r2.append(two["pairs_s"])
        r3.append(three["pairs_s"])
        ratio.append(three["pairs_s"] / two["pairs_s"])
        print(f"{k + 1:>5} {two['pairs_s']:>12.4g} {three['pairs_s']:>12.4g} {ratio[-1]:>7.3f} "
              f"{three['pairs_rhs'] / three['particles']:>18.1f}", flush=True)
    print(f"2D: {spread(r2)} pairs/s; 3D: {spread(r3)} pairs/s; 3D/2D {spread(ratio)}"
          f" -> target >= 0.8 {'met' if statistics.median(ratio) >= 0.8 else 'NOT met'}")
    res["rate"] = {"pairs_s_2d": r2, "pairs_s_3d": r3, "ratio": ratio}


def part_cpu_rate(a, res):
    print(f"\n== cpu_rate: pairs per CPU second on one thread, 3D box against 2D box, {a.rounds} alternating rounds")
    print("   (CPU time of a run of the given steps minus that of a 2-step run: the set-up cancels; time the")
    print("   process waited for a CPU does not count, so this is the figure a busy machine distorts least)")
    print(f"{'round':>5} {'2D pairs/cpu-s':>15} {'3D pairs/cpu-s':>15} {'3D/2D':>7}")
    r2, r3, ratio = [], [], []
    for k in range(a.rounds):
        rates = []
        for case, steps in ((CASE_2D, a.steps_2d), (CASE_3D, a.steps_3d)):
            long_run = bench(a.vesph, case, steps, [1])[0]
            short_run = bench(a.vesph, case, 2, [1])[0]
            rates.append((long_run["pairs"] - short_run["pairs"]) / (long_run["cpu_s"] - short_run["cpu_s"]))
        r2.append(rates[0])
        r3.append(rates[1])
        ratio.append(rates[1] / rates[0])
        print(f"{k + 1:>5} {rates[0]:>15.4g} {rates[1]:>15.4g} {ratio[-1]:>7.3f}", flush=True)
    print(f"2D: {spread(r2)}; 3D: {spread(r3)} pairs per CPU second; 3D/2D {spread(ratio)}"
          f" -> target >= 0.8 {'met' if statistics.median(ratio) >= 0.8 else 'NOT met'}")
    res["cpu_rate"] = {"pairs_per_cpu_s_2d": r2, "pairs_per_cpu_s_3d": r3, "ratio": ratio}


def part_threads(a, res):
    print(f"\n== threads: 2-thread speed-up, {a.rounds} rounds of 1 and 2 threads alternating")
    print(f"{'round':>5} {'box':>4} {'1 thread':>12} {'2 threads':>12} {'speed-up':>9}")
    out = {}
    for k in range(a.rounds):
        for label, case, steps in (("3D", CASE_3D, a.steps_3d), ("2D", CASE_2D, a.steps_2d)):
            one, two = bench(a.vesph, case, steps, [1, 2])
            out.setdefault(label, []).append(two["pairs_s"] / one["pairs_s"])
            print(f"{k + 1:>5} {label:>4} {one['pairs_s']:>12.4g} {two['pairs_s']:>12.4g} {out[label][-1]:>9.3f}",
                  flush=True)
    for label, s in out.items():
        print(f"{label}: speed-up {spread(s)} -> target >= 1.8 {'met' if statistics.median(s) >= 1.8 else 'NOT met'}")
    res["threads"] = out


def part_memory(a, res):
    n1, n2 = a.memory_sizes
    print(f"\n== memory: peak resident memory of the 3D box at {n1}^3 and {n2}^3 particles, one thread")
    out = {}
    for label, extra, target in (("newtonian", [], 1024), ("oldroyd_b", OLDROYD_B, 2048)):
        rows = [bench(a.vesph, CASE_3D, 2, [1], size_sets(n) + extra)[0] for n in (n1, n2)]
        slope = (rows[1]["peak_mib"] - rows[0]["peak_mib"]) * 1048576 / (rows[1]["particles"] - rows[0]["particles"])
        for r in rows:
            print(f"   {label:<10} {r['particles']:>9.0f} particles: peak {r['peak_mib']:.1f} MiB, "
                  f"(peak - start)/N = {r['bytes_particle']:.0f} bytes")
        print(f"   {label:<10} slope {slope:.0f} bytes/particle -> target <= {target} "
              f"{'met' if slope <= target else 'NOT met'}")
        out[label] = {"particles": [r["particles"] for r in rows], "peak_mib": [r["peak_mib"] for r in rows],
                      "bytes_per_particle": slope}
    res["memory"] = out


def part_scaling(a, res):
    print(f"\n== scaling: one thread, {a.scaling_steps} steps at every size, the sizes alternating in "
          f"{a.scaling_rounds} rounds (median per size)")
    print(f"{'round':>5} {'particles':>10} {'wall s':>8} {'s/particle-step':>16} {'pairs/s':>10}")
    per = {}
    for k in range(a.scaling_rounds):
        for n in a.scaling_sizes:
            r = bench(a.vesph, CASE_3D, a.scaling_steps, [1], size_sets(n))[0]
            t = r["wall_s"] / (r["particles"] * r["steps"])
            per.setdefault(int(r["particles"]), []).append(t)
            print(f"{k + 1:>5} {r['particles']:>10.0f} {r['wall_s']:>8.3f} {t:>16.4g} {r['pairs_s']:>10.4g}", flush=True)
    sizes_n = list(per)
    ref = statistics.median(per[sizes_n[0]])
    out = []
    for n in sizes_n:
        m = statistics.median(per[n])
        out.append({"particles": n, "s_per_particle_step": per[n], "median": m, "vs_smallest": m / ref})
        print(f"{n:>10} particles: {spread(per[n])} s per particle-step, {m / ref:.3f} of the smallest size's")
    worst = max(abs(o["vs_smallest"] - 1) for o in out)
    print(f"largest deviation from the smallest size (medians): {100 * worst:.1f} % -> target <= 20 % "
          f"{'met' if worst <= 0.2 else 'NOT met'}")
    res["scaling"] = out


def sizes(text, count=None):
    vals = [int(s) for s in text.split(",")]
    if any(v < 8 for v in vals) or (count and len(vals) != count):
        raise argparse.ArgumentTypeError(f"{text!r}: expected {count or 'some'} sizes n >= 8")
    return vals


def main(argv=None):
    ap = argparse.ArgumentParser(prog="bench_3d", description="3D benchmark figures (docs/performance.md)")
    ap.add_argument("--vesph", default=DEFAULT_VESPH)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps-2d", type=int, default=20)
    ap.add_argument("--steps-3d", type=int, default=20)
    ap.add_argument("--memory-sizes", type=lambda s: sizes(s, 2), default=[24, 46])
    ap.add_argument("--scaling-sizes", type=sizes, default=[22, 46, 100])
    ap.add_argument("--scaling-steps", type=int, default=4)
    ap.add_argument("--scaling-rounds", type=int, default=3)
    ap.add_argument("--parts", default="rate,cpu_rate,threads,memory,scaling")
    ap.add_argument("--json", metavar="OUT.json")
    a = ap.parse_args(argv)
    parts = a.parts.split(",")
    known = {"rate": part_rate, "cpu_rate": part_cpu_rate, "threads": part_threads, "memory": part_memory,
             "scaling": part_scaling}
    for p in parts:
        if p not in known:
            ap.error(f"unknown part {p!r} (choose from {', '.join(known)})")
    res = {"vesph": a.vesph, "cpus": os.cpu_count(), "load_before": load()}
    print(f"bench_3d: {a.vesph}; {os.cpu_count()} CPUs; load average (1 min) {res['load_before']:.2f}")
    try:
        for p in parts:
            known[p](a, res)
    except BenchError as e:
        print(f"bench_3d: error: {e}", file=sys.stderr)
        return 1
    res["load_after"] = load()
    print(f"\nload average (1 min) after: {res['load_after']:.2f}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
