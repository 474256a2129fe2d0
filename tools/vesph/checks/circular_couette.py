"""`tools/vesph-post circular_couette_check`: steady circular Couette flow against v = A r + B/r
(the check is vesph/checks/moving_walls.py, which documents it)."""
import sys

from vesph.checks.moving_walls import circular_main as main

if __name__ == "__main__":
    sys.exit(main())
