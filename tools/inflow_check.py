#!/usr/bin/python3
"""The documented command `tools/inflow_check.py`: runs `python3 -m vesph.measure.inflow` (vesph/measure/inflow.py) with the
same arguments. New command lines can use `tools/vesph-post inflow_check` instead."""
import sys

from vesph.measure import inflow as tool

if __name__ == "__main__":
    sys.exit(tool.main())
