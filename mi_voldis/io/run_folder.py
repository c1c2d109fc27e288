"""Crash-safe output folders: staged, checkpointed, swapped into place whole.

Every long job (a fit, a task, a rendered dataset) writes into ``OUT.partial`` and, once complete,
renames it to ``OUT`` (an existing ``OUT`` is first renamed to ``OUT.old`` and removed after the
swap), so ``OUT`` is never half-written and a failure leaves it as it was. A killed job leaves its
``OUT.partial`` with its checkpoints for ``--resume``.
"""
import contextlib
import json
import os
import shutil

import numpy as np


def staging(out):
    return out.rstrip("/") + ".partial"


@contextlib.contextmanager
def staged(out, resume=False):
    """``with staged(OUT, resume) as stage:`` write everything into ``stage``; on leaving the block
    without an exception it replaces ``OUT``. ``resume``: continue an existing ``OUT.partial``."""
    stage = staging(out)
    if resume and not os.path.isdir(stage):
        raise ValueError(f"{stage}: nothing to resume (no staged output)")
    if not resume:
        shutil.rmtree(stage, ignore_errors=True)
    os.makedirs(stage, exist_ok=True)
    yield stage
    commit(stage, out)


def commit(stage, out):
    """Replace ``out`` by the finished ``stage`` with renames only."""
    old = out.rstrip("/") + ".old"
    shutil.rmtree(old, ignore_errors=True)
    if os.path.exists(out):
        os.replace(out, old)
    os.replace(stage, out)
    shutil.rmtree(old, ignore_errors=True)


class Checkpoint:
    """One file holding arrays and a JSON header, replaced atomically (a kill -9 leaves the previous one)."""

    def __init__(self, path):
        self.path = path

    def save(self, arrays, meta):
        os.makedirs(os.path.dirname(self.path), exist_ok=True)
        tmp = self.path + ".tmp.npz"
        np.savez(tmp, __meta__=np.frombuffer(json.dumps(meta).encode(), np.uint8), **arrays)
        os.replace(tmp, self.path)

    def load(self):
        if not os.path.isfile(self.path):
            return None
        with np.load(self.path) as f:
            meta = json.loads(bytes(f["__meta__"]).decode())
            arrays = {k: f[k] for k in f.files if k != "__meta__"}
        return arrays, meta


def write_json(path, data):
    """Write ``data`` as JSON via a temporary file (never half-written)."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, default=float)
    os.replace(tmp, path)


def peak_rss_mib():
    """Peak resident memory of this process in MiB (``VmHWM``; None where /proc is missing).

    Unlike ``ru_maxrss``, VmHWM belongs to the address space and starts afresh at ``exec``: a child
    process forked from a large parent would otherwise report the parent's peak."""
    try:
        with open("/proc/self/status") as f:
            line = next(line for line in f if line.startswith("VmHWM:"))
    except (OSError, StopIteration):
        return None
    return int(line.split()[1]) / 1024.0
