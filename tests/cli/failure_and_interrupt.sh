# A run that blows up stops with exit 3, a diagnostic, the last good frame written and a
# readable output; SIGINT writes the current state and exits 130; nothing written is lost.
. "$(dirname "$0")/lib.sh"
CHECK="$PY $SRC/tools/check_output.py"

# 1. Blow-up detection: a speed limit far below the flow speed trips the check.
expect 3 "diverged: a particle moves at .* faster than checks.max_speed" -- "$VESPH" run "$SCENE" -o "$WORK/slow" --quiet --set checks.max_speed=1e-5
grep -q '"status": "diverged"' "$WORK/slow/summary.json" && pass || fail "summary.json status is not diverged"
$CHECK "$WORK/slow" >"$WORK/check.log" 2>&1 && pass || fail "output after divergence is not readable/valid: $(tail -5 "$WORK/check.log")"

# 1b. The same detection under the ARKODE integrators (the check runs in ERKStep's post-step
#     function, which must stop the integration cleanly).
for integrator in arkode arkode-fixed; do
  expect 3 "diverged: a particle moves at .* faster than checks.max_speed" -- "$VESPH" run "$SCENE" -o "$WORK/slow_$integrator" --quiet --set integrator.type=$integrator --set checks.max_speed=1e-5
  $CHECK "$WORK/slow_$integrator" >"$WORK/check.log" 2>&1 && pass || fail "$integrator: output after divergence is not valid: $(tail -5 "$WORK/check.log")"
done

# 2. A real numerical instability: an 8x too large viscous step limit makes the explicit
#    viscous term unstable; the run must be stopped (exit 3), not crash or hang.
expect 3 "diverged" -- "$VESPH" run "$SCENE" -o "$WORK/unstable" --quiet --set integrator.viscous_coefficient=1.0 --set integrator.cfl=1.0 --set integrator.force_coefficient=1.0
grep -q '"status": "diverged"' "$WORK/unstable/summary.json" && pass || fail "unstable run: summary.json status is not diverged"
$CHECK "$WORK/unstable" >"$WORK/check.log" 2>&1 && pass || fail "output of the unstable run is not valid: $(tail -5 "$WORK/check.log")"

# 3. SIGINT: stop cleanly with the current state written.
"$VESPH" run "$SCENE" -o "$WORK/int" --quiet --set time.end=1000 --set "output.times=[1000.0]" >"$WORK/int.log" 2>&1 &
pid=$!
sleep 3
kill -INT $pid
wait $pid
code=$?
[ "$code" = 130 ] && pass || fail "interrupted run exited $code, expected 130: $(tail -3 "$WORK/int.log")"
grep -q '"status": "interrupted"' "$WORK/int/summary.json" && pass || fail "summary.json status is not interrupted"
$CHECK "$WORK/int" >"$WORK/check.log" 2>&1 && pass || fail "output after SIGINT is not valid: $(tail -5 "$WORK/check.log")"
frames=$($PY -c "import h5py,sys; f=h5py.File(sys.argv[1]); print(len(f['frames']))" "$WORK/int/poiseuille_newtonian.h5")
[ "$frames" = 2 ] && pass || fail "expected the initial frame and the interrupted state, found $frames frames"
finish
