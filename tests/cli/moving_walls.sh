# Moving walls (docs/validation.md §15): the start-up of plane Couette flow against the analytic
# series (max error below 1 % of the wall speed at t = 0.025, 0.05, 0.1, 0.25 s) under the
# leapfrog and ARKODE, ramped over 0.1 s, with ISPH over its first 0.05 s and with translating
# image walls; the spin-up of a fluid in a
# rotating closed box toward solid-body rotation (below 0.1 % of omega L/2 at t = 0.2 s, still
# above 30 % at 0.01 s, the deviation's decay rate within 5 % of the square's slowest Stokes
# mode), also split in two by a resume (the walls' motion continues from the resumed time);
# refusals of bad motion keys (exit 2).
. "$(dirname "$0")/lib.sh"
COUETTE=$SRC/cases/couette_startup.toml
BOX=$SRC/cases/rotating_box.toml
POST="$SRC/tools/vesph-post"
for integrator in leapfrog arkode; do
  expect 0 "ok: finished" -- "$VESPH" run "$COUETTE" -o "$WORK/c-$integrator" --quiet --set "integrator.type=\"$integrator\""
  "$POST" couette_check "$WORK/c-$integrator/couette_startup.h5" --times 0.025 0.05 0.1 0.25 --tolerance 0.01 >"$WORK/check.log" 2>&1 \
    && pass || fail "$integrator: Couette start-up: $(cat "$WORK/check.log")"
  cat "$WORK/check.log"
done
# The ramped start (ramp_time = 0.1 s) against the series by Duhamel's principle.
expect 0 "ok: finished" -- "$VESPH" run "$COUETTE" -o "$WORK/c-ramp" --quiet --set "blocks[2].ramp_time=0.1"
"$POST" couette_check "$WORK/c-ramp/couette_startup.h5" --times 0.025 0.05 0.1 0.25 --tolerance 0.01 >"$WORK/check.log" 2>&1 \
  && pass || fail "ramped Couette start-up: $(cat "$WORK/check.log")"
cat "$WORK/check.log"
# ISPH: the same scene with the projection instead of the equation of state.
sed -e '/^\[effects.continuity\]/d' -e '/^\[effects.equation_of_state\]/d' -e '/^sound_speed/d' \
    -e '/^\[effects.pressure_gradient\]/d' -e 's/^name = .*/name = "couette_isph"/' "$COUETTE" > "$WORK/couette_isph.toml"
printf '\n[solver]\nscheme = "isph"\nlinear_solver = "umfpack"\n' >> "$WORK/couette_isph.toml"
expect 0 "ok: finished" -- "$VESPH" run "$WORK/couette_isph.toml" -o "$WORK/c-isph" --quiet --set time.end=0.05 --set "output.times=[0.025, 0.05]"
"$POST" couette_check "$WORK/c-isph/couette_isph.h5" --times 0.025 0.05 --tolerance 0.01 >"$WORK/check.log" 2>&1 \
  && pass || fail "ISPH: Couette start-up: $(cat "$WORK/check.log")"
cat "$WORK/check.log"
# Image walls (Fang's boundary + image particles, translating): the image-wall channel with the
# body force off and its upper wall sliding at U.
expect 0 "ok: finished" -- "$VESPH" run "$SRC/cases/poiseuille_newtonian_image_walls.toml" -o "$WORK/c-image" --quiet \
  --set "effects.body_force.acceleration=[0.0, 0.0]" --set "blocks[2].velocity=[1.0e-3, 0.0]" \
  --set "effects.equation_of_state.sound_speed={phi = 4.0, delta = 0.01, velocity = 1.0e-3, length = 1.0e-3}" \
  --set time.end=0.25 --set "output.times=[0.025, 0.05, 0.1, 0.25]"
"$POST" couette_check "$WORK/c-image/poiseuille_newtonian_image_walls.h5" --tolerance 0.01 >"$WORK/check.log" 2>&1 \
  && pass || fail "image walls: Couette start-up: $(cat "$WORK/check.log")"
cat "$WORK/check.log"

# The rotating box, in one piece and split at t = 0.05 s by a resume.
expect 0 "ok: finished" -- "$VESPH" run "$BOX" -o "$WORK/box" --quiet
"$POST" rotation_check "$WORK/box/rotating_box.h5" --time 0.2 --tolerance 0.001 --early-time 0.01 --early-minimum 0.3 \
  --decay 0.05 0.1 --decay-tolerance 0.05 >"$WORK/check.log" 2>&1 && pass || fail "rotating box: $(cat "$WORK/check.log")"
cat "$WORK/check.log"
expect 0 "ok: finished" -- "$VESPH" run "$BOX" -o "$WORK/box-seg" --quiet --set time.end=0.05 --set "output.times=[0.01, 0.05]"
expect 0 "ok: finished" -- "$VESPH" run "$BOX" -o "$WORK/box-seg" --quiet --resume
$PY - "$WORK/box/rotating_box.h5" "$WORK/box-seg/rotating_box.h5" >"$WORK/cmp.log" 2>&1 <<'PYEOF' && pass || fail "resumed rotating box differs: $(tail -3 "$WORK/cmp.log")"
# The same frames, fluid and walls (their positions and velocities set from t) within 1e-12 of
# each field's largest magnitude (a fresh neighbour list after the resume may sum in another order).
import sys
import h5py, numpy as np
with h5py.File(sys.argv[1], "r") as a, h5py.File(sys.argv[2], "r") as b:
    fa, fb = sorted(a["frames"]), sorted(b["frames"])
    assert fa == fb, (fa, fb)
    for k in fa:
        ga, gb = a["frames"][k], b["frames"][k]
        assert ga.attrs["time"] == gb.attrs["time"] and ga.attrs["step"] == gb.attrs["step"], k
        assert (ga["id"][:] == gb["id"][:]).all(), k
        for name in ("position", "velocity", "density"):
            x, y = ga[name][:], gb[name][:]
            err = np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)
            assert err <= 1e-12, f"frame {k} {name}: relative difference {err:.3g}"
    walls = a["frames"][fa[-1]]["kind"][:] != 0
    x = a["frames"][fa[-1]]["position"][:][walls]
    x0 = a["frames"][fa[0]]["position"][:][walls]
    t = a["frames"][fa[-1]].attrs["time"]
    c, s = np.cos(4.0 * t), np.sin(4.0 * t)
    turned = np.stack([c * x0[:, 0] - s * x0[:, 1], s * x0[:, 0] + c * x0[:, 1]], axis=1)
    assert np.abs(x - turned).max() < 1e-15, "walls not at omega t"
print("same run:", len(fa), "frames; walls turned by omega t =", 4.0 * t, "rad")
PYEOF
cat "$WORK/cmp.log"

# Refusals: exit 2, the key and what is expected.
expect 2 "blocks\[0\].angular_velocity: expected no angular_velocity on a fluid block" -- "$VESPH" check "$COUETTE" --set "blocks[0].angular_velocity=1.0"
expect 2 "blocks\[2\].angular_velocity: expected an axis_point with angular_velocity" -- "$VESPH" check "$COUETTE" --set "blocks[2].angular_velocity=1.0"
expect 2 "blocks\[1\].angular_velocity: expected a number \(rad/s; in 2D one number, the rotation about z" -- "$VESPH" check "$BOX" --set "blocks[1].angular_velocity=[0.0, 0.0, 4.0]"
expect 2 "blocks\[2\].velocity: expected an array of 2 numbers \(m/s\)" -- "$VESPH" check "$COUETTE" --set "blocks[2].velocity=[1.0]"
finish
