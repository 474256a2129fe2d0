# Scene geometry (docs/user-guide.md "[[blocks]]"): `vesph check` prints the particle count and
# volume per block; shapes with subtractions (cases/tank_orifice.toml) build and run a few
# steps; the refusals name the key.
. "$(dirname "$0")/lib.sh"
TANK=$SRC/cases/tank_orifice.toml
CC=$SRC/cases/circular_couette.toml
expect 0 "# blocks\[0\]: fluid box, 1912 particles" -- "$VESPH" check "$TANK"
grep -Eq "# blocks\[2\]: wall disk, .* particles, volume .* \(the shape's 0.00785398, [+-]0.000 %\)" "$WORK/out" \
  && pass || fail "the post's volume: $(grep 'blocks\[2\]' "$WORK/out")"
expect 0 "# blocks\[0\]: fluid tube, 3770 particles" -- "$VESPH" check "$CC"
grep -Eq "# blocks\[2\]: wall tube, .* \(the shape's 8.34486e-07, [+-]0.000 %\)" "$WORK/out" \
  && pass || fail "the outer tube's volume: $(grep 'blocks\[2\]' "$WORK/out")"
expect 0 "ok: finished" -- "$VESPH" run "$TANK" -o "$WORK/tank" --quiet --set time.end=0.01
# Refusals: exit 2, the key and what is expected.
expect 2 "blocks\[2\].outer_diameter: expected a wall at least one kernel support thick" -- "$VESPH" check "$CC" \
  --set 'blocks[2].outer_diameter=2.2e-3'
expect 2 "blocks\[1\]: overlaps blocks\[0\]" -- "$VESPH" check "$CC" --set 'blocks[1].diameter=1.1e-3'
expect 2 "blocks\[0\].axis: expected no axis in 2D" -- "$VESPH" check "$CC" --set 'blocks[0].axis=[0.0, 1.0]'
expect 2 "blocks\[0\].subtract\[0\].diameter: expected" -- "$VESPH" check "$TANK" \
  --set 'blocks[0].subtract=[{ shape = "disk", centre = [0.25, 0.2] }]'
expect 2 "blocks\[1\].subtract\[0\].max: expected a corner above min" -- "$VESPH" check "$TANK" \
  --set 'blocks[1].subtract=[{ shape = "box", min = [0.0, 0.0], max = [0.0, 0.61] }]'
expect 2 "blocks\[2\].treatment: expected \"dummy\" for a tube" -- "$VESPH" check "$CC" \
  --set 'blocks[2].treatment="image"' --set 'blocks[2].normal=[0.0, 1.0]'
finish
