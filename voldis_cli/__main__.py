"""``python -m voldis_cli PROGRAM [ARGS]``: a program of this package by name (``train``, ``optimize``,
``render``, ...), the same as ``scripts/PROGRAM.py`` of a checkout and the ``voldis-*`` command of an
install; the benchmark runs its children so, which works both where the scripts are and where only the
package is installed."""
import importlib
import sys

PROGRAMS = ("train", "optimize", "render", "make_dataset", "make_masks", "evaluate", "export_vol", "bench", "demo")

if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] not in PROGRAMS:
        sys.exit(f"usage: python -m voldis_cli {{{','.join(PROGRAMS)}}} [ARGS]")
    name = sys.argv.pop(1)
    sys.argv[0] = f"voldis_cli {name}"
    importlib.import_module(f"voldis_cli.{name}").entry()
