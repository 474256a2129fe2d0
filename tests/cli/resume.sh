# `vesph run --resume`: a run split into segments gives the run it would have been in one piece.
# Every frame is a checkpoint (/checkpoint: the integrator's state vector, the particle ids and
# the run's totals); --resume goes on from it, appending frames and diagnostics.
. "$(dirname "$0")/lib.sh"
CHECK="$PY $SRC/tools/check_output.py"
H5=poiseuille_newtonian.h5

# compare A B TOL: the two outputs have the same frames (times, steps) and diagnostics times,
# and their frames agree in position, velocity, density (and extra_stress) within TOL of each
# field's largest magnitude. The fixed-step integrators take the same steps after a resume
# (their carried rate F^n is restored, Integrator::carried), so only the summation order of the
# neighbour sums (a fresh neighbour list) can differ.
compare() {
  $PY - "$1" "$2" "$3" <<'PYEOF'
import glob, sys
import h5py, numpy as np
a_path, b_path = (glob.glob(d + "/*.h5")[0] for d in sys.argv[1:3])
tol = float(sys.argv[3])
with h5py.File(a_path, "r") as a, h5py.File(b_path, "r") as b:
    fa, fb = sorted(a["frames"]), sorted(b["frames"])
    assert fa == fb, f"frames {fa} vs {fb}"
    for k in fa:
        ga, gb = a["frames"][k], b["frames"][k]
        assert ga.attrs["time"] == gb.attrs["time"], (k, ga.attrs["time"], gb.attrs["time"])
        assert ga.attrs["step"] == gb.attrs["step"], (k, ga.attrs["step"], gb.attrs["step"])
        assert (ga["id"][:] == gb["id"][:]).all(), k
        for name in ("position", "velocity", "density", "extra_stress"):
            if name not in ga:
                continue
            x, y = ga[name][:], gb[name][:]
            scale = max(np.abs(x).max(), 1e-300)
            err = np.abs(x - y).max() / scale
            assert err <= tol, f"frame {k} {name}: relative difference {err:.3g} > {tol:g}"
    ta, tb = a["diagnostics/time"][:], b["diagnostics/time"][:]
    assert len(ta) == len(tb) and np.array_equal(ta, tb), f"diagnostics: {len(ta)} vs {len(tb)} rows"
print("same run:", len(fa), "frames,", len(ta), "diagnostics rows")
PYEOF
}

# 1. The Poiseuille demo in one piece and in two (to t = 0.1125 s, then on to 0.5 s).
"$VESPH" run "$SCENE" -o "$WORK/full" --quiet >"$WORK/full.log" 2>&1 || fail "full run: $(tail -3 "$WORK/full.log")"
expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/seg" --quiet --set time.end=0.1125 --set "output.times=[0.0225, 0.045, 0.1125]"
expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/seg" --quiet --resume
compare "$WORK/full" "$WORK/seg" 1e-12 >"$WORK/cmp.log" 2>&1 && pass || fail "segmented Poiseuille run differs: $(tail -3 "$WORK/cmp.log")"
$CHECK "$WORK/seg" >"$WORK/check.log" 2>&1 && pass || fail "resumed output is not valid: $(tail -5 "$WORK/check.log")"
$PY - "$WORK/full/summary.json" "$WORK/seg/summary.json" >"$WORK/sum.log" 2>&1 <<'PYEOF' && pass || fail "summary of the resumed run: $(tail -3 "$WORK/sum.log")"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
assert b["status"] == "ok" and b["steps"] == a["steps"], (a["steps"], b["steps"])
assert b["frames"] == a["frames"] and b["final_time"] == a["final_time"]
assert b["resumed"]["count"] == 1 and abs(b["resumed"]["from_time"] - 0.1125) < 1e-12, b["resumed"]
assert "resumed" not in a
PYEOF

# 2. Resuming a finished run with a later end time extends it (time.end may change).
expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/seg" --quiet --resume --set time.end=0.6 --set "output.times=[0.55]"
frames=$($PY -c "import h5py,sys; f=h5py.File(sys.argv[1]); print(len(f['frames']), f['frames/000006'].attrs['time'])" "$WORK/seg/$H5")
[ "$frames" = "7 0.6" ] && pass || fail "extended run: expected 7 frames ending at 0.6 s, got '$frames'"

# 3. Refusals (exit 2, the earlier output untouched): a physics key changed, nothing to resume.
expect 2 "the scene differs .* at 'fluid.viscosity'; only \[time\], \[output\], \[checks\] and \[integrator\]" -- \
  "$VESPH" run "$SCENE" -o "$WORK/seg" --quiet --resume --set time.end=0.7 --set fluid.viscosity=2e-3
