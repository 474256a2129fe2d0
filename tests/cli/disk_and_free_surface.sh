# Disk blocks (Fang et al. 2006 §4: the Cartesian lattice cut by the circle), per-block initial
# velocity, and free-surface detection by number density (thesis §4.2) and by Marrone's test (2D, 3D).
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
# The Marrone et al. (2010) test (effects.free_surface.method = "marrone"): on the jittered disk
# the number density with a threshold near 1 (0.94, the ISPH Oldroyd-B drop's) also flags
# particles deep inside, where the jitter leaves a sparse spot; Marrone's scan region flags the
# outermost particles only; with a threshold as well, a particle is flagged by its number
# density only within one kernel support of an outermost particle. A block lying on the wall:
# its bottom row touches the wall and is not on the free surface, its top row is.
sed -e 's/^\[effects.free_surface\]/[[blocks]]\nkind = "fluid"\nmin = [-0.04, 0.0]\nmax = [-0.02, 0.004]\n[effects.free_surface]/' \
  "$WORK/drop.toml" > "$WORK/fs.toml"
for m in nd marrone near; do
  case $m in
    nd) set -- --set effects.free_surface.threshold=0.94 ;;
    marrone) set -- --set 'effects.free_surface.method="marrone"' ;;
    near) set -- --set 'effects.free_surface.method="marrone"' --set effects.free_surface.threshold=0.94 ;;
  esac
  expect 0 "ok: finished" -- "$VESPH" run "$WORK/fs.toml" -o "$WORK/fs_$m" --quiet --set time.end=1e-5 \
    --set 'output.times=[1e-5]' --set blocks[0].jitter=0.2 "$@"
done
$PY - "$WORK" <<'PY' && pass || fail "Marrone free-surface flags"
import sys, h5py, numpy as np
from scipy.spatial import cKDTree
w, dx, R = sys.argv[1], 2e-4, 0.01
support = 3 * dx                                               # cubic spline, h = 1.5 dx
def frame(m):
    with h5py.File(f"{w}/fs_{m}/drop.h5", "r") as f:
        g = f["frames"]["000000"]
        fl = g["kind"][...] == 0
        return g["position"][...][fl], g["free_surface"][...][fl] == 1
x, nd = frame("nd")
flags = {"nd": nd, "marrone": frame("marrone")[1], "near": frame("near")[1]}
drop = x[:, 1] > 0.02
lat = np.round((x[drop] - [0.0, 0.04]) / dx) * dx              # lattice position in the disk
r = np.hypot(lat[:, 0], lat[:, 1])
box = x[~drop]
inner_x = (box[:, 0] > -0.04 + 2 * dx) & (box[:, 0] < -0.02 - 2 * dx)
ok = True
for m, s in flags.items():
    sd, sb = s[drop], s[~drop]
    deep = int(np.sum(sd[r < R - 5 * dx]))
    print(f"{m}: flagged {int(sd.sum())} in the disk, {deep} deeper than 5 dx; box bottom row flagged "
          f"{int(sb[inner_x & (box[:, 1] < dx)].sum())}, top row {int(sb[box[:, 1] > 0.004 - dx].sum())} "
          f"of {int(np.sum(box[:, 1] > 0.004 - dx))}")
    if m == "nd":
        # the weakness the Marrone test removes (a characterisation of this seed's lattice)
        if deep == 0: print("number density 0.94: expected flags deep inside the jittered disk"); ok = False
        continue
    if deep: print(f"{m}: a disk particle deeper than 5 dx is flagged"); ok = False
    if not np.all(sd[r > R - 0.5 * dx]): print(f"{m}: an outermost disk particle is not flagged"); ok = False
    if sb[inner_x & (box[:, 1] < dx)].any(): print(f"{m}: a particle lying on the wall is flagged"); ok = False
    if not sb[box[:, 1] > 0.004 - dx].all(): print(f"{m}: a particle of the block's top row is not flagged"); ok = False
