# Shared helpers for the command-line tests; sourced by each test with $1 = vesph binary,
# $2 = source directory.
set -u
VESPH=$1
SRC=$2
SCENE=$SRC/cases/poiseuille_newtonian.toml
PY=/usr/bin/python3
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
FAILED=0
PASSED=0
fail() { echo "FAIL: $*"; FAILED=$((FAILED + 1)); }
pass() { PASSED=$((PASSED + 1)); }
# expect CODE PATTERN -- command...: runs the command, checks exit code and that its stderr
# (or stdout) matches PATTERN (grep -E).
expect() {
  code=$1; pattern=$2; shift 3
  "$@" >"$WORK/out" 2>"$WORK/err"
  got=$?
  if [ "$got" != "$code" ]; then
    fail "'$*' exited $got, expected $code; stderr: $(tail -c 400 "$WORK/err")"
  elif ! grep -Eq -- "$pattern" "$WORK/err" "$WORK/out"; then
    fail "'$*' output does not match /$pattern/; stderr: $(tail -c 400 "$WORK/err")"
  else
    pass
  fi
}
finish() {
  echo "$PASSED passed, $FAILED failed"
  [ "$FAILED" = 0 ]
}
# The Poiseuille start-up (docs/validation.md §1) at 100 times the demo's viscosity and body
# force (the same steady speed; the comparison times scaled by 1/100), where the explicit viscous
# limit 0.125 h^2/nu = 2e-6 s is 28 times below the acoustic one (tests/cli/imex.sh,
# tests/cli/semi_implicit.sh); word-split on use.
STIFF_POISEUILLE="--set fluid.viscosity=0.1 --set effects.body_force.acceleration=[0.02,0.0] --set time.end=0.005
                  --set output.times=[0.000225,0.00045,0.001125,0.005]"