frames=$($PY -c "import h5py,sys; print(len(h5py.File(sys.argv[1])['frames']))" "$WORK/seg/$H5")
[ "$frames" = 7 ] && pass || fail "a refused resume changed the file: $frames frames"
expect 2 "nothing to resume: .*does not exist" -- "$VESPH" run "$SCENE" -o "$WORK/none" --quiet --resume

# 4. A viscoelastic scene (the elastic stress is part of the state) under the leapfrog, split at
#    an output time, and under ARKODE (adaptive: the resumed segment starts with a fresh step
#    size estimate, so it is the same run only to within the error tolerance).
#    Two relaxation times (t = 0.25 s, lambda = 0.125 s), split at one.
OB=$SRC/cases/startup_channel_oldroyd_b.toml
half=0.125
"$VESPH" run "$OB" -o "$WORK/ob_full" --quiet --set time.end=0.25 >"$WORK/ob_full.log" 2>&1 || fail "OB run: $(tail -3 "$WORK/ob_full.log")"
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_seg" --quiet --set time.end="$half" --set "output.times=[$half]"
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_seg" --quiet --resume --set time.end=0.25
$PY - "$WORK/ob_full" "$WORK/ob_seg" >"$WORK/ob_cmp.log" 2>&1 <<'PYEOF' && pass || fail "segmented Oldroyd-B run differs: $(tail -3 "$WORK/ob_cmp.log")"
import glob, sys
import h5py, numpy as np
a, b = (h5py.File(glob.glob(d + "/*.h5")[0], "r") for d in sys.argv[1:3])
la, lb = a["frames"][sorted(a["frames"])[-1]], b["frames"][sorted(b["frames"])[-1]]
assert la.attrs["time"] == lb.attrs["time"] and la.attrs["step"] == lb.attrs["step"]
for name in ("velocity", "extra_stress"):
    x, y = la[name][:], lb[name][:]
    err = np.abs(x - y).max() / np.abs(x).max()
    assert err < 1e-12, (name, err)
print("same final frame")
PYEOF

# 4b. An effect with between-step state (the second-order fluid's lagged material derivative
#     keeps the last step's acceleration and velocity: Effect::saveCarried / restoreCarried) is restored too.
LAG="--set effects.second_order_fluid.material_derivative=lagged --set effects.second_order_fluid.alpha1=-5e-5 --set output.interval=5e-4"
# shellcheck disable=SC2086
"$VESPH" run "$SOF" -o "$WORK/sof_full" --quiet $LAG --set time.end=2e-3 >"$WORK/sof.log" 2>&1 || fail "SOF run: $(tail -3 "$WORK/sof.log")"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SOF" -o "$WORK/sof_seg" --quiet $LAG --set time.end=1e-3
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SOF" -o "$WORK/sof_seg" --quiet $LAG --set time.end=2e-3 --resume
compare "$WORK/sof_full" "$WORK/sof_seg" 1e-12 >"$WORK/sof_cmp.log" 2>&1 && pass || fail "segmented lagged SOF run differs: $(tail -3 "$WORK/sof_cmp.log")"
for integ in arkode; do
  "$VESPH" run "$OB" -o "$WORK/ob_${integ}_full" --quiet --set integrator.type=$integ --set time.end=0.25 >"$WORK/ob_a.log" 2>&1 || fail "OB $integ: $(tail -3 "$WORK/ob_a.log")"
  expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_${integ}_seg" --quiet --set integrator.type=$integ --set time.end="$half" --set "output.times=[$half]"
  expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_${integ}_seg" --quiet --set integrator.type=$integ --resume --set time.end=0.25
  $PY - "$WORK/ob_${integ}_full" "$WORK/ob_${integ}_seg" >"$WORK/ob_a_cmp.log" 2>&1 <<'PYEOF' && pass || fail "segmented OB $integ run: $(tail -3 "$WORK/ob_a_cmp.log")"
import glob, sys
import h5py, numpy as np
a, b = (h5py.File(glob.glob(d + "/*.h5")[0], "r") for d in sys.argv[1:3])
la, lb = a["frames"][sorted(a["frames"])[-1]], b["frames"][sorted(b["frames"])[-1]]
assert la.attrs["time"] == lb.attrs["time"]
for name in ("velocity", "extra_stress"):
    x, y = la[name][:], lb[name][:]
    err = np.abs(x - y).max() / np.abs(x).max()
    # ARKODE's default relative tolerance is 1e-4 (per step); the two runs take different steps.
    assert err < 1e-3, (name, err)
    print(name, "relative difference", err)
