#!/usr/bin/python3
"""The documented command `tools/study_convergence.py`: runs `python3 -m vesph.studies.convergence` (vesph/studies/convergence.py) with the
same arguments. New command lines can use `tools/vesph-post study_convergence` instead."""
import sys

from vesph.studies import convergence as tool

if __name__ == "__main__":
    sys.exit(tool.main())
