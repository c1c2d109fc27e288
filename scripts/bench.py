"""Speed against error, side by side, in one command.

Runs voldis_cli/bench.py from a checkout; installed, the same program is the command `voldis-bench`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.bench import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
