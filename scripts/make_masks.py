"""Object masks for every view of a dataset from the masks of a few views, or from a box around the object.

Runs voldis_cli/make_masks.py from a checkout; installed, the same program is the command `voldis-make-masks`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.make_masks import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
