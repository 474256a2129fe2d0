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
