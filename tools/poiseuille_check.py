#!/usr/bin/python3
"""The documented command `tools/poiseuille_check.py`: runs `python3 -m vesph.checks.poiseuille` (vesph/checks/poiseuille.py) with the
same arguments. New command lines can use `tools/vesph-post poiseuille_check` instead."""
import sys

from vesph.checks import poiseuille as tool

if __name__ == "__main__":
    sys.exit(tool.main())
