#!/usr/bin/python3
"""The documented command `tools/check_output.py`: runs `python3 -m vesph.checks.output_file` (vesph/checks/output_file.py) with the
same arguments. New command lines can use `tools/vesph-post check_output` instead."""
import sys

from vesph.checks import output_file as tool

if __name__ == "__main__":
    sys.exit(tool.main())
