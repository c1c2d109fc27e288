"""Point Dr.Jit's LLVM backend at a libLLVM it can use (version 16 or newer).

Dr.Jit 1.5 emits intrinsics (e.g. ``llvm.minimum``) that LLVM 15 cannot select, so a machine whose
default libLLVM is 15 crashes inside the JIT. When ``DRJIT_LIBLLVM_PATH`` is unset, this module looks
for the newest ``libLLVM`` >= 16 in the usual Debian/Ubuntu locations and exports its path before the
LLVM backend starts. ``make setup`` installs Debian's ``libllvm19`` when none is found.
"""
import glob
import os
import re

MIN_VERSION = 16
SEARCH = ("/usr/lib/*-linux-gnu/libLLVM*.so*", "/usr/lib/llvm-*/lib/libLLVM*.so*", "/usr/lib64/libLLVM*.so*",
          "/opt/homebrew/opt/llvm/lib/libLLVM.dylib", "/usr/local/opt/llvm/lib/libLLVM.dylib")


def _version(path):
    m = re.search(r"(?:libLLVM[-.]|llvm-)(\d+)", path)
    return int(m.group(1)) if m else 0


def find_libllvm():
    """Path of the newest libLLVM with major version >= 16, or None."""
    found = [p for pattern in SEARCH for p in glob.glob(pattern) if _version(p) >= MIN_VERSION]
    return max(found, key=_version) if found else None


def configure():
    """Export ``DRJIT_LIBLLVM_PATH`` unless the user already chose a library."""
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        path = find_libllvm()
        if path:
            os.environ["DRJIT_LIBLLVM_PATH"] = path
