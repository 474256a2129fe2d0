# ISPH density relaxation (solver.density_relaxation, theory.md §10, studies.md §5): the
# Newtonian die of the die-swell studies (Re = 5, 10 particles across, the wsph_isph study's
# ISPH scene: predictor form, hydrostatic walls, symmetric grad p) from rest to t = 12.8 ms.
# The feed (parabolic, mean U = 3.333 m/s) fills the die with particles on its lattice.
# Asserted over the frames from 8 ms, on the fluid in the die between x = 0.16 and 0.19 m:
#  - with density_relaxation = 0.1 (the study's): the particle count within 3 % of the
#    lattice's 300, and the particles' mean displacement between frames (ids tracked) within
#    3 % of U (measured: -0.2 % and +0.4 %);
#  - without it: the die packs (count more than 2 % over the lattice) and the fluid moves more
#    than 5 % slower than the feed (measured: +3.4 % and -14.8 %): the volume drift of the
#    approximate projection that the term removes;
#  - scene errors: density_relaxation without [effects.free_surface], and with the divergence
#    cleaning (which would remove the divergence it asks for).
. "$(dirname "$0")/lib.sh"
$PY "$SRC/tools/die_swell_study.py" deborah --scheme isph --only re5_de0 --dry-run --out "$WORK/s" >/dev/null \
  || fail "die_swell_study.py --dry-run"
S="$WORK/s/deborah_isph/re5_de0/re5_de0.toml"
for g in 0.1 0; do
  expect 0 "ok: finished" -- "$VESPH" run "$S" -o "$WORK/g$g" --quiet --set time.end=0.0128 \
    --set output.interval=0.0008 --set solver.density_relaxation=$g
done
$PY - "$WORK/g0.1/re5_de0.h5" "$WORK/g0/re5_de0.h5" >"$WORK/pack.log" 2>&1 <<'PYEOF' && pass || fail "die packing: $(tail -6 "$WORK/pack.log")"
import sys
import h5py
import numpy as np
U, x0, x1, dx = 5.0 / 1.5, 0.16, 0.19, 0.001
lattice = round((x1 - x0) / dx) * 10
def measure(path):
    with h5py.File(path, "r") as f:
        fr = f["frames"]
        names = [k for k in sorted(fr) if fr[k].attrs["time"] >= 0.008 - 1e-9]
        counts, speeds = [], []
        for a, b in zip(names[:-1], names[1:]):
            A, B = fr[a], fr[b]
            xa, ka = A["position"][:], A["kind"][:]
            inside = (ka == 0) & (xa[:, 0] > x0) & (xa[:, 0] < x1)
            counts.append(inside.sum())
            _, ia, ib = np.intersect1d(A["id"][:], B["id"][:], return_indices=True)
            keep = inside[ia]
            dt = B.attrs["time"] - A.attrs["time"]
            speeds.append(((B["position"][:][ib[keep], 0] - xa[ia[keep], 0]) / dt).mean())
    return np.mean(counts) / lattice - 1, np.mean(speeds) / U - 1
relaxed, plain = measure(sys.argv[1]), measure(sys.argv[2])
print(f"density_relaxation 0.1: count {relaxed[0]:+.3%} of the lattice, transport {relaxed[1]:+.3%} of U")
print(f"without: count {plain[0]:+.3%}, transport {plain[1]:+.3%}")
ok = abs(relaxed[0]) < 0.03 and abs(relaxed[1]) < 0.03 and plain[0] > 0.02 and plain[1] < -0.05
sys.exit(0 if ok else 1)
PYEOF
cat "$WORK/pack.log"
expect 2 "density_relaxation needs \[effects.free_surface\]" -- "$VESPH" check "$SRC/cases/poiseuille_newtonian_isph.toml" \
  --set solver.density_relaxation=0.1
expect 2 "density_relaxation: expected 0 with divergence_cleaning = true" -- "$VESPH" check "$SRC/cases/hydrostatic_tank_isph.toml" \
  --set solver.density_relaxation=0.1 --set solver.divergence_cleaning=true
finish
