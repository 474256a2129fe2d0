#!/usr/bin/python3
"""The documented command `tools/second_order_channel_check.py`: runs `python3 -m vesph.checks.second_order_channel` (vesph/checks/second_order_channel.py) with the
same arguments. New command lines can use `tools/vesph-post second_order_channel_check` instead."""
import sys

from vesph.checks import second_order_channel as tool

if __name__ == "__main__":
    sys.exit(tool.main())
