# ISPH density relaxation (solver.density_relaxation_time, theory.md §10, studies.md §5): the
# Newtonian die of the die-swell studies (Re = 5, 10 particles across, the wsph_isph study's
# ISPH scene: predictor form, hydrostatic walls, symmetric grad p) from rest to t = 12.8 ms.
# The feed (parabolic, mean U = 3.333 m/s) fills the die with particles on its lattice.
# Asserted over the frames from 8 ms, on the fluid in the die between x = 0.16 and 0.19 m:
#  - with density_relaxation_time = 0.32 ms (the study's; a tenth of the error per 3.2e-5 s
#    step, under the leapfrog and under the adaptive ARKODE): the particle count within 3 % of the
#    lattice's 300, and the particles' mean displacement between frames (ids tracked) within
#    3 % of U (measured: -0.2 % and +0.4 %);
#  - without it: the die packs (count more than 2 % over the lattice) and the fluid moves more
#    than 5 % slower than the feed (measured: +3.4 % and -14.8 %): the volume drift of the
#    approximate projection that the term removes;
#  - without it but with solver.inlet_condition = "velocity" (the buffer's pressure carries the
#    Neumann data of its velocity, theory.md §10): count and transport within 3 % as well
#    (measured: 0.0 % and -1.1 %; the die's packing starts at a zero-gradient buffer, studies.md §5);
#  - scene errors: density_relaxation_time without [effects.free_surface], and with the divergence
#    cleaning (which would remove the divergence it asks for); inlet_condition = "velocity" with
#    the incremental form.
. "$(dirname "$0")/lib.sh"
$PY "$SRC/tools/die_swell_study.py" deborah --scheme isph --only re5_de0 --dry-run --out "$WORK/s" >/dev/null \
  || fail "die_swell_study.py --dry-run"
S="$WORK/s/deborah_isph/re5_de0/re5_de0.toml"
grep -q '^density_relaxation_time = 0.00032' "$S" && pass || fail "the study's ISPH scene has no density_relaxation_time"
sed '/^density_relaxation_time/d' "$S" >"$WORK/plain.toml"
R="--quiet --set time.end=0.0128 --set output.interval=0.0008"
expect 0 "ok: finished" -- "$VESPH" run "$S" -o "$WORK/relaxed" $R
expect 0 "ok: finished" -- "$VESPH" run "$S" -o "$WORK/arkode" $R --set 'integrator.type="arkode"'
expect 0 "ok: finished" -- "$VESPH" run "$WORK/plain.toml" -o "$WORK/plain" $R
expect 0 "ok: finished" -- "$VESPH" run "$WORK/plain.toml" -o "$WORK/inlet" $R --set 'solver.inlet_condition="velocity"'
$PY - "$WORK/relaxed/re5_de0.h5" "$WORK/arkode/re5_de0.h5" "$WORK/plain/re5_de0.h5" "$WORK/inlet/re5_de0.h5" >"$WORK/pack.log" 2>&1 <<'PYEOF' && pass || fail "die packing: $(tail -6 "$WORK/pack.log")"
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
relaxed, adaptive, plain, inlet = (measure(p) for p in sys.argv[1:5])
print(f"relaxed over 0.32 ms: count {relaxed[0]:+.3%} of the lattice, transport {relaxed[1]:+.3%} of U")
print(f"the same under arkode: count {adaptive[0]:+.3%}, transport {adaptive[1]:+.3%}")
print(f"without: count {plain[0]:+.3%}, transport {plain[1]:+.3%}")
print(f"without, velocity inlet: count {inlet[0]:+.3%}, transport {inlet[1]:+.3%}")
ok = all(abs(q) < 0.03 for q in relaxed + adaptive + inlet) and plain[0] > 0.02 and plain[1] < -0.05
sys.exit(0 if ok else 1)
PYEOF
cat "$WORK/pack.log"
expect 2 "density_relaxation_time needs \[effects.free_surface\]" -- "$VESPH" check "$SRC/cases/poiseuille_newtonian_isph.toml" \
  --set solver.density_relaxation_time=1e-3
expect 2 "density_relaxation_time: expected absent with divergence_cleaning = true" -- "$VESPH" check \
  "$SRC/cases/hydrostatic_tank_isph.toml" --set solver.density_relaxation_time=1e-3 --set solver.divergence_cleaning=true
expect 2 "inlet_condition = .velocity. is not implemented with the incremental form" -- "$VESPH" check \
  "$SRC/cases/channel_inflow_outflow_isph.toml" --set 'solver.inlet_condition="velocity"'
expect 2 "solver.inlet_condition: expected only with a prescribed \[inflow\]" -- "$VESPH" check \
  "$SRC/cases/hydrostatic_tank_isph.toml" --set 'solver.inlet_condition="velocity"'
sed '/^\[inflow\]/,/^\[outflow\]/{/^\[outflow\]/!d}' "$SRC/cases/channel_inflow_outflow_isph.toml" >"$WORK/outflow_only.toml"
expect 2 "solver.inlet_condition: expected only with a prescribed \[inflow\]" -- "$VESPH" check "$WORK/outflow_only.toml" \
  --set 'solver.carried_pressure="predictor"' --set 'solver.inlet_condition="velocity"'
finish
