# ISPH wall impact (docs/validation.md §11, theory.md §10): a flat block of viscous fluid
# (50 x 25 particles, dx = 0.2 mm) falls at 1 m/s onto a wall, with the predictor form
# (solver.carried_pressure = "predictor") and the no-penetration wall condition
# (solver.wall_condition = "no_penetration"), the outermost row and the cut rows as free
# surface (method = "marrone", threshold = 0.97). Asserted, over the frames to t = 10 ms:
#  - no fluid particle comes closer than dx/4 to the wall surface (measured: 0.69 dx at the
#    closest; the incremental form with the hydrostatic walls pushed particles 0.47 dx into
#    the wall, with +-4e5 Pa of pressure noise);
#  - the fluid pressure stays below 2e4 Pa (measured peak in the frames 4.3e3 Pa at 1 ms);
#  - at 10 ms the block is at rest (max |v| < 0.03 m/s; measured 0.009) and its largest
#    pressure within 10 % of rho g H = 49.05 Pa (measured 49.0);
#  - scene errors: no_penetration with the incremental form, predictor without a carried
#    pressure.
. "$(dirname "$0")/lib.sh"
cat >"$WORK/block.toml" <<'TOML'
name = "block"
dimension = 2
[domain]
min = [-0.02, -0.0006]
max = [0.02, 0.02]
[particles]
spacing = 2.0e-4
kernel = "cubic"
smoothing_ratio = 1.5
[fluid]
density = 1000.0
viscosity = 4.0
[[blocks]]
kind = "fluid"
min = [-0.005, 0.001]
max = [0.005, 0.006]
velocity = [0.0, -1.0]
[[blocks]]
kind = "wall"
min = [-0.015, -0.0006]
max = [0.015, 0.0]
[effects.pressure_gradient]
form = "renormalised"
[effects.viscosity]
[effects.body_force]
acceleration = [0.0, -9.81]
[effects.free_surface]
method = "marrone"
threshold = 0.97
[solver]
scheme = "isph"
linear_solver = "umfpack"
carried_pressure = "predictor"
wall_condition = "no_penetration"
[integrator]
type = "leapfrog"
[time]
end = 0.01
[output]
interval = 0.0005
TOML
expect 0 "ok: finished" -- "$VESPH" run "$WORK/block.toml" -o "$WORK/block" --quiet
$PY - "$WORK/block/block.h5" >"$WORK/block.log" 2>&1 <<'PYEOF' && pass || fail "block impact: $(tail -6 "$WORK/block.log")"
import sys
import h5py
import numpy as np
dx, rho, g, H = 2.0e-4, 1000.0, 9.81, 0.005
with h5py.File(sys.argv[1], "r") as f:
    frames = f["frames"]
    closest, peak = np.inf, 0.0
    for k in frames:
        fr = frames[k]
        fluid = fr["kind"][:] == 0
        closest = min(closest, fr["position"][:][fluid, 1].min())
        peak = max(peak, np.abs(fr["pressure"][:][fluid]).max())
    last = frames[sorted(frames)[-1]]
    fluid = last["kind"][:] == 0
    speed = np.linalg.norm(last["velocity"][:][fluid], axis=1).max()
    p_max = last["pressure"][:][fluid].max()
    t = last.attrs["time"]
print(f"closest {closest / dx:.3f} dx, peak |p| {peak:.4g} Pa, at t = {t:.4g} s: max |v| {speed:.3g} m/s, max p {p_max:.4g} Pa (rho g H {rho * g * H:.4g})")
ok = closest > 0.25 * dx and peak < 2e4 and abs(t - 0.01) < 1e-9 and speed < 0.03 and abs(p_max / (rho * g * H) - 1) < 0.1
sys.exit(0 if ok else 1)
PYEOF
expect 2 "wall_condition = \"no_penetration\" is not implemented with the incremental form" -- \
  "$VESPH" check "$WORK/block.toml" --set 'solver.carried_pressure="increment"'
sed '/^\[effects.pressure_gradient\]/,/^form/d' "$WORK/block.toml" >"$WORK/plain.toml"
expect 2 "carried_pressure = \"predictor\" needs \[effects.pressure_gradient\]" -- "$VESPH" check "$WORK/plain.toml"
finish
