"""An ISPH drop against its WCSPH reference, from the CSVs of tools/drop_measure.py (the ctest
scripts drop_tensile_contrast.sh and tests/long/drop_isph_newtonian.sh).

Asserts that the ISPH drop is in one fragment in every frame, that its interior summation
density stays within --max-density of the first frame, that width/D is within --max-width-diff
of the reference at --times, and, as asked, a retraction of at least --min-retraction D after
the widest frame (Oldroyd-B) or no setback of the width over --max-setback D (Newtonian).
Prints the measured figures; exits non-zero with the failed assertion.
"""
import argparse
import csv


def frames(path):
    with open(path) as f:
        return {round(float(r["tV_over_D"]), 3): r for r in csv.DictReader(f)}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("reference", help="drop_measure CSV of the WCSPH run")
    ap.add_argument("isph", help="drop_measure CSV of the ISPH run")
    ap.add_argument("--times", required=True, help="t V/D at which the widths are compared, comma-separated")
    ap.add_argument("--max-width-diff", type=float, required=True, help="largest |width/D difference|")
    ap.add_argument("--max-density", type=float, default=0.01, help="largest |interior density change| (relative)")
    ap.add_argument("--min-retraction", type=float, help="least retraction after the widest frame, in D")
    ap.add_argument("--max-setback", type=float, help="largest drop of width/D below an earlier maximum, in D")
    a = ap.parse_args()
    wc, isph = frames(a.reference), frames(a.isph)
    broken = [(t, r["fragments"]) for t, r in isph.items() if r["fragments"] != "1"]
    assert not broken, f"ISPH drop in pieces (t V/D, fragments): {broken}"
    err = max(abs(float(r["interior_density_rel_err"])) for r in isph.values())
    times = [float(t) for t in a.times.split(",")]
    worst = max(abs(float(isph[t]["width_over_D"]) - float(wc[t]["width_over_D"])) for t in times)
    widths = [float(isph[t]["width_over_D"]) for t in sorted(isph)]
    retraction = max(widths) - widths[-1]
    setback, widest = 0.0, 0.0
    for w in widths:
        setback, widest = max(setback, widest - w), max(widest, w)
    print(f"ISPH vs WCSPH width/D: max difference {worst:.3f} at t V/D {a.times}; retraction {retraction:.3f} D; "
          f"largest setback {setback:.3f} D; interior density within {100 * err:.2f} %")
    assert err <= a.max_density, f"ISPH interior summation density off by {100 * err:.2f} % (limit {100 * a.max_density:g} %)"
    assert worst <= a.max_width_diff, f"ISPH width/D differs from WCSPH by {worst:.3f} (limit {a.max_width_diff})"
    if a.min_retraction is not None:
        assert retraction >= a.min_retraction, f"ISPH drop retracts by {retraction:.3f} D only (at least {a.min_retraction})"
    if a.max_setback is not None:
        assert setback <= a.max_setback, f"the ISPH drop retracts by {setback:.3f} D (limit {a.max_setback})"


if __name__ == "__main__":
    main()
