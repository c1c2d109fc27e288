#!/usr/bin/env sh
# Make sure a libLLVM >= 16 exists for Dr.Jit's LLVM backend (Debian's LLVM 15 crashes its JIT with
# "Cannot select: fminimum"). Installs Debian's libllvm19 when none is found; prints the library path.
set -eu
best=""
best_ver=0
for lib in /usr/lib/*-linux-gnu/libLLVM*.so* /usr/lib/llvm-*/lib/libLLVM*.so* /usr/lib64/libLLVM*.so*; do
    [ -e "$lib" ] || continue
    ver=$(printf '%s\n' "$lib" | sed -n 's/.*\(libLLVM[-.]\|llvm-\)\([0-9][0-9]*\).*/\2/p' | head -n 1)
    [ -n "$ver" ] || continue
    if [ "$ver" -ge 16 ] && [ "$ver" -gt "$best_ver" ]; then best="$lib"; best_ver="$ver"; fi
done
if [ -z "$best" ]; then
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "error: no libLLVM >= 16 found and no apt-get to install one; install LLVM 16+ and set DRJIT_LIBLLVM_PATH" >&2
        exit 1
    fi
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "installing Debian's libllvm19 for Dr.Jit (LLVM >= 16 needed) ..." >&2
    $sudo apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq libllvm19 >&2
    exec "$0"
fi
echo "$best"