marrone, near = flags["marrone"], flags["near"]
if np.any(marrone[drop][r < R - 1.5 * dx]): print("marrone: a disk particle deeper than 1.5 dx is flagged"); ok = False
# near = marrone, plus the number-density flags within one support of a marrone flag
close = np.zeros(len(x), bool)
for i, js in enumerate(cKDTree(x).query_ball_point(x[marrone], support * (1 - 1e-9))):
    close[js] = True
expected = marrone | (nd & close)
if not np.array_equal(near, expected):
    print(f"near: {int(np.sum(near != expected))} flags differ from marrone + number density within a support"); ok = False
sys.exit(0 if ok else 1)
PY
# In 3D: a box of fluid (20 x 20 x 10 particles) resting on a wall; Marrone's test flags exactly
# the top and side layers, not the row on the wall and nothing inside.
# (the particles and the fluid of the 2D scene above)
{
  printf 'name = "b3"\ndimension = 3\n[domain]\nmin = [-0.004, -0.004, -0.0006]\nmax = [0.004, 0.004, 0.004]\n'
  sed -n '/^\[particles\]/,/^viscosity/p' "$WORK/drop.toml"
} > "$WORK/box3.toml"
cat >> "$WORK/box3.toml" <<'TOML'
[[blocks]]
kind = "fluid"
min = [-0.002, -0.002, 0.0]
max = [0.002, 0.002, 0.002]
[[blocks]]
kind = "wall"
min = [-0.003, -0.003, -0.0006]
max = [0.003, 0.003, 0.0]
[effects.continuity]
[effects.equation_of_state]
sound_speed = 12.5
[effects.pressure_gradient]
[effects.viscosity]
[effects.free_surface]
method = "marrone"
[time]
end = 1.0e-5
[output]
times = [1.0e-5]
TOML
expect 0 "ok: finished" -- "$VESPH" run "$WORK/box3.toml" -o "$WORK/box3" --quiet
$PY - "$WORK/box3/b3.h5" <<'PY' && pass || fail "3D Marrone flags"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    g = f["frames"]["000000"]
    fluid = g["kind"][...] == 0
    x, s = g["position"][...][fluid], g["free_surface"][...][fluid] == 1
dx, half, height = 2e-4, 0.002, 0.002
outer = (x[:, 2] > height - dx) | (np.abs(x[:, 0]) > half - dx) | (np.abs(x[:, 1]) > half - dx)
print(f"{len(x)} fluid, {int(s.sum())} flagged, {int(outer.sum())} in the top and side layers")
sys.exit(0 if len(x) == 4000 and np.array_equal(s, outer) else 1)
PY
expect 2 "effects.free_surface.lambda_interior: expected absent with method = \"number_density\"" -- "$VESPH" check "$WORK/fs.toml" \
  --set effects.free_surface.lambda_interior=0.7
expect 2 "effects.free_surface.lambda_interior: expected at least lambda_surface" -- "$VESPH" check "$WORK/fs.toml" \
  --set 'effects.free_surface.method="marrone"' --set effects.free_surface.lambda_surface=0.5 --set effects.free_surface.lambda_interior=0.4
expect 2 "effects.free_surface.method" -- "$VESPH" check "$WORK/fs.toml" --set 'effects.free_surface.method="divergence"'
# errors
sed -e '/^\[effects.free_surface\]/d' "$WORK/drop.toml" > "$WORK/no_detection.toml"
expect 2 "free_surface_mirror needs .*add \[effects.free_surface\]" -- "$VESPH" check "$WORK/no_detection.toml"
expect 2 "threshold" -- "$VESPH" check "$WORK/drop.toml" --set 'effects.free_surface.threshold=1.5'
expect 2 "inside the domain" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].centre=[0.0, 0.055]'
# (blocks overlap when a particle lies inside another block's shape or two blocks' particles lie
# closer than half a spacing; a disk wall needs its centre and diameter)
expect 2 "blocks\[1\]: overlaps blocks\[0\]: a particle of blocks\[0\] at .* lies inside blocks\[1\]'s shape" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].centre=[0.0, 0.0095]'
expect 2 "blocks\[1\].centre: expected" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[1].shape="disk"'
expect 2 "diameter" -- "$VESPH" check "$WORK/drop.toml" --set 'blocks[0].diameter=-1.0'
finish
