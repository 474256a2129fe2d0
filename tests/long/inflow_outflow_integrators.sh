# Long test (ctest -L long): the open channel of cases/channel_inflow_outflow.toml
# (tests/cli/inflow_outflow.sh runs it under the leapfrog and arkode) under midpoint and
# arkode-fixed: the particle accounting and the Poiseuille profile within 3 % by
# tools/inflow_check.py, and flow counts in summary.json. About 90 s on one core.
. "$(dirname "$0")/../cli/lib.sh"
C=$SRC/cases/channel_inflow_outflow.toml
for integ in midpoint arkode-fixed; do
  expect 0 "ok: finished" -- "$VESPH" run "$C" -o "$WORK/$integ" --quiet --set time.end=0.35 --set "integrator.type=\"$integ\""
  $PY "$SRC/tools/inflow_check.py" "$WORK/$integ/channel_inflow_outflow.h5" --profile-x 0.015 --mean-velocity 0.1 \
    --from 0.25 >"$WORK/$integ.log" 2>&1 && pass || fail "$integ: $(tail -8 "$WORK/$integ.log")"
  grep -q '"released": [1-9]' "$WORK/$integ/summary.json" && grep -q '"removed": [1-9]' "$WORK/$integ/summary.json" && pass ||
    fail "$integ: summary.json has no flow counts"
done
finish
