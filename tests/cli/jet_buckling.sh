# Jet on a plate at the CI resolution (3D; cases/jet_buckling_newtonian.toml at D = 4 dx instead
# of 8 dx: dx = 1 mm, the plate and the nozzle's buffer 3 spacings deep), Re = 0.5, H/D = 10,
# run to t = 0.24 s (t U/D = 30):
#   - the run finishes without a blow-up (the density stays within 10 % of rho0);
#   - jet_buckling_measure reads it and finds no void wider than 3 dx inside the fluid
#     (--max-void-gap 3; the run's largest is 2.5 dx).
# The buckling itself is not asserted: at this resolution (and at D = 8 dx so far) the jet's
# axis above the pile stays within 0.25 D of the nozzle's, against Cruickshank & Munson's
# criterion (docs/validation.md §19, "not reproduced"). The measure's indicator is printed.
# About 33 s of CPU time single-threaded (measured on the shared machine: 32.6 s user). The
# viscous step coefficient stays at the default 0.125 here (the D = 4 dx jets ran to 0.3 s with
# it; the case takes 0.0625, which the D = 8 dx jet needs), half the cost.
. "$(dirname "$0")/lib.sh"
CASE=$SRC/cases/jet_buckling_newtonian.toml
expect 0 "ok: finished" -- "$VESPH" run "$CASE" -o "$WORK/run" --quiet --set time.end=0.24 --set output.interval=0.01 \
  --set particles.spacing=1.0e-3 --set 'domain.min=[-12.0e-3,-3.0e-3,-12.0e-3]' \
  --set 'domain.max=[12.0e-3,43.0e-3,12.0e-3]' --set 'blocks[1].min=[-12.0e-3,-3.0e-3,-12.0e-3]' \
  --set 'inflow.max=[2.0e-3,43.0e-3,2.0e-3]' --set integrator.viscous_coefficient=0.125
$PY - "$WORK/run/summary.json" >"$WORK/summary.log" 2>&1 <<'PYEOF' && pass || fail "summary: $(tail -3 "$WORK/summary.log")"
import json, sys
s = json.load(open(sys.argv[1]))
print(f"status {s['status']}, max density deviation {s['max_density_deviation']:.4f}, "
      f"fluid particles {s['fluid_particles']}, escaped {s['escaped']}")
assert s["status"] == "ok" and s["max_density_deviation"] < 0.1
PYEOF
cat "$WORK/summary.log"
expect 0 "RESULT: PASS" -- "$SRC/tools/vesph-post" jet_buckling_measure "$WORK/run/jet_buckling_newtonian.h5" \
  --no-png --max-void-gap 3
grep -E "^(largest|onset|coiling|oscillation|voids)" "$WORK/out"
finish
