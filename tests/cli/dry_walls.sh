# Dry wall particles ([effects.pressure_gradient] dry_walls = "omit", docs/validation.md §20,
# session 21): a 2D tank of water at rest whose side walls (dummy layers) rise 2 mm above the
# surface. With the walls' particles above the surface in the pressure sum (the default) the
# column beside each wall settles below the far surface (-0.043 dx at t = 1 s, growing to
# -0.050 dx at 4 s: Adami's extrapolated pressure, negative above the water, holds the corner
# particle down); with them left out it stays at the level (+0.014 dx). Bounds: the default
# below -0.025 dx, the option within 0.025 dx of the level; the scene error of the key.
. "$(dirname "$0")/lib.sh"
cat > "$WORK/tank.toml" <<'TOML'
name = "tank2d"
dimension = 2
[domain]
min = [-0.0015, -0.0015]
max = [0.0175, 0.0115]
[particles]
spacing = 5.0e-4
kernel = "wendland_c2"
smoothing_ratio = 1.5
[fluid]
density = 1000.0
viscosity = 0.0225
[[blocks]]
kind = "fluid"
shape = "box"
min = [0.0, 0.0]
max = [0.016, 0.007]
hydrostatic = true
[[blocks]]
kind = "wall"
shape = "box"
min = [-0.0015, -0.0015]
max = [0.0, 0.009]
[[blocks]]
kind = "wall"
shape = "box"
min = [0.016, -0.0015]
max = [0.0175, 0.009]
[[blocks]]
kind = "wall"
shape = "box"
min = [0.0, -0.0015]
max = [0.016, 0.0]
[effects.continuity]
[effects.equation_of_state]
sound_speed = { phi = 1.0, delta = 0.03, velocity = 0.01, length = 0.007 }
[effects.pressure_gradient]
[effects.viscosity]
[effects.body_force]
acceleration = [0.0, -0.6]
[time]
end = 1.0
[output]
interval = 0.5
TOML
expect 0 "ok: finished" -- "$VESPH" run "$WORK/tank.toml" -o "$WORK/default" --quiet
expect 0 "ok: finished" -- "$VESPH" run "$WORK/tank.toml" -o "$WORK/omit" --quiet \
  --set 'effects.pressure_gradient.dry_walls="omit"'
# The top particle of the first and last columns against the mean top of the columns 8 dx or
# more from the walls, in the last frame, in dx.
$PY - "$WORK/default/tank2d.h5" "$WORK/omit/tank2d.h5" >"$WORK/levels.log" 2>&1 <<'PYEOF' && pass || fail "levels: $(tail -5 "$WORK/levels.log")"
import sys
import h5py
import numpy as np
dx = 5e-4
for path, (lo, hi) in zip(sys.argv[1:], ((-1.0, -0.025), (-0.025, 0.025))):
    with h5py.File(path, "r") as f:
        frames = f["frames"]
        g = frames[sorted(frames.keys())[-1]]
        fluid = g["kind"][:] == 0
        x = g["position"][:][fluid]
    column = np.floor(x[:, 0] / dx + 1e-9).astype(int)
    tops = np.array([x[column == c, 1].max() for c in range(column.max() + 1)])
    far = tops[8:-8].mean()
    beside = (tops[[0, -1]] - far) / dx
    print(f"{path}: the columns beside the walls {beside[0]:+.4f} / {beside[1]:+.4f} dx from the far level "
          f"(expected in [{lo}, {hi}])")
    assert np.all((beside >= lo) & (beside <= hi)), "outside the bounds"
PYEOF
cat "$WORK/levels.log"
expect 2 "dry_walls: expected one of: include, omit" -- "$VESPH" check "$WORK/tank.toml" \
  --set 'effects.pressure_gradient.dry_walls="wet"'
finish
