# Bad input and faults (issue 37): absurd scene files, special files, malformed --set keys,
# absurd coefficients, two constitutive models, a huge domain around a drop, and a full disk.
# Each exits with its code and a message naming the file or the key; nothing crashes.
. "$(dirname "$0")/lib.sh"
S=$SCENE
# Absurd nesting is refused before the TOML library sees it (it overflowed the stack).
$PY -c "print('.'.join(['a']*31000) + ' = 1')" > "$WORK/deep.toml"
expect 2 "deep.toml: a key of 31000 dotted parts" -- "$VESPH" check "$WORK/deep.toml"
$PY -c "print('[' + '.'.join(['t']*31000) + ']')" > "$WORK/header.toml"
expect 2 "header.toml: a key of 31000 dotted parts" -- "$VESPH" check "$WORK/header.toml"
$PY -c "print('# ' + 'x' * (5 << 20))" > "$WORK/big.toml"
expect 2 "big.toml: larger than the 4 MiB a scene file may have" -- "$VESPH" check "$WORK/big.toml"
# Special files are named as such (a directory read as an empty scene said 'name' was missing).
expect 2 "$WORK: is a directory, not a scene file" -- "$VESPH" check "$WORK"
expect 2 "/dev/null: is a device, not a scene file" -- "$VESPH" check /dev/null
expect 2 "/dev/zero: is a device, not a scene file" -- "$VESPH" run /dev/zero -o "$WORK/zero"
# Malformed array indices in --set (they ended in 'stoul', exit 1).
expect 2 "--set 'blocks\[abc\].min=1': '\[abc\]' is not an array index" -- "$VESPH" check "$S" --set 'blocks[abc].min=1'
expect 2 "--set 'blocks\[\].min=1': '\[\]' is not an array index" -- "$VESPH" check "$S" --set 'blocks[].min=1'
expect 2 "--set 'blocks\[\[0\]\].min=1'" -- "$VESPH" check "$S" --set 'blocks[[0]].min=1'
expect 2 "--set 'blocks\[99999999999999999999\].min=1'" -- "$VESPH" check "$S" --set 'blocks[99999999999999999999].min=1'
# A long value is echoed cut (a 2 MB value was echoed whole).
$PY - "$S" "$WORK/long.toml" <<'PYEOF'
import sys
text = open(sys.argv[1]).read().replace("density = 1000.0", 'density = "' + "z" * 2000000 + '"', 1)
open(sys.argv[2], "w").write(text)
PYEOF
expect 2 "long.toml: fluid.density: expected a positive number \(kg/m\^3\), got \"zzzz.*\(2000002 characters\)" -- "$VESPH" check "$WORK/long.toml"
[ "$(wc -c < "$WORK/err")" -lt 400 ] && pass || fail "the long value is echoed whole: $(wc -c < "$WORK/err") bytes"
# Absurd coefficients are refused by check with their range (they drove the step to zero).
D=$SRC/cases/drop_oldroyd_b_isph.toml
expect 2 "effects.particle_shifting.speed: expected a positive number of at most 10000 \(m/s\), got 1e\+300" -- "$VESPH" check "$D" --set effects.particle_shifting.speed=1e300
expect 2 "effects.artificial_viscosity.alpha: expected a non-negative number of at most 100, got 1e\+308" -- "$VESPH" check "$D" --set effects.artificial_viscosity.alpha=1e308
expect 2 "effects.density_diffusion.delta: expected a non-negative number of at most 10, got 1e\+308" -- "$VESPH" check "$S" --set 'effects.density_diffusion.delta=1e308'
# Two constitutive models, naming both.
O=$SRC/cases/startup_channel_oldroyd_b.toml
expect 2 "one constitutive model per scene, but the scene has both \[effects.oldroyd_b\] and \[effects.ucm\]" -- "$VESPH" check "$O" --set 'effects.ucm={relaxation_time=1.0, polymer_viscosity=1.0}'
expect 2 "both \[effects.oldroyd_b\] and \[effects.xpp\]" -- "$VESPH" check "$O" --set 'effects.xpp={backbone_relaxation_time=1.0, modulus=1.0, arms=2, anisotropy=0.1}'
# A huge domain around the drop: the cell grid covers the particles only (bad_alloc before).
expect 0 "name = 'drop_oldroyd_b_isph'" -- "$VESPH" check "$D" --set 'domain.max=[60.0, 60.0]'

