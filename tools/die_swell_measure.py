#!/usr/bin/python3
"""The documented command `tools/die_swell_measure.py`: runs `python3 -m vesph.measure.die_swell` (vesph/measure/die_swell.py) with the
same arguments. New command lines can use `tools/vesph-post die_swell_measure` instead."""
import sys

from vesph.measure import die_swell as tool

if __name__ == "__main__":
    sys.exit(tool.main())
