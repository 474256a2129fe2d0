# Circular Couette flow (docs/validation.md §16): an inner wall cylinder (rings) turning at
# omega inside a fluid tube and an outer wall tube at rest; the steady azimuthal velocity
# against v = A r + B/r within 1 % of the wall speed omega R1 at t = 0.3 s (leapfrog, WCSPH,
# 20 rings across the gap).
. "$(dirname "$0")/lib.sh"
CASE=$SRC/cases/circular_couette.toml
expect 0 "ok: finished" -- "$VESPH" run "$CASE" -o "$WORK/cc" --quiet
"$SRC/tools/vesph-post" circular_couette_check "$WORK/cc/circular_couette.h5" --tolerance 0.01 >"$WORK/check.log" 2>&1 \
  && pass || fail "circular Couette: $(cat "$WORK/check.log")"
cat "$WORK/check.log"
# The walls turned rigidly: the inner cylinder's particles at omega t from their start, the
# outer tube's where they were.
$PY - "$WORK/cc/circular_couette.h5" >"$WORK/walls.log" 2>&1 <<'PYEOF' && pass || fail "walls: $(tail -3 "$WORK/walls.log")"
import sys
import h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    names = sorted(f["frames"])
    first, last = f["frames"][names[0]], f["frames"][names[-1]]
    t = last.attrs["time"]
    ids0, ids1 = first["id"][:], last["id"][:]
    assert (ids0 == ids1).all()
    x0, x1 = first["position"][:], last["position"][:]
    walls = first["kind"][:] != 0
    r0 = np.hypot(x0[:, 0], x0[:, 1])
    inner = walls & (r0 < 0.5e-3)
    outer = walls & (r0 > 1.0e-3)
    c, s = np.cos(4.0 * t), np.sin(4.0 * t)
    turned = np.stack([c * x0[:, 0] - s * x0[:, 1], s * x0[:, 0] + c * x0[:, 1]], axis=1)
    assert np.abs(x1[inner] - turned[inner]).max() < 1e-15, "inner cylinder not at omega t"
    assert np.abs(x1[outer] - x0[outer]).max() == 0, "outer tube moved"
print("inner cylinder turned by", 4.0 * t, "rad; outer tube at rest")
PYEOF
cat "$WORK/walls.log"
finish
