"""Render a dataset with ground truth from a bundled Mitsuba scene, or from a random one.

Runs voldis_cli/make_dataset.py from a checkout; installed, the same program is the command `voldis-make-dataset`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.make_dataset import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
