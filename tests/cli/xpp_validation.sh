# Validation: start-up of plane channel flow of an XPP fluid (cases/startup_channel_xpp.toml,
# Wi = 2 at the wall, 49 % shear thinning) with the leapfrog, checked by
# tools/xpp_steady_shear.py:
#  - at t = 6 lambda_0b, over the interior particles, T_xy, tau_xy, tau_xx, tau_yy, N1, tau_zz
#    (extra_stress_zz) and v_x within 3 % of the maxima of the steady homogeneous-shear XPP
#    solution at the local shear stress T_xy = -rho F (y - y_c) (the reference is itself
#    within 0.5 % of its steady state by then: the 1-D start-up);
#  - --transient: every frame finite; the centreline velocity and the interior maxima of
#    |T_xy| and T_xx at most 2 times their steady values, within 3 % of the 1-D start-up of the
#    same flow (incompressible, method of lines) and without frame-to-frame oscillation about
#    it (second difference of the deviation below 0.01);
#  - the same check at a 0.5 % tolerance must fail (the velocity error is about 1.3 %): the
#    check discriminates;
#  - the output is a valid vesph-1 file with extra_stress_zz (tools/check_output.py).
# The case under arkode is run once by hand (docs/validation.md), not here (cost).
. "$(dirname "$0")/lib.sh"
CASE=$SRC/cases/startup_channel_xpp.toml
expect 0 "ok: finished" -- "$VESPH" run "$CASE" -o "$WORK/xpp" --quiet
H5=$WORK/xpp/startup_channel_xpp.h5
$PY "$SRC/tools/xpp_steady_shear.py" check "$H5" --transient > "$WORK/check.log" 2>&1 \
  && pass || fail "XPP validation: $(grep -E 'FAIL|error' "$WORK/check.log")"
grep -E "^steady reference|1-D start-up at|^  [A-Za-z_0-9]+ +max|peak|RESULT" "$WORK/check.log"
$PY "$SRC/tools/xpp_steady_shear.py" check "$H5" --tolerance 0.005 > "$WORK/tight.log" 2>&1
[ $? = 1 ] && grep -q "RESULT: FAIL" "$WORK/tight.log" && pass \
  || fail "the check at a 0.5 % tolerance did not fail: $(tail -3 "$WORK/tight.log")"
$PY "$SRC/tools/check_output.py" "$WORK/xpp" > "$WORK/out.log" 2>&1 && pass || fail "invalid output: $(tail -5 "$WORK/out.log")"
grep -q "extra_stress_zz" "$WORK/xpp/startup_channel_xpp.xdmf" && pass || fail "the XDMF file does not declare extra_stress_zz"
finish