PYEOF
done

# 4c. Open boundaries: the particle set changes during the run (released and removed
#     particles, new ids, the buffer moving); the checkpoint keeps the whole set, the next id
#     and the totals. Prescribed and extrapolated (body-force) inflow, 74 and 90 particles
#     released and removed by t = 0.1 s, split at 0.05 s.
for flow in channel_inflow_outflow channel_open_body_force; do
  F=$SRC/cases/$flow.toml
  "$VESPH" run "$F" -o "$WORK/${flow}_full" --quiet --set time.end=0.1 --set output.interval=0.025 >"$WORK/flow.log" 2>&1 ||
    fail "$flow: $(tail -3 "$WORK/flow.log")"
  expect 0 "ok: finished" -- "$VESPH" run "$F" -o "$WORK/${flow}_seg" --quiet --set time.end=0.05 --set output.interval=0.025
  expect 0 "ok: finished" -- "$VESPH" run "$F" -o "$WORK/${flow}_seg" --quiet --set time.end=0.1 --set output.interval=0.025 --resume
  compare "$WORK/${flow}_full" "$WORK/${flow}_seg" 1e-12 >"$WORK/flow_cmp.log" 2>&1 && pass || fail "segmented $flow run differs: $(tail -3 "$WORK/flow_cmp.log")"
  $PY - "$WORK/${flow}_full/$flow.h5" "$WORK/${flow}_seg/$flow.h5" >"$WORK/flow_diag.log" 2>&1 <<'PYEOF' && pass || fail "$flow: flow diagnostics differ: $(tail -3 "$WORK/flow_diag.log")"
import sys
import h5py, numpy as np
a, b = (h5py.File(p, "r") for p in sys.argv[1:3])
for c in ("released", "removed", "fluid_particles"):
    assert np.array_equal(a["diagnostics/" + c][:], b["diagnostics/" + c][:]), c
assert a["diagnostics/released"][-1] > 0 and a["diagnostics/removed"][-1] > 0, "nothing released or removed: no test"
print("released", a["diagnostics/released"][-1], "removed", a["diagnostics/removed"][-1])
PYEOF
done

# 4d. The one-evaluation symplectic integrator carries the rates of its last (midpoint)
#     evaluation, which are not a function of the state: restored from the checkpoint, the
#     resumed run is the same run. The Poiseuille demo, the Oldroyd-B channel (stresses in the
#     state) and the inflow/outflow channel (the particle set changes, the rates re-evaluated).
SYM="--set integrator.type=symplectic"
# shellcheck disable=SC2086
"$VESPH" run "$SCENE" -o "$WORK/sym_full" --quiet $SYM --set time.end=0.225 --set "output.times=[0.1125]" >"$WORK/sym.log" 2>&1 || fail "symplectic run: $(tail -3 "$WORK/sym.log")"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/sym_seg" --quiet $SYM --set time.end=0.1125 --set "output.times=[0.1125]"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/sym_seg" --quiet $SYM --set time.end=0.225 --set "output.times=[0.1125]" --resume
compare "$WORK/sym_full" "$WORK/sym_seg" 1e-12 >"$WORK/sym_cmp.log" 2>&1 && pass || fail "segmented symplectic Poiseuille run differs: $(tail -3 "$WORK/sym_cmp.log")"
# shellcheck disable=SC2086
"$VESPH" run "$OB" -o "$WORK/ob_sym_full" --quiet $SYM --set time.end=0.25 --set output.interval=$half >"$WORK/ob_sym.log" 2>&1 || fail "OB symplectic: $(tail -3 "$WORK/ob_sym.log")"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_sym_seg" --quiet $SYM --set time.end="$half" --set output.interval=$half
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$OB" -o "$WORK/ob_sym_seg" --quiet $SYM --resume --set time.end=0.25 --set output.interval=$half
compare "$WORK/ob_sym_full" "$WORK/ob_sym_seg" 1e-12 >"$WORK/ob_sym_cmp.log" 2>&1 && pass || fail "segmented symplectic Oldroyd-B run differs: $(tail -3 "$WORK/ob_sym_cmp.log")"
F=$SRC/cases/channel_inflow_outflow.toml
# shellcheck disable=SC2086
"$VESPH" run "$F" -o "$WORK/flow_sym_full" --quiet $SYM --set time.end=0.1 --set output.interval=0.025 >"$WORK/flow_sym.log" 2>&1 ||
  fail "inflow/outflow symplectic: $(tail -3 "$WORK/flow_sym.log")"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$F" -o "$WORK/flow_sym_seg" --quiet $SYM --set time.end=0.05 --set output.interval=0.025
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$F" -o "$WORK/flow_sym_seg" --quiet $SYM --set time.end=0.1 --set output.interval=0.025 --resume
compare "$WORK/flow_sym_full" "$WORK/flow_sym_seg" 1e-12 >"$WORK/flow_sym_cmp.log" 2>&1 && pass || fail "segmented symplectic inflow/outflow run differs: $(tail -3 "$WORK/flow_sym_cmp.log")"