median_step() {  # median accepted step of a run's diagnostics
  $PY -c "import sys, h5py, numpy; print(numpy.median(h5py.File(sys.argv[1], 'r')['diagnostics/dt'][:]))" "$1"
}
# stiff_poiseuille LABEL DIR INTEGRATOR-ARGS...: that start-up with the given integrator keys:
# the Poiseuille check (2 % of the centreline velocity at every comparison time) and a median
# accepted step of at least 20 times the viscous limit.
stiff_poiseuille() {
  label=$1; dir=$WORK/$2; shift 2
  viscous_limit=2e-6  # 0.125 h^2/nu, h = 4e-5 m, nu = 1e-4 m^2/s
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$dir" --quiet $STIFF_POISEUILLE "$@"
  $PY "$SRC/tools/poiseuille_check.py" "$dir/poiseuille_newtonian.h5" --times 0.000225 0.00045 0.001125 0.005 \
    > "$WORK/check.log" 2>&1 && pass || fail "$label: Poiseuille validation failed: $(cat "$WORK/check.log")"
  grep -E "RESULT" "$WORK/check.log"
  dt=$(median_step "$dir/poiseuille_newtonian.h5")
  echo "$label: median step $dt s ($viscous_limit s viscous limit)"
  $PY -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 20 * float(sys.argv[2]) * (1 - 1e-9) else 1)" "$dt" "$viscous_limit" \
    && pass || fail "$label: median step $dt s is not 20 times the viscous limit $viscous_limit s"
}
# The open channel of cases/channel_inflow_outflow.toml to t = 0.35 s under integrator $1
# (tests/cli/inflow_outflow.sh, tests/long/inflow_outflow_integrators.sh): the particle accounting
# and the Poiseuille profile within 3 % (tools/inflow_check.py), and flow counts in summary.json.
open_channel() {
  integ=$1
  expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/channel_inflow_outflow.toml" -o "$WORK/$integ" --quiet --set time.end=0.35 --set "integrator.type=\"$integ\""
  $PY "$SRC/tools/inflow_check.py" "$WORK/$integ/channel_inflow_outflow.h5" --profile-x 0.015 --mean-velocity 0.1 \
    --from 0.25 >"$WORK/$integ.log" 2>&1 && pass || fail "$integ: $(tail -8 "$WORK/$integ.log")"
  grep -q '"released": [1-9]' "$WORK/$integ/summary.json" && grep -q '"removed": [1-9]' "$WORK/$integ/summary.json" && pass ||
    fail "$integ: summary.json has no flow counts"
}
# drop_integrators "INTEGRATORS": every drop case (cases/drop_newtonian.toml, drop_oldroyd_b.toml,
# drop_ucm.toml, drop_newtonian_isph.toml, drop_oldroyd_b_isph.toml) under each of the given
# integrators at its default settings, nothing but integrator.type changed
# (tests/cli/drop_integrators.sh, tests/long/drop_integrators_fixed_step.sh). A quarter of the
# resolution (dx = 0.08 cm, D/dx = 25) to t V/D = 2; the Oldroyd-B ISPH drop at half (see
# drop_integrators.sh). Each run must finish, keep the volume within 1 % and not fracture
# (tools/drop_measure.py); the integrators must agree on width/D at t V/D = 2 within 0.03.
drop_integrators() {
  integrators=$1
  QUARTER="--set particles.spacing=8e-4 --set domain.min=[-0.06,-0.0024] --set blocks[1].min=[-0.05,-0.0024] --set time.end=0.04 --set output.interval=0.005"
  HALF="--set particles.spacing=4e-4 --set domain.min=[-0.06,-0.0012] --set blocks[1].min=[-0.05,-0.0012] --set time.end=0.04 --set output.interval=0.005"
  for c in newtonian oldroyd_b ucm newtonian_isph oldroyd_b_isph; do
    Q=$QUARTER
    [ "$c" = oldroyd_b_isph ] && Q=$HALF
    for integ in $integrators; do
      # shellcheck disable=SC2086
      OMP_NUM_THREADS=1 "$VESPH" run "$SRC/cases/drop_$c.toml" -o "$WORK/${c}_$integ" --quiet $Q \
        --set "integrator.type=\"$integ\"" >"$WORK/${c}_$integ.log" 2>&1 &
    done
    wait
    for integ in $integrators; do
      r=$WORK/${c}_$integ
      grep -q '"status": "ok"' "$r/summary.json" 2>/dev/null && pass || fail "$c under $integ did not finish: $(tail -3 "$r.log")"
      $PY "$SRC/tools/drop_measure.py" "$r/drop_$c.h5" --no-png --no-fracture --max-volume-error 0.01 >"$r/measure.log" 2>&1 && pass ||
        fail "$c under $integ: $(tail -4 "$r/measure.log")"
    done
    # shellcheck disable=SC2086
    $PY - "$WORK" "$c" $integrators >"$WORK/${c}_agree.log" 2>&1 <<'PYEOF' && pass || fail "$c: integrators disagree: $(tail -5 "$WORK/${c}_agree.log")"
import csv, sys
w, c = sys.argv[1], sys.argv[2]
widths = {}
for integ in sys.argv[3:]:
    with open(f"{w}/{c}_{integ}/drop_{c}_drop.csv") as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]
    assert abs(float(last["tV_over_D"]) - 2.0) < 1e-6, last["tV_over_D"]
    widths[integ] = float(last["width_over_D"])
