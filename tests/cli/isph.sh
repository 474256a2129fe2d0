# Incompressible SPH (solver.scheme = "isph", src/isph): the projection after every step.
#  - transient Poiseuille (cases/poiseuille_newtonian_isph.toml, shortened to t = 0.1125 s)
#    within the foundation's 2 % of the analytic solution under the leapfrog, arkode and the
#    symplectic integrator (which evaluates its rates again after every projection, which
#    changes the state); midpoint and arkode-fixed: tests/long/isph_integrators.sh;
#  - hydrostatic tank (cases/hydrostatic_tank_isph.toml, to t = 0.6 s): pressure within 2 % of
#    rho g depth below the first three particle layers at every frame, max speed below
#    1e-3 sqrt(g H) after settling (t >= 0.5 s); with the case's predictor form within 1e-3
#    from 0.2 s and 2e-4, which the incremental form does not reach;
#  - divergence cleaning (tank to t = 0.3 s): discrete divergence after / before < 1e-6 at every
#    step, pressure still within 2 %;
#  - the linear solvers (umfpack, klu, bicgstab with diagonal and ILUT preconditioners) give
#    the same pressure to the iterative tolerance;
#  - a failed solve (BiCGSTAB limited to one iteration) stops the run with exit 3, the last good
#    frame and summary.json (status "diverged");
#  - scene errors: WCSPH effects in an ISPH scene, ISPH keys in a WCSPH scene, iterative keys
#    with a direct solver exit 2 naming the key.
. "$(dirname "$0")/lib.sh"
T=$SRC/cases/hydrostatic_tank_isph.toml

# leapfrog, arkode and symplectic here; midpoint and arkode-fixed in tests/long/isph_integrators.sh.
for integ in leapfrog arkode symplectic; do isph_poiseuille "$integ"; done
$PY - "$WORK/p_symplectic/summary.json" >"$WORK/p_sym.log" 2>&1 <<'PYEOF' && pass || fail "symplectic under ISPH: $(tail -3 "$WORK/p_sym.log")"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["rhs_evals"] == 2 * s["steps"] + 1, (s["steps"], s["rhs_evals"])  # one more after each projection
PYEOF
grep -q '"scheme": "isph"' "$WORK/p_leapfrog/summary.json" && grep -q '"solves"' "$WORK/p_leapfrog/summary.json" && pass ||
  fail "summary.json lacks the ISPH solver figures"

expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/tank" --quiet --set time.end=0.6
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/tank/hydrostatic_tank_isph.h5" --max-speed 1e9) >"$WORK/tank.log" 2>&1 && pass ||
  fail "hydrostatic tank pressure: $(tail -5 "$WORK/tank.log")"
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/tank/hydrostatic_tank_isph.h5" --from 0.5) >"$WORK/tank2.log" 2>&1 && pass ||
  fail "hydrostatic tank after settling: $(tail -5 "$WORK/tank2.log")"
$PY "$SRC/tools/check_output.py" "$WORK/tank" >"$WORK/tank_out.log" 2>&1 && pass || fail "tank output not valid: $(tail -3 "$WORK/tank_out.log")"
# The case's predictor form (solver.carried_pressure = "predictor") settles far closer than the
# 2 % / 1e-3 of the issue: pressure within 1e-3 of rho g H from 0.2 s, after the start-up
# (measured 1.1e-4 at 0.2 s, 4.1e-3 at 0.1 s), speed below 2e-4 sqrt(gH) from 0.5 s (measured
# 9.0e-5). The incremental form, which keeps what earlier steps left in the pressure, does not
# reach 1e-3 (measured 5.4e-3 at 0.25 s).
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/tank/hydrostatic_tank_isph.h5" --from 0.2 --tolerance 1e-3 --max-speed 1e9) >"$WORK/tank3.log" 2>&1 && pass ||
  fail "predictor tank pressure within 1e-3: $(tail -5 "$WORK/tank3.log")"
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/tank/hydrostatic_tank_isph.h5" --from 0.5 --max-speed 2e-4) >"$WORK/tank4.log" 2>&1 && pass ||
  fail "predictor tank speed below 2e-4: $(tail -5 "$WORK/tank4.log")"
expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/tank_inc" --quiet --set time.end=0.3 --set output.interval=0.25 \
  --set 'solver.carried_pressure="increment"'
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/tank_inc/hydrostatic_tank_isph.h5" --from 0.2 --tolerance 1e-3 --max-speed 1e9) >"$WORK/tank5.log" 2>&1 &&
  fail "the incremental tank reached 1e-3 of rho g H (the contrast to the predictor form is gone): $(tail -3 "$WORK/tank5.log")" || pass

# Divergence cleaning (solver.divergence_cleaning): the discrete divergence after the exact
# projection is below 1e-6 of the divergence of v* at every step (issue 6), the pressure stays
# hydrostatic within 2 % (t = 0.3 s: 150 steps; the settled speed is in docs/validation.md §11).
expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/clean" --quiet --set time.end=0.3 --set output.interval=0.1 \
  --set solver.divergence_cleaning=true
