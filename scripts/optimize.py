"""Run a manipulation task on a fitted run.

Runs voldis_cli/optimize.py from a checkout; installed, the same program is the command `voldis-edit`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.optimize import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
