# Fang et al. (2006) §3.3 walls (boundary particles on the surface, image particles behind it,
# eqs. 46-48), selectable per wall block ([[blocks]] treatment = "image"): the transient
# Poiseuille channel with both extrapolations within the foundation's 2 % of the analytic
# solution at the four comparison times (cases/poiseuille_newtonian_image_walls.toml), and the
# scene errors of the new keys.
. "$(dirname "$0")/lib.sh"
C=$SRC/cases/poiseuille_newtonian_image_walls.toml
for ex in centroid fang; do
  expect 0 "ok: finished" -- "$VESPH" run "$C" -o "$WORK/$ex" --quiet --set "blocks[1].extrapolation=\"$ex\"" \
    --set "blocks[2].extrapolation=\"$ex\""
  (cd "$SRC/tools" && $PY poiseuille_check.py "$WORK/$ex/poiseuille_newtonian_image_walls.h5") >"$WORK/$ex.log" 2>&1 && pass ||
    fail "image walls ($ex): $(tail -5 "$WORK/$ex.log")"
done
# the literal eq. (47) is less accurate than the centroid form (0.72 % against 0.18 % at 0.1125 s)
$PY - "$WORK" >"$WORK/cmp.log" 2>&1 <<'PYEOF' && pass || fail "centroid not better than fang: $(tail -3 "$WORK/cmp.log")"
import re, sys
w = sys.argv[1]
def worst(ex):
    errs = [float(m.group(1)) for m in re.finditer(r"^\s+\d{6}\s+\S+\s+\d+\s+\d+\s+(\S+)", open(f"{w}/{ex}.log").read(), re.M)]
    assert len(errs) == 4, errs
    return max(errs)
c, f = worst("centroid"), worst("fang")
print(c, f)
assert c < 0.5 and c < f, (c, f)
PYEOF
expect 2 "blocks\[1\].normal: expected a coordinate unit vector" -- "$VESPH" check "$C" --set 'blocks[1].normal=[0.5, 0.5]'
expect 2 "blocks\[1\].extrapolation: expected one of: fang, centroid" -- "$VESPH" check "$C" --set 'blocks[1].extrapolation="linear"'
expect 2 "unknown key 'blocks\[0\].treatment'" -- "$VESPH" check "$C" --set 'blocks[0].treatment="image"'
expect 2 "treatment = \"image\" walls are not implemented with solver.scheme = \"isph\"" -- "$VESPH" check \
  "$SRC/cases/hydrostatic_tank_isph.toml" --set 'blocks[1].treatment="image"' --set 'blocks[1].normal=[0.0, 1.0]'
finish