(cd "$SRC/tools" && $PY hydrostatic_check.py "$WORK/clean/hydrostatic_tank_isph.h5" --max-speed 1e9) >"$WORK/clean.log" 2>&1 && pass ||
  fail "tank with divergence cleaning, pressure: $(tail -5 "$WORK/clean.log")"
$PY - "$WORK/clean/hydrostatic_tank_isph.h5" >"$WORK/clean_div.log" 2>&1 <<'PYEOF' && pass || fail "divergence cleaning: $(tail -5 "$WORK/clean_div.log")"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    d = f["diagnostics"]
    before, projected, after = d["divergence_before"][:], d["divergence_projected"][:], d["divergence_after"][:]
ratio = after / before
print(f"steps {len(ratio)}, after/before max {ratio.max():.3e}, projected/before min {(projected / before).min():.3f}")
assert len(ratio) >= 100
assert ratio.max() < 1e-6, f"div after / div before = {ratio.max():.3e} >= 1e-6"
# the approximate projection alone leaves most of it (the cleaning is what removes it)
assert (projected / before).min() > 0.1
PYEOF
expect 2 "solver.cleaning_solver: expected only with divergence_cleaning = true" -- "$VESPH" check "$T" --set 'solver.cleaning_solver="klu"'

# The solvers agree: 5 steps of the tank with each, final pressures compared.
TSHORT="--set time.end=0.01 --set output.interval=0.01"
for s in umfpack klu; do
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/s_$s" --quiet $TSHORT --set "solver.linear_solver=\"$s\""
done
for pc in diagonal ilut; do
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$T" -o "$WORK/s_$pc" --quiet $TSHORT --set 'solver.linear_solver="bicgstab"' \
    --set "solver.preconditioner=\"$pc\"" --set solver.tolerance=1e-12 --set solver.max_iterations=20000
done
$PY - "$WORK" >"$WORK/agree.log" 2>&1 <<'PYEOF' && pass || fail "solvers disagree: $(tail -5 "$WORK/agree.log")"
import sys, h5py, numpy as np
w = sys.argv[1]
def last(name):
    with h5py.File(f"{w}/s_{name}/hydrostatic_tank_isph.h5", "r") as f:
        fr = f["frames"][sorted(f["frames"])[-1]]
        return fr["pressure"][:]
ref = last("umfpack")
scale = np.abs(ref).max()
for name, tol in (("klu", 1e-9), ("diagonal", 1e-6), ("ilut", 1e-6)):
    d = np.abs(last(name) - ref).max() / scale
    print(name, d)
    assert d < tol, f"{name}: max |p - p_umfpack| / max |p| = {d:.3e} >= {tol}"
PYEOF

# A failed solve: exit 3, last good frame, summary.
expect 3 "ISPH (initial )?pressure solve failed.*no convergence" -- "$VESPH" run "$T" -o "$WORK/fail" --quiet $TSHORT \
  --set 'solver.linear_solver="bicgstab"' --set solver.max_iterations=1 --set solver.tolerance=1e-14
grep -q '"status": "diverged"' "$WORK/fail/summary.json" && pass || fail "failed solve: summary.json status is not diverged"
$PY "$SRC/tools/check_output.py" "$WORK/fail" >"$WORK/fail.log" 2>&1 && pass || fail "failed solve: output not valid: $(tail -3 "$WORK/fail.log")"

# Scene errors.
expect 2 "effects.equation_of_state: not with solver.scheme = \"isph\"" -- "$VESPH" check "$T" --set 'effects.equation_of_state.sound_speed=10.0'
expect 2 "effects.continuity: not with solver.scheme = \"isph\"" -- "$VESPH" check "$T" --set 'effects.continuity={}'
# the artificial viscosity takes its signal speed from the scene in ISPH (no equation of state)
expect 2 "effects.artificial_viscosity needs the sound speed.*give effects.artificial_viscosity.sound_speed" -- "$VESPH" check "$T" --set 'effects.artificial_viscosity={}'
expect 0 "sound_speed = 12.5" -- "$VESPH" check "$T" --set 'effects.artificial_viscosity.sound_speed=12.5'
expect 2 "solver.linear_solver: expected no linear_solver with scheme = \"wcsph\"" -- "$VESPH" check "$SCENE" --set 'solver.linear_solver="klu"'
expect 2 "solver.tolerance: expected no tolerance for the direct solver 'umfpack'" -- "$VESPH" check "$T" --set solver.tolerance=1e-8
expect 2 "solver.linear_solver: expected one of: umfpack, klu, bicgstab" -- "$VESPH" check "$T" --set 'solver.linear_solver="cholmod"'
expect 2 "solver.scheme: expected one of: wcsph, isph" -- "$VESPH" check "$T" --set 'solver.scheme="sph"'
expect 0 "ISPH projection after every step" -- "$VESPH" check "$T"
expect 0 "umfpack" -- "$VESPH" list
finish
