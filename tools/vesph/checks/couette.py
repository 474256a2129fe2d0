"""`tools/vesph-post couette_check`: start-up of plane Couette flow against the analytic series
(the check is vesph/checks/moving_walls.py, which documents it)."""
import sys

from vesph.checks.moving_walls import couette_main as main

if __name__ == "__main__":
    sys.exit(main())
