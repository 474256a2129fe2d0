# The tensile instability detected and cured (issue 5): the Oldroyd-B drop of
# cases/drop_oldroyd_b.toml (Fang et al. 2006 §4) at half resolution (dx = 0.04 cm, 1961
# particles) to t V/D = 4 (through the impact, the fastest spreading and the retraction):
#   epsilon = 0   (no artificial stress) fractures: tools/drop_measure.py --expect-fracture
#   epsilon = 0.5 (Fang's value)         stays intact: --no-fracture, volume error <= 1 %
# The full-resolution runs to t V/D = 8 are in docs/validation.md §10 (too long for CI).
. "$(dirname "$0")/lib.sh"
CASE=$SRC/cases/drop_oldroyd_b.toml
HALF="--set particles.spacing=4e-4 --set domain.min=[-0.06,-0.0012] --set blocks[1].min=[-0.05,-0.0012] --set time.end=0.08 --set output.interval=0.005"
for eps in 0 0.5; do
  # shellcheck disable=SC2086
  OMP_NUM_THREADS=1 "$VESPH" run "$CASE" -o "$WORK/e$eps" --quiet $HALF --set effects.artificial_stress.epsilon=$eps \
    >"$WORK/e$eps.log" 2>&1 &
done
wait
for eps in 0 0.5; do
  grep -q '"status": "ok"' "$WORK/e$eps/summary.json" 2>/dev/null && pass || fail "epsilon = $eps: the run did not finish: $(tail -3 "$WORK/e$eps.log")"
done
$PY "$SRC/tools/drop_measure.py" "$WORK/e0/drop_oldroyd_b.h5" --no-png --expect-fracture >"$WORK/m0.log" 2>&1 && pass ||
  fail "epsilon = 0 did not fracture: $(tail -4 "$WORK/m0.log")"
$PY "$SRC/tools/drop_measure.py" "$WORK/e0.5/drop_oldroyd_b.h5" --no-png --no-fracture --max-volume-error 0.01 >"$WORK/m5.log" 2>&1 && pass ||
  fail "epsilon = 0.5 fractured or lost volume: $(tail -4 "$WORK/m5.log")"
finish
