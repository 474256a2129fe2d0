#!/usr/bin/python3
"""The documented command `tools/drop_measure.py`: runs `python3 -m vesph.measure.drop` (vesph/measure/drop.py) with the
same arguments. New command lines can use `tools/vesph-post drop_measure` instead."""
import sys

from vesph.measure import drop as tool

if __name__ == "__main__":
    sys.exit(tool.main())
