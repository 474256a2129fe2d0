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
finish
