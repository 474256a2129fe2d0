# Long test (ctest -L long): the drops of tests/cli/drop_integrators.sh under midpoint and
# arkode-fixed beside the leapfrog (lib.sh: drop_integrators): every run finishes, keeps its
# volume within 1 %, does not fracture, and the three agree on width/D at t V/D = 2 within 0.03.
# About 130 s on one core.
. "$(dirname "$0")/../cli/lib.sh"
drop_integrators "leapfrog midpoint arkode-fixed"
finish
