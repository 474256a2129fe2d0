# Long test (ctest -L long; out of the suite since session 8 for CI time: the suite keeps the
# Newtonian ISPH drop under three integrators in cli.drop_integrators and the Oldroyd-B ISPH drop
# against WCSPH in cli.drop_tensile_contrast). About 120 s on one core.
# The Newtonian drop with incompressible SPH (issue 6): cases/drop_newtonian_isph.toml beside the
# WCSPH drop of cases/drop_newtonian.toml (Fang et al. 2006 §4), both at half resolution
# (dx = 0.04 cm, 1961 particles) to t V/D = 3 (the impact at 1.5 and the fast spreading).
# The ISPH drop must
#   - stay in one piece (one fragment in every frame),
#   - keep its interior summation density within 1 % of the first frame (its sum m/rho is
#     constant by construction, so this is the volume measure; measured 0.6 % at most),
#   - spread with the WCSPH drop: width/D within 0.05 of it at t V/D = 2, 2.5, 3 (measured 0.041
#     at most with the case's predictor form; the incremental form, 0.076, fails this),
#   - spread monotonically (a Newtonian drop without surface tension has nothing to pull it
#     back): width/D never more than 0.01 below its largest earlier value. With the
#     renormalised pressure gradient the drop retracted from 1.66 D at 2 to 1.59 D at 3.
# The full-resolution run to t V/D = 8 is in docs/validation.md §11 (too long for CI).
. "$(dirname "$0")/../cli/lib.sh"
HALF="--set particles.spacing=4e-4 --set domain.min=[-0.06,-0.0012] --set blocks[1].min=[-0.05,-0.0012] --set time.end=0.06 --set output.interval=0.005"
for c in newtonian newtonian_isph; do
  # shellcheck disable=SC2086
  OMP_NUM_THREADS=1 "$VESPH" run "$SRC/cases/drop_$c.toml" -o "$WORK/$c" --quiet $HALF >"$WORK/$c.log" 2>&1 &
done
wait
for c in newtonian newtonian_isph; do
  grep -q '"status": "ok"' "$WORK/$c/summary.json" 2>/dev/null && pass || fail "$c: the run did not finish: $(tail -3 "$WORK/$c.log")"
  $PY "$SRC/tools/drop_measure.py" "$WORK/$c/drop_$c.h5" --no-png >"$WORK/m_$c.log" 2>&1 && pass ||
    fail "$c: drop_measure failed: $(tail -4 "$WORK/m_$c.log")"
done
$PY "$SRC/tests/cli/drop_compare.py" "$WORK/newtonian/drop_newtonian_drop.csv" "$WORK/newtonian_isph/drop_newtonian_isph_drop.csv" \
  --times 2,2.5,3 --max-width-diff 0.05 --max-setback 0.01 >"$WORK/compare.log" 2>&1 && pass ||
  fail "ISPH against WCSPH: $(tail -3 "$WORK/compare.log")"
cat "$WORK/compare.log"
finish
