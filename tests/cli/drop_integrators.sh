# Every drop case under the integrators (issues 5, 6): the three cases of Fang et al. (2006) §4
# (cases/drop_newtonian.toml, drop_oldroyd_b.toml, drop_ucm.toml) and the two ISPH drops
# (drop_newtonian_isph.toml, drop_oldroyd_b_isph.toml; arkode's velocity scale is then the drop's
# initial speed) at their default settings, nothing but the integrator type changed: here the
# leapfrog (the fixed-step reference), arkode (adaptive) and symplectic (at its own default CFL
# coefficient); midpoint and arkode-fixed against the leapfrog in the long test
# tests/long/drop_integrators_fixed_step.sh. To keep CI short they run at a quarter of the
# resolution (dx = 0.08 cm, D/dx = 25, about 490 particles) to t V/D = 2 (through the impact at
# 1.5 and the fastest spreading); the Oldroyd-B ISPH drop, with its particle shifting, at half the
# resolution (dx = 0.04 cm, D/dx = 50): at a quarter its rim under the adaptive ARKODE moves by
# 0.03 D (three quarters of a spacing) when only output.interval changes (0.005 ... 0.001 s:
# 1.944 ... 1.996 with the shifting, 1.953 ... 1.986 without; leapfrog 1.974), more than the
# tolerance below; at half resolution the four agree within 0.001 D (2.0103 ... 2.0112).
# Each run must finish (status ok), keep the volume within 1 % and not fracture
# (tools/drop_measure.py), and the integrators must agree on the spread at t V/D = 2 within 3 %
# of D (lib.sh: drop_integrators). (ISPH: the volume sum m/rho is constant by construction; the
# check still runs.) The full-resolution runs are in docs/validation.md §10 and §11.
. "$(dirname "$0")/lib.sh"
drop_integrators "leapfrog arkode symplectic"
finish
