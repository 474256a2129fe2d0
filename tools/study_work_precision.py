#!/usr/bin/python3
"""The documented command `tools/study_work_precision.py`: runs `python3 -m vesph.studies.work_precision` (vesph/studies/work_precision.py) with the
same arguments. New command lines can use `tools/vesph-post study_work_precision` instead."""
import sys

from vesph.studies import work_precision as tool

if __name__ == "__main__":
    sys.exit(tool.main())