# A full disk: a 2 MiB tmpfs (needs root; skipped where mount is refused). The run stops with a
# message naming the directory, HDF5 is closed cleanly (no crash at exit), the frames written
# and their checkpoint stay readable, and --resume goes on once there is room.
MNT=$WORK/small_disk
mkdir -p "$MNT"
if mount -t tmpfs -o size=2m tmpfs "$MNT" 2>/dev/null; then
  trap 'umount "$MNT" 2>/dev/null; rm -rf "$WORK"' EXIT
  expect 1 "no space left for the next frame on the disk of $MNT/out: .*the frames up to t = .* are intact" -- "$VESPH" run "$S" -o "$MNT/out" --quiet --set output.interval=0.005 --set time.end=0.2 --set output.times=[]
  $PY - "$MNT/out/poiseuille_newtonian.h5" <<'PYEOF' && pass || fail "the output on the full disk is not readable"
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    frames = sorted(f["frames"])
    assert len(frames) >= 2, frames
    assert f["checkpoint"].attrs["time"] == f["frames"][frames[-1]].attrs["time"]
PYEOF
  mount -o remount,size=64m "$MNT"
  expect 0 "vesph: ok: finished" -- "$VESPH" run "$S" -o "$MNT/out" --quiet --resume --set output.interval=0.005 --set time.end=0.2 --set output.times=[]
  umount "$MNT"
else
  echo "skipped the full-disk test: mount -t tmpfs is not permitted here"
fi
# A write that fails half way (a file size limit: EFBIG, as ENOSPC after the free-space check):
# a clear message and exit 1, not a crash in HDF5's close at exit (exit 139 before).
(trap '' XFSZ; ulimit -f 600; exec "$VESPH" run "$S" -o "$WORK/limited" --quiet --set output.interval=0.005 --set time.end=0.2 --set output.times=[]) >"$WORK/out" 2>"$WORK/err"
got=$?
[ "$got" = 1 ] && grep -q "cannot write .* to $WORK/limited/poiseuille_newtonian.h5" "$WORK/err" && pass || fail "a failed write exited $got: $(tail -c 400 "$WORK/err")"
# Ranges of coefficients that collapsed the step (item 5, 10) and a fixed step under the floor.
expect 2 "fluid.viscosity: expected a non-negative number of at most 1e\+06 \(Pa s\), got 1e\+300" -- "$VESPH" check "$S" --set fluid.viscosity=1e300
expect 2 "effects.equation_of_state.reference_pressure: expected a number in \[-1e\+12, 1e\+12\] \(Pa\), got -1e\+308" -- "$VESPH" check "$S" --set effects.equation_of_state.reference_pressure=-1e308
expect 2 "integrator.step: expected a step of at least 1e-12 time.end" -- "$VESPH" check "$S" --set integrator.step=1e-20
# The step floor: a viscosity inside the range that still drives the step under 1e-12 time.end
# (it ran for ever before): exit 3 naming the step and the limit; the last good frame is written.
expect 3 "step 1 \(t = .*\) was .* s, below the step floor 1e-12 time.end = 5e-13 s; the (viscous|acoustic) limit set it" -- timeout 60 "$VESPH" run "$S" -o "$WORK/floor" --quiet --set fluid.viscosity=1e6
grep -q '"status": "diverged"' "$WORK/floor/summary.json" && pass || fail "the collapsed step's summary is not 'diverged'"
# A last good frame must be finite (item 10): a sound speed whose square overflows gives a NaN
# pressure at t = 0 (finite state): no frame of NaN is written as "last good", and the message
# says so.
expect 3 "non-finite pressure or stress in the frame at t = 0 s; the last good state \(t = 0.000000 s\) gives non-finite pressures or stresses and is not written; the file holds no frame" -- "$VESPH" run "$SRC/cases/bench_periodic_box.toml" -o "$WORK/nan" --quiet --set effects.equation_of_state.sound_speed=1e200
# check catches what run refuses (item 6): a name too long for a file name; a scene of any size
# is stored (3000 output times made the scene attribute overflow HDF5's 64 KiB).
LONG=$($PY -c "print('n' * 250)")
expect 2 "name: expected a name of at most 200 bytes" -- "$VESPH" check "$S" --set "name=\"$LONG\""
TIMES=$($PY -c "print('[' + ', '.join(repr(0.5 * (k + 1) / 3000) for k in range(3000)) + ']')")
# (checks.max_speed stops the run after its first frame: the scene is stored when the file is made.)
"$VESPH" run "$S" -o "$WORK/big_scene" --quiet --set "output.times=$TIMES" --set checks.max_speed=1e-30 >"$WORK/out" 2>"$WORK/err"
[ $? = 3 ] && grep -q "faster than checks.max_speed" "$WORK/err" && pass || fail "the 3000-time scene: $(tail -c 300 "$WORK/err")"
$PY - "$WORK/big_scene/poiseuille_newtonian.h5" "$SRC/tools" <<'PYEOF' && pass || fail "the 3000-time scene is not stored whole"
import sys
sys.path.insert(0, sys.argv[2])
import h5py
from vesph.output import open_h5, read_header
f, _ = open_h5(sys.argv[1])
scene_read, dim, dx = read_header(f, sys.argv[1])
assert len(scene_read["output"]["times"]) == 3000, len(scene_read["output"]["times"])
f.close()
with h5py.File(sys.argv[1], "r") as f:
    scene = f.attrs["scene"]
    scene = scene.decode() if isinstance(scene, bytes) else scene
    assert len(scene) > 65536 and scene.count(",") >= 2999, len(scene)
    assert len(f["frames"]) >= 1
