#!/usr/bin/python3
"""The documented command `tools/startup_channel_check.py`: runs `python3 -m vesph.checks.startup_channel` (vesph/checks/startup_channel.py) with the
same arguments. New command lines can use `tools/vesph-post startup_channel_check` instead."""
import sys

from vesph.checks import startup_channel as tool

if __name__ == "__main__":
    sys.exit(tool.main())
