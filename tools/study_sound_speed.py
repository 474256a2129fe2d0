#!/usr/bin/python3
"""The documented command `tools/study_sound_speed.py`: runs `python3 -m vesph.studies.sound_speed` (vesph/studies/sound_speed.py) with the
same arguments. New command lines can use `tools/vesph-post study_sound_speed` instead."""
import sys

from vesph.studies import sound_speed as tool

if __name__ == "__main__":
    sys.exit(tool.main())
