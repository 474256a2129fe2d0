#!/usr/bin/python3
"""The documented command `tools/die_swell_study.py`: runs `python3 -m vesph.studies.die_swell` (vesph/studies/die_swell.py) with the
same arguments. New command lines can use `tools/vesph-post die_swell_study` instead."""
import sys

from vesph.studies import die_swell as tool

if __name__ == "__main__":
    sys.exit(tool.main())
