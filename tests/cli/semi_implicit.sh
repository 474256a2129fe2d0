# The fixed-step semi-implicit reference (semi-implicit, docs/theory.md §9.6) on the stiff
# cases of tests/cli/imex.sh: the Poiseuille start-up (docs/validation.md §1) at 100 times the
# demo's viscosity and body force, where the explicit part's (acoustic) limit is 28 times the
# viscous limit 0.125 h^2/nu = 2e-6 s: the same check (2 % of the centreline velocity at every
# comparison time) at a median step of at least 20 times the viscous limit. Then the Oldroyd-B
# start-up under ISPH (docs/validation.md §6) at the output interval 0.0125 s (max_step; nothing
# else bounds the step of a fluid at rest), 31 times the viscous limit: the 3 % check.
. "$(dirname "$0")/lib.sh"
stiff_poiseuille semi-implicit poiseuille --set integrator.type=semi-implicit
OBI=$SRC/cases/startup_channel_oldroyd_b_isph.toml
expect 0 "ok: finished" -- "$VESPH" run "$OBI" -o "$WORK/ob" --quiet --set integrator.type=semi-implicit \
  --set integrator.max_step=0.0125
$PY "$SRC/tools/startup_channel_check.py" "$WORK/ob/startup_channel_oldroyd_b_isph.h5" > "$WORK/ob.log" 2>&1 \
  && pass || fail "Oldroyd-B: $(grep -E 'FAIL|steady' "$WORK/ob.log")"
grep -E "^E =|RESULT" "$WORK/ob.log"
dt=$(median_step "$WORK/ob/startup_channel_oldroyd_b_isph.h5")
echo "Oldroyd-B: median step $dt s (4e-4 s viscous limit)"
$PY -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 20 * 4e-4 else 1)" "$dt" \
  && pass || fail "Oldroyd-B: median step $dt s is not 20 times the viscous limit 4e-4 s"
# A resumed run (checkpoints carry f_E, Integrator::carried) gives the run in one piece: the
# WCSPH Oldroyd-B start-up split at 0.015 s. A fresh neighbour list may sum in another order;
# the stage solves then converge from round-off-different values, so 1e-10, not bit for bit.
OB=$SRC/cases/startup_channel_oldroyd_b.toml
SEMI="--set integrator.type=semi-implicit --set output.times=[0.015]"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_full" --quiet $SEMI --set time.end=0.03
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_seg" --quiet $SEMI --set time.end=0.015
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_seg" --quiet $SEMI --set time.end=0.03 --resume
$PY - "$WORK/ob_full" "$WORK/ob_seg" >"$WORK/resume.log" 2>&1 <<'PYEOF' && pass || fail "segmented run differs: $(tail -3 "$WORK/resume.log")"
import glob, sys
import h5py, numpy as np
a, b = (h5py.File(glob.glob(d + "/*.h5")[0], "r") for d in sys.argv[1:3])
assert sorted(a["frames"]) == sorted(b["frames"])
for k in sorted(a["frames"]):
    ga, gb = a["frames"][k], b["frames"][k]
    assert ga.attrs["time"] == gb.attrs["time"] and ga.attrs["step"] == gb.attrs["step"], k
    for name in ("position", "velocity", "density", "extra_stress"):
        x, y = ga[name][:], gb[name][:]
        err = np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)
        assert err <= 1e-10, (k, name, err)
print("segmented run matches")
PYEOF
# A changing particle set (inflow and outflow: the state is resized, the integrator's buffers
# with it): runs, and particles were released and removed.
F=$SRC/cases/channel_inflow_outflow.toml
expect 0 "ok: finished" -- "$VESPH" run "$F" -o "$WORK/inflow" --quiet --set integrator.type=semi-implicit --set time.end=0.03
$PY -c "import sys, h5py; d = h5py.File(sys.argv[1], 'r')['diagnostics']; sys.exit(0 if d['released'][-1] > 0 and d['removed'][-1] > 0 else 1)" \
  "$WORK/inflow/channel_inflow_outflow.h5" && pass || fail "inflow: nothing released or removed by t = 0.03 s"
# A stage solve that does not converge stops the run (exit 3) and says so.
# shellcheck disable=SC2086
expect 3 "did not converge in 3 GMRES iterations" -- "$VESPH" run "$SCENE" -o "$WORK/unconverged" --quiet $STIFF_POISEUILLE \
  --set integrator.type=semi-implicit --set integrator.max_linear_iterations=3
# Keys: max_linear_iterations only for semi-implicit; vesph list shows the integrator.
expect 2 "max_linear_iterations" -- "$VESPH" check "$SCENE" --set integrator.max_linear_iterations=10
expect 0 "semi-implicit" -- "$VESPH" list
finish
