#!/usr/bin/python3
"""The documented command `tools/startup_channel_profiles.py`: runs `python3 -m vesph.measure.channel_profiles` (vesph/measure/channel_profiles.py) with the
same arguments. New command lines can use `tools/vesph-post startup_channel_profiles` instead."""
import sys

from vesph.measure import channel_profiles as tool

if __name__ == "__main__":
    sys.exit(tool.main())
