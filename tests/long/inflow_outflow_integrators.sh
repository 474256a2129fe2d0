# Long test (ctest -L long): the open channel of cases/channel_inflow_outflow.toml
# (tests/cli/inflow_outflow.sh runs it under the leapfrog and arkode) under midpoint and
# arkode-fixed: the particle accounting and the Poiseuille profile within 3 % by
# tools/inflow_check.py, and flow counts in summary.json; and the body-force channel
# (cases/channel_open_body_force.toml; the suite runs it under the leapfrog) under arkode: its flow
# rate within 3 %. About 160 s on one core.
. "$(dirname "$0")/../cli/lib.sh"
for integ in midpoint arkode-fixed; do open_channel "$integ"; done
open_channel_body_force arkode
finish
