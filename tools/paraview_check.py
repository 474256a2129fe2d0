#!/usr/bin/python3
"""The documented command `tools/paraview_check.py`: runs `python3 -m vesph.checks.paraview` (vesph/checks/paraview.py) with the
same arguments. New command lines can use `tools/vesph-post paraview_check` instead."""
import sys

from vesph.checks import paraview as tool

if __name__ == "__main__":
    sys.exit(tool.main())
