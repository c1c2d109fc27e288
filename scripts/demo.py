"""The README's main command: the whole pipeline on the bundled default scene.

Runs voldis_cli/demo.py from a checkout; installed, the same program is the command `voldis-demo`.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # a checkout without installing

from voldis_cli.demo import entry, main  # noqa: E402, F401  (main: for tests that call the script)

if __name__ == "__main__":
    entry()