PYEOF
# Unbounded allocations (item 7): a tiny output interval, a tiny spacing; refused with the figure.
expect 2 "output.interval: expected at most 1000000 output times \(output.interval and output.times give 5e\+299; each frame of the .* particles holds about .* MiB\)" -- "$VESPH" check "$S" --set output.interval=1e-300
expect 2 "particles.spacing: the blocks hold about .* particles at a spacing of 2.5e-08 m, about .* GiB at 1024 bytes each, more than the .* GiB of memory of this machine" -- "$VESPH" check "$S" --set particles.spacing=2.5e-8
# Checkpoints are validated on resume (item 4): a checksum of the state, ids and arrays; finite
# values; positions in the domain (the periodic axis: within a period and max_speed * t); the
# time within the run and that of a frame. A checkpoint without a checksum (older vesph) is
# checked for the rest only.
R=$WORK/resume
expect 0 "vesph: ok" -- "$VESPH" run "$S" -o "$R" --quiet --set time.end=0.05 --set output.times=[0.02,0.05]
cp "$R/poiseuille_newtonian.h5" "$WORK/good.h5"
damage() {  # damage PYTHON-STATEMENTS: applied to the checkpoint group g of a fresh copy
  cp "$WORK/good.h5" "$R/poiseuille_newtonian.h5"
  $PY - "$R/poiseuille_newtonian.h5" "$1" <<'PYEOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    g = f["checkpoint"]
    exec(sys.argv[2])
PYEOF
}
RUN_R="$VESPH run $S -o $R --quiet --resume --set time.end=0.06 --set output.times=[0.02,0.05]"
damage 'b = g["state"][...].view(np.uint8).copy(); b[1001] ^= 0x10; g["state"][...] = b.view(np.float64)'
expect 2 "--resume: the checkpoint in $R/poiseuille_newtonian.h5 fails its checksum" -- $RUN_R
damage 'g["id"][3] = g["id"][3] + 1'
expect 2 "fails its checksum" -- $RUN_R
damage 'del g.attrs["checksum"]; s = g["state"][...]; s[0] = 1e20; g["state"][...] = s'
expect 2 "--resume: the checkpoint in $R/poiseuille_newtonian.h5 places particle id .* at x = 1e\+20 m, outside the domain \[0, 0.0005\] by more than one period" -- $RUN_R
damage 'del g.attrs["checksum"]; s = g["state"][...]; s[1] = 0.5; g["state"][...] = s'
expect 2 "places particle id .* at y = 0.5 m, outside the domain" -- $RUN_R
damage 'del g.attrs["checksum"]; s = g["state"][...]; s[5] = np.nan; g["state"][...] = s'
expect 2 "holds a non-finite state value" -- $RUN_R
damage 'g.attrs.modify("time", -1.0)'
expect 2 "--resume: the checkpoint in $R/poiseuille_newtonian.h5 is at t = -1 s, before the start of the run" -- $RUN_R
damage 'g.attrs.modify("time", 0.03)'
expect 2 "is at t = 0.03 s, the time of none of the file's frames" -- $RUN_R
damage 'del g.attrs["checksum"]; i = g["id"][...]; i[1] = i[0]; g["id"][...] = i'
expect 2 "holds a particle id twice" -- $RUN_R
damage 'del g.attrs["checksum"]'
expect 0 "vesph: ok" -- $RUN_R
finish
