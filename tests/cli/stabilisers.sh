# The stabilisers (artificial_viscosity, xsph, artificial_stress, particle_shifting; surface_pressure) switched on in existing scenes
# by --set: each runs a short Poiseuille channel to the end with valid output, the artificial
# stress also the Oldroyd-B channel (elastic stress on fluid and wall particles); `check` prints
# their defaults; bad keys and missing prerequisites exit 2 with a message naming the key.
. "$(dirname "$0")/lib.sh"
S=$SCENE
OB=$SRC/cases/startup_channel_oldroyd_b.toml
SHORT="--set time.end=0.01 --set output.times=[0.01]"
run_ok() {  # run_ok NAME SCENE --set ...: runs to the end and writes a valid file
  name=$1; scene=$2; shift 2
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$scene" -o "$WORK/$name" --quiet $SHORT "$@"
  $PY "$SRC/tools/check_output.py" "$WORK/$name" >"$WORK/$name.log" 2>&1 && pass ||
    fail "$name: output not valid: $(tail -3 "$WORK/$name.log")"
}
run_ok av "$S" --set 'effects.artificial_viscosity.alpha=1.0' --set 'effects.artificial_viscosity.beta=2.0'
run_ok xsph "$S" --set 'effects.xsph.epsilon=0.5'
run_ok xsph_normalised "$S" --set 'effects.xsph.form="normalised"'
run_ok as "$S" --set 'effects.artificial_stress.epsilon=0.3' --set 'effects.equation_of_state.reference_pressure=-1e-5'
run_ok all "$S" --set 'effects.artificial_viscosity={ alpha = 1.0, beta = 2.0 }' --set 'effects.xsph={}' --set 'effects.artificial_stress={}'
run_ok as_oldroyd_b "$OB" --set 'effects.artificial_stress={}' --set 'effects.artificial_viscosity={ alpha = 1.0, beta = 2.0 }'
run_ok shifting "$S" --set 'effects.particle_shifting.speed=0.01'
run_ok surface_pressure_oldroyd_b "$OB" --set 'effects.free_surface={}' --set 'effects.surface_pressure={}'
run_ok shifting_oldroyd_b "$OB" --set 'effects.particle_shifting.speed=0.01' --set 'effects.particle_shifting.coefficient=1.0'

# defaults shown by check
# the water defaults (DualSPHysics' alpha = 0.01, no beta term; Fang's drops state alpha = 1, beta = 2)
expect 0 "artificial_viscosity = \{ alpha = 0.01, beta = 0.0 \}" -- "$VESPH" check "$S" --set 'effects.artificial_viscosity={}'
expect 0 "artificial_stress = \{ epsilon = 0.2[0-9]*, exponent = 4 \}" -- "$VESPH" check "$S" --set 'effects.artificial_stress={}'
expect 0 "xsph = \{ epsilon = 0.5, form = 'monaghan' \}" -- "$VESPH" check "$S" --set 'effects.xsph={}'
expect 0 "coefficient = 2.0" -- "$VESPH" check "$S" --set 'effects.particle_shifting.speed=0.01'
expect 0 "artificial_viscosity" -- "$VESPH" list
for word in xsph artificial_stress particle_shifting; do
  grep -q "$word" "$WORK/out" && pass || fail "vesph list does not mention $word"
done

expect 0 "value = 'normal_stress'" -- "$VESPH" check "$OB" --set 'effects.free_surface={}' --set 'effects.surface_pressure={}'

# bad keys
expect 2 "effects.surface_pressure needs the free-surface flags and normals: add \[effects.free_surface\]" -- "$VESPH" check "$OB" --set 'effects.surface_pressure={}'
# a Newtonian fluid's normal stress comes from the velocity gradient: refused without it, accepted with it
expect 2 "needs the stress T: the extra stress of the second-order fluid, or the velocity gradient" -- "$VESPH" check "$S" --set 'effects.free_surface={}' --set 'effects.surface_pressure={}'
expect 0 "surface_pressure = \{ ambient_pressure = 0.0, value = 'normal_stress' \}" -- "$VESPH" check "$S" --set 'effects.free_surface={}' --set 'effects.surface_pressure={}' --set 'effects.velocity_gradient={}'
expect 2 "the ISPH projection imposes its surface pressure itself" -- "$VESPH" check "$SRC/cases/poiseuille_newtonian_isph.toml" --set 'effects.free_surface={}' --set 'effects.surface_pressure={}'
expect 2 "effects.surface_pressure.value: expected one of: normal_stress, zero" -- "$VESPH" check "$OB" --set 'effects.free_surface={}' --set 'effects.surface_pressure.value="half"'
expect 2 "effects.artificial_viscosity.alpha: expected a non-negative number, got -1" -- "$VESPH" check "$S" --set effects.artificial_viscosity.alpha=-1
expect 2 "effects.artificial_viscosity.beta: expected a non-negative number" -- "$VESPH" check "$S" --set effects.artificial_viscosity.beta=-2
expect 2 "effects.xsph.epsilon: expected a number in \[0, 1\], got 1.5" -- "$VESPH" check "$S" --set effects.xsph.epsilon=1.5
expect 2 "effects.xsph.form: expected one of: monaghan, normalised" -- "$VESPH" check "$S" --set 'effects.xsph.form="shepard"'
expect 2 "unknown key 'effects.xsph.eps'" -- "$VESPH" check "$S" --set effects.xsph.eps=0.5
expect 2 "effects.artificial_stress.epsilon: expected a number in \[0, 1\]" -- "$VESPH" check "$S" --set effects.artificial_stress.epsilon=-0.1
expect 2 "effects.artificial_stress.exponent: expected an integer in \[1, 16\], got 0" -- "$VESPH" check "$S" --set effects.artificial_stress.exponent=0
expect 2 "effects.artificial_stress.exponent: expected an integer" -- "$VESPH" check "$S" --set effects.artificial_stress.exponent=2.5
expect 2 "W\(dx\) = 0" -- "$VESPH" check "$S" --set 'effects.artificial_stress={}' --set particles.smoothing_ratio=0.5 --set 'particles.kernel="cubic"'
expect 2 "effects.particle_shifting.speed: expected a positive number \(this key is required\)" -- "$VESPH" check "$S" --set 'effects.particle_shifting={}'
expect 2 "effects.particle_shifting.coefficient: expected a number in \[0, 100\]" -- "$VESPH" check "$S" --set effects.particle_shifting.speed=1 --set effects.particle_shifting.coefficient=-1
# prerequisites: the sound speed and the pressure come from the equation of state
grep -v '^\[effects.equation_of_state\]\|^sound_speed\|^\[effects.pressure_gradient\]' "$S" > "$WORK/noeos.toml"
expect 2 "noeos.toml: effects.artificial_viscosity needs the sound speed.*add \[effects.equation_of_state\]" -- "$VESPH" check "$WORK/noeos.toml" --set 'effects.artificial_viscosity={}'
# the ISPH signal speed is for scenes without an equation of state only
expect 2 "effects.artificial_viscosity.sound_speed: only in scenes without an equation of state" -- "$VESPH" check "$S" --set 'effects.artificial_viscosity.sound_speed=12.5'
expect 2 "effects.artificial_viscosity.sound_speed: expected a positive number \(m/s\)" -- "$VESPH" check "$WORK/noeos.toml" --set 'effects.artificial_viscosity.sound_speed=-1'
expect 2 "noeos.toml: effects.artificial_stress needs the particle pressure.*add \[effects.equation_of_state\]" -- "$VESPH" check "$WORK/noeos.toml" --set 'effects.artificial_stress={}'
finish
