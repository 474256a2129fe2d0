# Implicit-explicit ARKODE (arkode-imex, docs/theory.md §9.5) on stiff viscous flow: the
# Poiseuille start-up (docs/validation.md §1) at 100 times the demo's viscosity (and 100 times
# its body force, so the same steady speed; the comparison times scaled by 1/100), where the
# explicit viscous limit 0.125 h^2/nu = 2e-6 s is 28 times below the acoustic one. arkode-imex
# must pass the same check (2 % of the centreline velocity at every comparison time) with a
# median step of at least 20 times the viscous limit, adaptive and fixed-step; the scene keys
# it refuses are refused with exit 2. Then the Oldroyd-B start-up under ISPH (below).
. "$(dirname "$0")/lib.sh"
stiff_poiseuille arkode-imex imex --set integrator.type=arkode-imex
stiff_poiseuille arkode-imex-fixed imex_fixed --set integrator.type=arkode-imex-fixed --set integrator.step=4e-5
stiff_poiseuille "arkode-imex ARK548L2SA" imex_ark548 --set integrator.type=arkode-imex --set integrator.table=ARK548L2SA
# The Oldroyd-B start-up (docs/validation.md §6) under ISPH, where no sound speed bounds the
# step: with the viscous force, the relaxation and the elastic shear wave implicit, the step is
# set by the output interval and the error control, far above the viscous limit 0.125 h^2/nu_s
# (4e-4 s in both: the same solvent viscosity); the check of
# tools/startup_channel_check.py (3 %) must pass as for the leapfrog.
OBI=$SRC/cases/startup_channel_oldroyd_b_isph.toml
for run in "E0.5_beta0.5 4e-4" "E2_beta0.5 4e-4 --set effects.oldroyd_b.relaxation_time=0.5 --set time.end=5.0 --set output.interval=0.05"; do
  set -- $run
  name=$1 limit=$2; shift 2
  expect 0 "ok: finished" -- "$VESPH" run "$OBI" -o "$WORK/$name" --quiet --set integrator.type=arkode-imex \
    --set integrator.reference_velocity=2.5e-5 "$@"
  $PY "$SRC/tools/startup_channel_check.py" "$WORK/$name/startup_channel_oldroyd_b_isph.h5" > "$WORK/$name.log" 2>&1 \
    && pass || fail "$name: $(grep -E 'FAIL|steady' "$WORK/$name.log")"
  grep -E "^E =|RESULT" "$WORK/$name.log"
  dt=$(median_step "$WORK/$name/startup_channel_oldroyd_b_isph.h5")
  echo "$name: median step $dt s ($limit s viscous limit)"
  $PY -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 20 * float(sys.argv[2]) else 1)" "$dt" "$limit" \
    && pass || fail "$name: median step $dt s is not 20 times the viscous limit $limit s"
done
# Refused keys: an unknown pair, a fixed step for the adaptive integrator.
expect 2 "integrator.table" -- "$VESPH" check "$SCENE" --set integrator.type=arkode-imex --set integrator.table=DORMAND_PRINCE_7_4_5
expect 2 "arkode-imex-fixed" -- "$VESPH" check "$SCENE" --set integrator.type=arkode-imex --set integrator.step=1e-5
# vesph list shows the integrators and the pairs
expect 0 "arkode-imex-fixed" -- "$VESPH" list
expect 0 "ARK548L2SAb_DIRK_8_4_5" -- "$VESPH" list
finish
