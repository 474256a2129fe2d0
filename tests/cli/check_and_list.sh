# `vesph check` prints the resolved scene with every default; `vesph list` names what exists.
. "$(dirname "$0")/lib.sh"
expect 0 "max_density_deviation = 0.5" -- "$VESPH" check "$SCENE"
grep -q "viscous_coefficient = 0.125" "$WORK/out" && pass || fail "check does not print the integrator defaults"
grep -q "skin = 0.1" "$WORK/out" && pass || fail "check does not print the neighbour defaults"
expect 0 "1000 particles \(800 fluid, 200 fixed\)" -- "$VESPH" check "$SCENE"
expect 0 "viscosity = 0.002" -- "$VESPH" check "$SCENE" --set fluid.viscosity=2e-3
expect 0 "leapfrog" -- "$VESPH" list
for word in continuity equation_of_state pressure_gradient viscosity body_force midpoint cubic quintic wendland_c2 dummy_walls "treatment = \"image\""; do
  grep -q "$word" "$WORK/out" && pass || fail "vesph list does not mention $word"
done
# --json: the same for programs, with the default step-limit coefficients and kernel tables
expect 0 '"step_limits"' -- "$VESPH" list --json
/usr/bin/python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
s = d["step_limits"]
assert s["cfl"] == {"wcsph": 0.125, "isph": 0.175}, s
assert (s["viscous_coefficient"], s["force_coefficient"]) == (0.125, 0.25), s
assert [k["name"] for k in d["kernels"]] == ["cubic", "quintic", "wendland_c2"]
assert all(len(k["samples"][dim]["W"]) == k["table_intervals"] + 1 for k in d["kernels"] for dim in ("2", "3"))
' "$WORK/out" && pass || fail "vesph list --json: step limits or kernels"
expect 2 "subcommand" -- "$VESPH"
finish
