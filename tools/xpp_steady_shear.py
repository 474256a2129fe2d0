#!/usr/bin/python3
"""The documented command `tools/xpp_steady_shear.py`: runs `python3 -m vesph.checks.xpp_shear` (vesph/checks/xpp_shear.py) with the
same arguments. New command lines can use `tools/vesph-post xpp_steady_shear` instead."""
import sys

from vesph.checks import xpp_shear as tool

if __name__ == "__main__":
    sys.exit(tool.main())
