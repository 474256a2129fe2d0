# Long test (ctest -L long): the ISPH Poiseuille start-up of tests/cli/isph.sh (which runs it under
# the leapfrog, arkode and symplectic) under midpoint and arkode-fixed, within 2 % of the analytic
# solution (lib.sh: isph_poiseuille). About 25 s on one core.
. "$(dirname "$0")/../cli/lib.sh"
for integ in midpoint arkode-fixed; do isph_poiseuille "$integ"; done
finish
