"""Score a run's removal against a dataset's ground-truth backgrounds (SPIn-NeRF's protocol).

Runs voldis_cli/evaluate.py from a checkout; installed, the same program is the command `voldis-evaluate`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.evaluate import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
