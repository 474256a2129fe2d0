# Rod climbing (docs/validation.md §20), the CI version: the scenes of cases/rod_climbing_*.toml
# made small and short (container R = 4a instead of 8a, fluid 3.5a deep instead of 7a, the rod
# at omega = 20 rad/s, 0.2 s: about 600 steps of 4755 particles each), a test of stability and
# of the sign of the effect only, each rise measured from the surface at rest (a fourth run, the
# rod at rest: its surface at the rod -0.013 dx at 0.2 s): the Newtonian surface falls at the rod
# (measured -0.067 dx), an Oldroyd-B fluid with 2 eta_p lambda > rho a^2/2 (lambda = 0.05 s,
# Wi = 1) climbs it (+0.066 dx), and one with 2 eta_p lambda < rho a^2/2 (lambda = 0.005 s,
# Wi = 0.1) still falls (-0.045 dx; the theory: by 0.75 of the Newtonian fall). The bounds are
# about half of each measured rise. Session 23 took the cases back to the default walls (with
# dry_walls = "omit", sessions 21-22: -0.106 / +0.025 / -0.089 dx, the rest +0.008 dx, bounds
# -0.053 / +0.012 / -0.045); from the far level before session 21 -0.079 / +0.053 / -0.058 dx.
# The Wi = 0.1 fall is what the case's both_sides_diffusion mends: with the whole polymer
# viscosity through eq. 27 at this rod of 2 dx that fluid climbed (+0.102 dx, the fluids before
# session 20).
# (Session 20: the cases' fluids more viscous, eta0 = 0.0225 Pa s, and their floor free-slip; with
# the fluids before, -0.066 / +0.107 / -0.057 dx.)
. "$(dirname "$0")/lib.sh"
SMALL="--set domain.min=[-0.0055,-0.0015,-0.0055] --set domain.max=[0.0055,0.008,0.0055]
 --set blocks[0].outer_diameter=0.008 --set blocks[0].length=0.0035 --set blocks[0].centre=[0.0,0.00175,0.0]
 --set blocks[1].length=0.006 --set blocks[1].centre=[0.0,0.003,0.0] --set blocks[1].angular_velocity=[0.0,20.0,0.0]
 --set blocks[2].inner_diameter=0.008 --set blocks[2].outer_diameter=0.011 --set blocks[2].length=0.006
 --set blocks[2].centre=[0.0,0.003,0.0] --set blocks[3].diameter=0.011 --set time.end=0.2 --set output.interval=0.05
 --set effects.equation_of_state.sound_speed.length=0.0035"
# shellcheck disable=SC2086  # SMALL is a list of arguments
expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/rod_climbing_newtonian.toml" -o "$WORK/n" --quiet $SMALL
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/rod_climbing_oldroyd_b.toml" -o "$WORK/ob" --quiet $SMALL \
  --set effects.oldroyd_b.relaxation_time=0.05
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/rod_climbing_oldroyd_b.toml" -o "$WORK/ob01" --quiet $SMALL \
  --set effects.oldroyd_b.relaxation_time=0.005
# The same container with the rod at rest: the surface at rest, from which the rises are measured
# (the walls' contact with the surface moves the first annulus by a few per cent of dx at rest:
# rod_climbing_check --rest, validation.md §20).
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/rod_climbing_newtonian.toml" -o "$WORK/rest" --quiet $SMALL \
  --set 'blocks[1].angular_velocity=[0.0,0.0,0.0]'
# The rise at the rod (the first annulus' surface above the far band's, rod_climbing_check's
# measure) in the last frame less the rest run's at the same time, and the run's sanity (mass,
# volume, speed, no void) in every frame.
PYTHONPATH=$SRC/tools $PY - "$WORK/rest/rod_climbing_newtonian.h5" "$WORK/n/rod_climbing_newtonian.h5" \
  "$WORK/ob/rod_climbing_oldroyd_b.h5" "$WORK/ob01/rod_climbing_oldroyd_b.h5" \
  >"$WORK/sign.log" 2>&1 <<'PYEOF' && pass || fail "sign of the effect: $(tail -5 "$WORK/sign.log")"
import sys
import numpy as np
from vesph.checks.rod_climbing import FRAME_FIELDS, measure_frame, setup
from vesph.output import Output
with Output(sys.argv[1]) as h5:
    rest = measure_frame(h5.read(len(h5.frames) - 1, FRAME_FIELDS), setup(h5.scene, h5.dx, at_rest=True), h5.dx)["rise"]
    rest_time = h5.frames[-1][1]
print(f"at rest: the surface at the rod {rest / h5.dx:+.4f} dx at t = {rest_time:g} s")
# (the expected sign, the bound on the rise in dx): about half of each run's measured rise
for path, (sign, bound) in zip(sys.argv[2:], ((-1, -0.033), (1, 0.033), (-1, -0.022))):
    with Output(path) as h5:
        p, dx = setup(h5.scene, h5.dx), h5.dx
        rows = [measure_frame(h5.read(k, FRAME_FIELDS), p, dx) for k in range(len(h5.frames))]
    assert abs(h5.frames[-1][1] - rest_time) < 1e-9, "the rest run ends at another time"
    rise = (rows[-1]["rise"] - rest) / dx
    print(f"{p['model']}: rise at the rod from the surface at rest {rise:+.4f} dx at t = {h5.frames[-1][1]:g} s "
          f"(expected {'above' if sign > 0 else 'below'} {bound:+g} dx); least interior filling "
          f"{min(m['fill'] for m in rows):.3f}; largest speed {max(m['max_speed'] for m in rows) / (abs(p['omega']) * p['a']):.3f} omega a")
    assert (rise > bound) if sign > 0 else (rise < bound), "wrong sign or too small"
    assert min(m["fill"] for m in rows) > 0.7, "a void"
    assert max(m["max_speed"] for m in rows) < 2 * abs(p["omega"]) * p["a"], "too fast"
    assert abs(rows[-1]["mass"] / rows[0]["mass"] - 1) < 1e-12, "mass changed"
    assert abs(rows[-1]["volume"] / rows[0]["volume"] - 1) < 0.01, "volume changed"
PYEOF
cat "$WORK/sign.log"
finish
