# Free-slip walls ([[blocks]] slip = "free", docs/theory.md §6.4): the transient Poiseuille
# channel with its upper wall free-slip is the lower half of a channel twice as high, the wall
# its plane of symmetry (the steady velocity there 4 times the no-slip centreline's). Checked
# against that analytic solution (tools/poiseuille_check.py reads the slip) at the four
# comparison times within the foundation's 2 %, under the leapfrog and arkode-imex, with the
# wall above and below; the scene errors of the key.
. "$(dirname "$0")/lib.sh"
for run in "upper blocks[2] leapfrog" "lower blocks[1] leapfrog" "imex blocks[2] arkode-imex"; do
  set -- $run
  expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/$1" --quiet $STIFF_POISEUILLE \
    --set "$2.slip=\"free\"" --set "integrator.type=\"$3\""
  $PY "$SRC/tools/poiseuille_check.py" "$WORK/$1/poiseuille_newtonian.h5" --times 0.000225 0.00045 0.001125 0.005 \
    >"$WORK/$1.log" 2>&1 && pass || fail "free slip ($1): $(tail -5 "$WORK/$1.log")"
done
C=$SRC/cases/poiseuille_newtonian.toml
expect 2 "blocks\[1\].slip: expected one of: no, free" -- "$VESPH" check "$C" --set 'blocks[1].slip="partial"'
expect 2 "blocks\[0\].slip: .*no slip on a fluid block" -- "$VESPH" check "$C" --set 'blocks[0].slip="free"'
expect 2 "blocks\[1\].slip: .*on a moving wall" -- "$VESPH" check "$C" --set 'blocks[1].slip="free"' \
  --set 'blocks[1].velocity=[1e-4, 0.0]'
expect 2 "blocks\[1\].slip: .*treatment = \"image\"" -- "$VESPH" check "$SRC/cases/poiseuille_newtonian_image_walls.toml" \
  --set 'blocks[1].slip="free"'
finish
