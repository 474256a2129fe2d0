# Results do not depend on the thread count. The suite runs its tests one thread each
# (tools/run-tests.sh sets OMP_NUM_THREADS=1: two tests side by side on two cores), so this test
# is where the OpenMP paths run: each scene (above kParallelMinimum = 4096 particles, so the
# loops split) for a few steps once with --threads 1 and once with --threads 2, the last frames compared:
#   - the WCSPH Oldroyd-B drop (7845 fluid particles, leapfrog; per-particle loops whose
#     reductions are maxima): identical to 1e-12 of each field's largest value;
#   - the same drop under arkode (the N_Vector sums run in parallel, so the error norms and
#     with them the steps may differ in the last bits): within 1e-7;
#   - the ISPH Newtonian drop (the pressure matrix assembled in parallel, the AMG solve):
#     within 1e-7 (the Krylov tolerance is 1e-8).
. "$(dirname "$0")/lib.sh"

compare() {  # compare NAME TOLERANCE DIR1 DIR2 H5
  $PY - "$2" "$3/$5" "$4/$5" >"$WORK/$1.log" 2>&1 <<'PYEOF' && pass || fail "$1: 1 and 2 threads differ: $(tail -3 "$WORK/$1.log")"
import sys
import h5py, numpy as np
tol = float(sys.argv[1])
with h5py.File(sys.argv[2], "r") as a, h5py.File(sys.argv[3], "r") as b:
    fa, fb = sorted(a["frames"]), sorted(b["frames"])
    assert fa == fb and len(fa) >= 2, (fa, fb)
    last = fa[-1]
    assert abs(a["frames"][last].attrs["time"] - b["frames"][last].attrs["time"]) < 1e-12
    for name in a["frames"][last]:
        x, y = a["frames"][last][name][:], b["frames"][last][name][:]
        if x.dtype.kind not in "fc":
            assert np.array_equal(x, y), name
            continue
        scale = max(np.max(np.abs(x)), 1e-300)
        err = np.max(np.abs(x - y)) / scale
        print(f"{name}: {err:.2e} of the largest value")
        assert err <= tol, (name, err)
PYEOF
  tail -n 2 "$WORK/$1.log"
}

DROP=$SRC/cases/drop_oldroyd_b.toml
for t in 1 2; do
  expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/wcsph$t" --quiet --threads $t --set time.end=2e-4 --set output.interval=1e-4
  expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/arkode$t" --quiet --threads $t --set time.end=5e-5 \
    --set output.interval=2.5e-5 --set 'integrator.type="arkode"'
done
compare wcsph 1e-12 "$WORK/wcsph1" "$WORK/wcsph2" drop_oldroyd_b.h5
compare arkode 1e-7 "$WORK/arkode1" "$WORK/arkode2" drop_oldroyd_b.h5

ISPH=$SRC/cases/drop_newtonian_isph.toml
for t in 1 2; do
  expect 0 "ok: finished" -- "$VESPH" run "$ISPH" -o "$WORK/isph$t" --quiet --threads $t --set time.end=1e-4 --set output.interval=5e-5
done
compare isph 1e-7 "$WORK/isph1" "$WORK/isph2" drop_newtonian_isph.h5
finish