print(c, widths)
spread = max(widths.values()) - min(widths.values())
assert spread < 0.03, f"width/D at t V/D = 2 differs by {spread:.3f} between integrators"
PYEOF
    cat "$WORK/${c}_agree.log"
  done
}
# isph_poiseuille INTEGRATOR: the ISPH Poiseuille start-up (cases/poiseuille_newtonian_isph.toml,
# shortened to t = 0.1125 s) under that integrator within the foundation's 2 % of the analytic
# solution (tools/poiseuille_check.py); output in $WORK/p_INTEGRATOR (tests/cli/isph.sh,
# tests/long/isph_integrators.sh). arkode takes the flow's 2.5e-5 m/s as its velocity scale.
isph_poiseuille() {
  integ=$1
  extra=""
  [ "$integ" = arkode ] && extra="--set integrator.reference_velocity=2.5e-5"
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/poiseuille_newtonian_isph.toml" -o "$WORK/p_$integ" --quiet \
    --set time.end=0.1125 --set "output.times=[0.0225,0.1125]" --set "integrator.type=\"$integ\"" $extra
  $PY "$SRC/tools/poiseuille_check.py" "$WORK/p_$integ/poiseuille_newtonian_isph.h5" >"$WORK/p_$integ.log" 2>&1 && pass ||
    fail "ISPH Poiseuille under $integ: $(tail -4 "$WORK/p_$integ.log")"
}
# open_channel_body_force INTEGRATOR: the thesis' feed (cases/channel_open_body_force.toml: a
# body force inside the channel only, the buffer following the fluid) to t = 0.35 s: the flow
# rate the body force drives, U = F W^2/(12 nu) = 0.1 m/s, within 3 % (tools/inflow_check.py;
# tests/cli/inflow_outflow.sh, tests/long/inflow_outflow_integrators.sh).
open_channel_body_force() {
  integ=$1
  expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/channel_open_body_force.toml" -o "$WORK/bf-$integ" --quiet \
    --set time.end=0.35 --set "integrator.type=\"$integ\""
  $PY "$SRC/tools/inflow_check.py" "$WORK/bf-$integ/channel_open_body_force.h5" --profile-x 0.015 --mean-velocity 0.1 \
    --from 0.25 >"$WORK/bf-$integ.log" 2>&1 && pass || fail "body force, $integ: $(tail -8 "$WORK/bf-$integ.log")"
}
# The second-order fluid's channel start-up (cases/startup_channel_second_order_fluid.toml, thesis
# §4.3.2) shortened to H/20 (tests/cli/second_order_fluid_validation.sh,
# tests/long/second_order_fluid_forms.sh); word-split on use.
SOF=$SRC/cases/startup_channel_second_order_fluid.toml
SOF_H20="--set particles.spacing=5e-4 --set domain.min=[0.0,-2.5e-3] --set domain.max=[1.0e-2,1.25e-2]
 --set blocks[0].max=[1.0e-2,1.0e-2] --set blocks[1].min=[0.0,-2.5e-3] --set blocks[1].max=[1.0e-2,0.0]
 --set blocks[2].max=[1.0e-2,1.25e-2] --set time.end=0.007 --set output.interval=0.0005"
# sof_check NAME SCENE CHECK-ARGS -- run arguments: runs the scene and
# tools/second_order_channel_check.py with CHECK-ARGS on its output.
sof_check() {
  name=$1; scene=$2; args=$3; shift 4
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$scene" -o "$WORK/$name" --quiet "$@"
  # shellcheck disable=SC2086
  $PY "$SRC/tools/second_order_channel_check.py" "$WORK/$name/startup_channel_second_order_fluid.h5" $args \
    > "$WORK/$name.log" 2>&1 && pass || fail "$name: $(grep -E 'FAIL' "$WORK/$name.log")"
  echo "$name: $(grep -E 'retardation by|steady N1|RESULT' "$WORK/$name.log" | tr '\n' ' ')"
}
# sof_form FORM DERIVATIVE: the H/20 start-up with that form and convected derivative (procedure 3):
# profile, stresses and the start-up history within 3 % (--transient).
sof_form() {
  # shellcheck disable=SC2086
  sof_check "$1_$2" "$SOF" --transient -- $SOF_H20 --set "effects.second_order_fluid.form=\"$1\"" \
    --set "effects.second_order_fluid.derivative=\"$2\""
}
