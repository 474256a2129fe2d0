#!/usr/bin/python3
"""The documented command `tools/isph_bench.py`: runs `python3 -m vesph.studies.isph_bench` (vesph/studies/isph_bench.py) with the
same arguments. New command lines can use `tools/vesph-post isph_bench` instead."""
import sys

from vesph.studies import isph_bench as tool

if __name__ == "__main__":
    sys.exit(tool.main())
