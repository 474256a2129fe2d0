"""`tools/vesph-post rotation_check`: spin-up in a rotating closed box toward solid-body rotation
(the check is vesph/checks/moving_walls.py, which documents it)."""
import sys

from vesph.checks.moving_walls import rotation_main as main

if __name__ == "__main__":
    sys.exit(main())
