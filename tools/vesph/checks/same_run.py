"""`tools/vesph-post same_run_check A.h5 B.h5`: two vesph-1 files of the same scene hold the same
run — the check of a distributed run (mpirun -np N vesph run) against the serial one (issue 36).

The frames of equal time are compared particle by particle, matched by id (the two files may
order them differently: a distributed run writes each frame's particles in id order, moving
ones first); both must hold the same ids. Every floating-point dataset the two frames share
(position, velocity, density, mass, pressure, stresses) is compared by its largest difference
over the largest magnitude of the dataset in A over all compared frames (or an absolute scale
given with --atol, where that is larger), and the diagnostics columns and the gauges' series
likewise.

Usage: same_run_check A.h5 B.h5 [--rtol R] [--atol NAME=VALUE]...
  --rtol R            the largest relative difference allowed (default 1e-9: round-off of a
                      run whose sums are taken in another order, grown over thousands of steps)
  --atol NAME=VALUE   a floor of the scale of dataset NAME, in its unit (e.g. pressure=1e-3
                      Pa: a fluid at rest has pressures of round-off size, whose differences
                      are then compared with 1 mPa instead of with themselves)
Exit status 0 when every frame and column agrees, 1 otherwise, 2 for usage errors.
"""
import argparse
import sys

import numpy as np

from vesph.output import Output, ToolError, run_reporting_errors


def compare(path_a, path_b, floors):
    """Yields (what, relative difference) for every compared dataset; raises ToolError when the
    two files cannot be compared (no common frame time, different particle ids)."""
    with Output(path_a) as a, Output(path_b) as b:
        times_b = {round(t, 15): k for k, (_, t) in enumerate(b.frames)}
        common = [(ka, times_b[round(t, 15)], t) for ka, (_, t) in enumerate(a.frames) if round(t, 15) in times_b]
        if not common:
            raise ToolError(f"{path_a} and {path_b} share no frame time")
        scales = dict(floors)
        for ka, _, _ in common:
            g = a.group(ka)
            for name in g.keys():
                if np.issubdtype(g[name].dtype, np.floating) and g[name].size:
                    scales[name] = max(scales.get(name, 0.0), float(np.max(np.abs(g[name][()]))))
        for ka, kb, t in common:
            ga, gb = a.group(ka), b.group(kb)
            ida, idb = ga["id"][()], gb["id"][()]
            if len(ida) != len(idb) or not np.array_equal(np.sort(ida), np.sort(idb)):
                raise ToolError(f"the frames at t = {t} s hold different particles ({len(ida)} and {len(idb)})")
            oa, ob = np.argsort(ida), np.argsort(idb)
            for name in sorted(set(ga.keys()) & set(gb.keys())):
                va, vb = ga[name][()], gb[name][()]
                if not np.issubdtype(va.dtype, np.floating):
                    if not np.array_equal(va[oa], vb[ob]):
                        yield f"t = {t:g} s {name}", float("inf")
                    continue
                scale = max(scales.get(name, 0.0), 1e-300)
                yield f"t = {t:g} s {name}", float(np.max(np.abs(va[oa] - vb[ob]))) / scale if va.size else 0.0
        columns = ("kinetic_energy", "mass", "max_speed", "max_density_deviation")
        da, db = a.diagnostics(*columns), b.diagnostics(*columns)
        for name, ca, cb in zip(columns, da, db):
            n = min(len(ca), len(cb))
            if len(ca) != len(cb):
                yield f"diagnostics rows ({len(ca)} and {len(cb)})", float("inf")
            scale = max(float(np.max(np.abs(ca[:n]))) if n else 0.0, 1e-300)
            yield f"diagnostics {name}", float(np.max(np.abs(ca[:n] - cb[:n]))) / scale if n else 0.0
        # The gauges' series (a distributed run sums each gauge over every process's particles):
        # the same NaNs (a dry gauge), the values by the column's largest magnitude in A.
        ga_all, gb_all = a.gauges(), b.gauges()
        if set(ga_all) != set(gb_all):
            yield f"gauges ({sorted(ga_all)} and {sorted(gb_all)})", float("inf")
        for gname in sorted(set(ga_all) & set(gb_all)):
            for col, va in ga_all[gname].columns.items():
                vb = gb_all[gname].columns.get(col)
                if vb is None or len(vb) != len(va):
                    yield f"gauge {gname} {col} (rows)", float("inf")
                    continue
                if not np.array_equal(np.isnan(va), np.isnan(vb)):
                    yield f"gauge {gname} {col} (NaN)", float("inf")
                    continue
                ok = ~np.isnan(va)
                scale = max(float(np.max(np.abs(va[ok]))) if ok.any() else 0.0, 1e-300)
                yield f"gauge {gname} {col}", float(np.max(np.abs(va[ok] - vb[ok]))) / scale if ok.any() else 0.0


def run(args):
    worst = 0.0
    failed = []
    floors = {}
    for item in args.atol:
        name, _, value = item.partition("=")
        try:
            floors[name] = float(value)
        except ValueError:
            raise ToolError(f"--atol {item!r}: expected NAME=VALUE") from None
    for what, rel in compare(args.a, args.b, floors):
        worst = max(worst, rel)
        mark = "" if rel <= args.rtol else "   <-- above the tolerance"
        print(f"{what:44s} {rel:.3e}{mark}")
        if rel > args.rtol:
            failed.append(what)
    print(f"largest relative difference {worst:.3e} (tolerance {args.rtol:g}): {'FAIL' if failed else 'PASS'}")
    return 1 if failed else 0


def main():
    p = argparse.ArgumentParser(prog="same_run_check", description=__doc__.splitlines()[0])
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("--rtol", type=float, default=1e-9)
    p.add_argument("--atol", action="append", default=[], metavar="NAME=VALUE")
    return run_reporting_errors("same_run_check", run, p.parse_args())


if __name__ == "__main__":
    sys.exit(main())
