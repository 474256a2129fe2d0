# Disk blocks (Fang et al. 2006 §4: the Cartesian lattice cut by the circle), per-block initial
# velocity, and free-surface detection by number density (thesis §4.2).
. "$(dirname "$0")/lib.sh"
cat > "$WORK/drop.toml" <<'TOML'
name = "drop"
dimension = 2
[domain]
min = [-0.051, -0.0012]
max = [0.051, 0.06]
[particles]
spacing = 2.0e-4
kernel = "cubic"
smoothing_ratio = 1.5
[fluid]
density = 1000.0
viscosity = 4.0
[[blocks]]
kind = "fluid"
shape = "disk"
centre = [0.0, 0.04]
diameter = 0.02
velocity = [0.0, -1.0]
[[blocks]]
kind = "wall"
min = [-0.05, -0.0012]
max = [0.05, 0.0]
[effects.continuity]
[effects.equation_of_state]
sound_speed = 12.5
[effects.pressure_gradient]
free_surface_mirror = true
[effects.viscosity]
[effects.free_surface]
[effects.body_force]
acceleration = [0.0, -9.81]
[time]
end = 2.0e-5
TOML
# Fang's drop: D = 2 cm at 0.02 cm spacing is 7845 particles (the lattice points of a disk of
# radius 50 spacings, Gauss' circle problem N(50) = 7845).
expect 0 "7845 fluid" -- "$VESPH" check "$WORK/drop.toml"
expect 0 "ok: finished" -- "$VESPH" run "$WORK/drop.toml" -o "$WORK/run" --quiet
$PY - "$WORK/run/drop.h5" <<'PY' && pass || fail "disk / free-surface frame check"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1])
g = f["frames"][sorted(f["frames"].keys())[0]]
kind, x, v, fs = g["kind"][...], g["position"][...], g["velocity"][...], g["free_surface"][...]
fl = kind == 0
r = np.hypot(x[fl, 0], x[fl, 1] - 0.04)
dx = 2e-4
ok = True
# every particle on the disk's outermost lattice layer is flagged, none deeper than 2 spacings
surf = fs[fl] == 1
if not np.all(surf[r > 0.01 - 0.5 * dx]): print("an outermost particle is not flagged"); ok = False
if np.any(surf[r < 0.01 - 2 * dx]): print("a particle 2 spacings inside is flagged"); ok = False
if np.any(fs[~fl] != 0): print("a wall particle is flagged"); ok = False
if not np.allclose(v[fl], [0.0, -1.0]): print("the block velocity is not the initial velocity"); ok = False
if not np.allclose(v[~fl], 0.0): print("walls move"); ok = False
print("flagged", int(surf.sum()), "of", int(fl.sum()))
sys.exit(0 if ok else 1)
PY
# jitter: reproducible for a seed, different for another, within jitter/2 dx of the lattice
for run in a b c; do
  seed=1; [ $run = c ] && seed=2
  expect 0 "ok: finished" -- "$VESPH" run "$WORK/drop.toml" -o "$WORK/jit_$run" --quiet --set time.end=1e-5 \
    --set 'output.times=[1e-5]' --set blocks[0].jitter=0.2 --set blocks[0].seed=$seed
done
$PY - "$WORK" <<'PY' && pass || fail "jittered disk: not reproducible or not within the bound"
import sys, h5py, numpy as np
w = sys.argv[1]
def first(run):
    with h5py.File(f"{w}/jit_{run}/drop.h5", "r") as f:
        g = f["frames"]["000000"]
        return g["position"][...][g["kind"][...] == 0]
a, b, c = first("a"), first("b"), first("c")
dx = 2e-4
lattice = np.round((a - [0.0, 0.04]) / dx) * dx + [0.0, 0.04]
ok = np.array_equal(a, b) and not np.array_equal(a, c) and np.abs(a - lattice).max() <= 0.1 * dx * (1 + 1e-9) \
     and np.abs(a - lattice).max() > 0.05 * dx
print("max displacement / dx", np.abs(a - lattice).max() / dx)
sys.exit(0 if ok else 1)
PY
expect 2 "blocks\[0\].jitter: expected a number in \[0, 0.5\]" -- "$VESPH" check "$WORK/drop.toml" --set blocks[0].jitter=0.7
# errors
sed -e '/^\[effects.free_surface\]/d' "$WORK/drop.toml" > "$WORK/no_detection.toml"
expect 2 "free_surface_mirror needs .*add \[effects.free_surface\]" -- "$VESPH" check "$WORK/no_detection.toml"
expect 2 "threshold" -- "$VESPH" check "$WORK/drop.toml" --set 'effects.free_surface.threshold=1.5'
expect 2 "inside the domain" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].centre=[0.0, 0.055]'
expect 2 "overlaps.*bounding box" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].centre=[0.0, 0.0095]'
expect 2 "\"box\" for a wall block" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[1].shape="disk"'
expect 2 "diameter" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].diameter=-1.0'
finish
