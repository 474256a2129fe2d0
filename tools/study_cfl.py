#!/usr/bin/python3
"""The documented command `tools/study_cfl.py`: runs `python3 -m vesph.studies.cfl` (vesph/studies/cfl.py) with the
same arguments. New command lines can use `tools/vesph-post study_cfl` instead."""
import sys

from vesph.studies import cfl as tool

if __name__ == "__main__":
    sys.exit(tool.main())