# 4d. ISPH: the projection hook carries the pressure field (the incremental form's p^n in the
#     right-hand side, BiCGSTAB's first guess) and its solver totals (StepHook::saveCarried);
#     without them the resumed segment would start from a pressure solved afresh. The tank
#     with BiCGSTAB (a first guess that differs changes the iterates), 20 steps split at 10.
T=$SRC/cases/hydrostatic_tank_isph.toml
TANK="--set time.end=0.04 --set output.interval=0.02 --set solver.linear_solver=\"bicgstab\" --set solver.tolerance=1e-10"
# shellcheck disable=SC2086
"$VESPH" run "$T" -o "$WORK/tank_full" --quiet $TANK >"$WORK/tank.log" 2>&1 || fail "ISPH tank: $(tail -3 "$WORK/tank.log")"
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/tank_seg" --quiet $TANK --set time.end=0.02
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/tank_seg" --quiet $TANK --resume
compare "$WORK/tank_full" "$WORK/tank_seg" 1e-12 >"$WORK/tank_cmp.log" 2>&1 && pass || fail "segmented ISPH run differs: $(tail -3 "$WORK/tank_cmp.log")"
$PY - "$WORK/tank_full" "$WORK/tank_seg" >"$WORK/tank_sum.log" 2>&1 <<'PYEOF' && pass || fail "ISPH resume: pressure or totals differ: $(tail -3 "$WORK/tank_sum.log")"
import glob, json, sys
import h5py, numpy as np
a, b = (h5py.File(glob.glob(d + "/*.h5")[0], "r") for d in sys.argv[1:3])
la, lb = a["frames"][sorted(a["frames"])[-1]], b["frames"][sorted(b["frames"])[-1]]
x, y = la["pressure"][:], lb["pressure"][:]
err = np.abs(x - y).max() / np.abs(x).max()
assert err < 1e-12, ("pressure", err)
sa, sb = (json.load(open(d + "/summary.json"))["isph"] for d in sys.argv[1:3])
assert sa["solves"] == sb["solves"] > 0, (sa["solves"], sb["solves"])
assert sa["iterations_total"] == sb["iterations_total"], (sa["iterations_total"], sb["iterations_total"])
assert sa["iterations_max"] == sb["iterations_max"]
print("pressure", err, "solves", sb["solves"], "iterations", sb["iterations_total"])
PYEOF

# 5. After SIGINT the run goes on from the state it was interrupted at, and ends where the
#    uninterrupted run ends.
"$VESPH" run "$SCENE" -o "$WORK/int" --quiet >"$WORK/int.log" 2>&1 &
pid=$!
sleep 2
kill -INT $pid
wait $pid
code=$?
if [ "$code" = 130 ]; then
  expect 0 "ok: finished" -- "$VESPH" run "$SCENE" -o "$WORK/int" --quiet --resume
  $PY - "$WORK/full/$H5" "$WORK/int/$H5" >"$WORK/int_cmp.log" 2>&1 <<'PYEOF' && pass || fail "interrupted and resumed run: $(tail -3 "$WORK/int_cmp.log")"
import sys
import h5py, numpy as np
a, b = (h5py.File(p, "r") for p in sys.argv[1:3])
la, lb = a["frames"][sorted(a["frames"])[-1]], b["frames"][sorted(b["frames"])[-1]]
assert la.attrs["time"] == lb.attrs["time"] and la.attrs["step"] == lb.attrs["step"], (la.attrs["step"], lb.attrs["step"])
err = np.abs(la["velocity"][:] - lb["velocity"][:]).max() / np.abs(la["velocity"][:]).max()
assert err < 1e-12, err
assert len(b["frames"]) == len(a["frames"]) + 1  # the frame written at the interruption
assert np.array_equal(a["diagnostics/time"][:], b["diagnostics/time"][:])
print("ok")
PYEOF
elif [ "$code" = 0 ]; then
  echo "note: the run finished within 2 s, nothing was interrupted"
  pass
else
  fail "interrupted run exited $code: $(tail -3 "$WORK/int.log")"
fi
finish
