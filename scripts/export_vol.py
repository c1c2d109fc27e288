"""Export a fitted field as dense world-space .vol grids for Mitsuba's own gridvolume / heterogeneous medium.

Runs voldis_cli/export_vol.py from a checkout; installed, the same program is the command `voldis-export-vol`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.export_vol import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
