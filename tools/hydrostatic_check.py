#!/usr/bin/python3
"""The documented command `tools/hydrostatic_check.py`: runs `python3 -m vesph.measure.hydrostatic` (vesph/measure/hydrostatic.py) with the
same arguments. New command lines can use `tools/vesph-post hydrostatic_check` instead."""
import sys

from vesph.measure import hydrostatic as tool

if __name__ == "__main__":
    sys.exit(tool.main())
