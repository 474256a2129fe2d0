# Validation: transient plane Poiseuille flow (thesis 4.3.1, Morris et al. 1997), the demo
# case at full size. At t = 0.0225, 0.045, 0.1125 and 0.5 s the largest deviation of any fluid
# particle's x-velocity from the analytic solution must be below 2 % of the steady centreline
# velocity, the fluid mass exactly conserved, and the density deviation within the delta of
# thesis eq. (3.38) that set the sound speed (tools/poiseuille_check.py). The output must be a
# valid vesph-1 file (every integrator at its default settings) with an XDMF file valid against tools/xdmf3.dtd (tools/check_output.py).
. "$(dirname "$0")/lib.sh"
for integrator in leapfrog midpoint arkode arkode-fixed symplectic; do
  expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/$integrator" --quiet --set integrator.type=$integrator
  $PY "$SRC/tools/poiseuille_check.py" "$WORK/$integrator/poiseuille_newtonian.h5" --times 0.0225 0.045 0.1125 0.5 > "$WORK/check.log" 2>&1 \
    && pass || fail "$integrator: Poiseuille validation failed: $(cat "$WORK/check.log")"
  cat "$WORK/check.log"
  $PY "$SRC/tools/check_output.py" "$WORK/$integrator" > "$WORK/out.log" 2>&1 && pass || fail "$integrator: invalid output: $(tail -5 "$WORK/out.log")"
done
command -v h5dump >/dev/null && {
  for ds in id kind position velocity density mass pressure; do
    h5dump -n "$WORK/leapfrog/poiseuille_newtonian.h5" | grep -q "dataset */frames/000004/$ds\$" && pass || fail "h5dump does not list /frames/000004/$ds"
  done
  for ds in time dt kinetic_energy mass max_speed max_density_deviation; do
    h5dump -n "$WORK/leapfrog/poiseuille_newtonian.h5" | grep -q "dataset */diagnostics/$ds\$" && pass || fail "h5dump does not list /diagnostics/$ds"
  done
}
finish
