# Invalid input exits 2 with a message naming the file, the key and what is expected.
. "$(dirname "$0")/lib.sh"
S=$SCENE
expect 2 "poiseuille_newtonian.toml: unknown key 'fluid.viscosty'.*valid keys in \[fluid\]: density, viscosity" -- "$VESPH" check "$S" --set fluid.viscosty=1
expect 2 "fluid.viscosity: expected a non-negative number \(Pa s\), got -1" -- "$VESPH" check "$S" --set fluid.viscosity=-1
expect 2 "fluid.density: expected a positive number \(kg/m\^3\), got \"water\"" -- "$VESPH" check "$S" --set fluid.density=water
expect 2 "integrator.type: expected one of: leapfrog, midpoint, arkode, arkode-fixed, symplectic, arkode-imex, arkode-imex-fixed, semi-implicit, got \"rk99\"" -- "$VESPH" check "$S" --set integrator.type=rk99
expect 2 "effects.turbulence: expected the name of an effect \(continuity, " -- "$VESPH" check "$S" --set "effects.turbulence={}"
expect 2 "blocks\[0\].max: expected an extent that is a whole number of particle spacings" -- "$VESPH" check "$S" --set particles.spacing=3e-5
expect 2 "blocks\[1\].max: expected a wall at least one kernel support thick" -- "$VESPH" check "$S" --set particles.smoothing_ratio=2.0
expect 2 "particles.kernel: expected one of: cubic, quintic, wendland_c2, got \"gauss\"" -- "$VESPH" check "$S" --set particles.kernel=gauss
expect 2 "domain.periodic: expected an array of 2 booleans" -- "$VESPH" check "$S" --set "domain.periodic=[true]"
expect 2 "integrator.cfl: expected a number in \[1e-06, 1\]" -- "$VESPH" check "$S" --set integrator.cfl=2
# the adaptive arkode takes the limits as caps above its error-controlled step: up to 10
expect 0 "cfl = 4" -- "$VESPH" check "$S" --set integrator.type=arkode --set integrator.cfl=4 --set integrator.viscous_coefficient=2
expect 2 "integrator.cfl: expected a number in \[1e-06, 10\]" -- "$VESPH" check "$S" --set integrator.type=arkode --set integrator.cfl=11
# ISPH has no sound-speed rule: arkode's velocity scale is the fastest initial fluid speed (the
# drop's 1 m/s), and a fluid at rest (the tank) must give reference_velocity
expect 0 "type = 'arkode'" -- "$VESPH" check "$SRC/cases/drop_newtonian_isph.toml" --set integrator.type=arkode
expect 2 "integrator.reference_velocity: expected the expected flow speed.*no sound-speed rule, inflow or initial fluid velocity gives one" -- "$VESPH" check "$SRC/cases/hydrostatic_tank_isph.toml" --set integrator.type=arkode
expect 2 "integrator.viscous_coefficient: expected a number in \[1e-06, 1\]" -- "$VESPH" check "$S" --set integrator.type=arkode-fixed --set integrator.viscous_coefficient=2
expect 2 "poiseuille_newtonian.toml: domain: the periodic length along axis 0 .* must be at least 3 times the neighbour search radius" -- "$VESPH" check "$S" --set "domain.max=[2.0e-4, 1.125e-3]" --set "blocks[0].max=[2.0e-4, 1.0e-3]" --set "blocks[1].max=[2.0e-4, 0.0]" --set "blocks[2].max=[2.0e-4, 1.125e-3]"
grep -v '^\[effects.equation_of_state\]\|^sound_speed' "$S" > "$WORK/noeos.toml"
expect 2 "noeos.toml: effects.pressure_gradient needs the particle pressure.*add \[effects.equation_of_state\]" -- "$VESPH" check "$WORK/noeos.toml"
# A required key that is missing, and a file that is not TOML or does not exist.
grep -v '^end = 0.5' "$S" > "$WORK/noend.toml"
expect 2 "noend.toml: time.end: expected a positive number \(s\) \(this key is required\)" -- "$VESPH" check "$WORK/noend.toml"
printf 'name = "x"\n[fluid\ndensity = 1\n' > "$WORK/bad.toml"
expect 2 "bad.toml: not valid TOML" -- "$VESPH" check "$WORK/bad.toml"
expect 2 "missing.toml: cannot open the scene file" -- "$VESPH" run "$WORK/missing.toml"
expect 2 "--set 'novalue': expected KEY=VALUE" -- "$VESPH" check "$S" --set novalue
# a solvent viscosity that no effect applies (it would show in extra_stress only)
sed -e '/^\[effects.viscosity\]/d' "$SRC/cases/startup_channel_oldroyd_b.toml" > "$WORK/ob_no_viscosity.toml"
expect 2 "solvent viscosity, but the scene has no \[effects.viscosity\]" -- "$VESPH" check "$WORK/ob_no_viscosity.toml"
# run refuses invalid input before writing anything
expect 2 "fluid.viscosity" -- "$VESPH" run "$S" -o "$WORK/out_bad" --set fluid.viscosity=-1
[ ! -e "$WORK/out_bad" ] && pass || fail "run with invalid input created its output directory"
finish
