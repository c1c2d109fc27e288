"""Crash-safe output folders: staged, checkpointed, swapped into place whole.

Every long job (a fit, a task, a rendered dataset) writes into ``OUT.partial`` and, once complete,
renames it to ``OUT`` (an existing ``OUT`` is first renamed to ``OUT.old`` and removed after the
swap), so ``OUT`` is never half-written and a failure leaves it as it was. A killed job leaves its
``OUT.partial`` with its checkpoints for ``--resume``; a finished job's ``OUT`` holds no checkpoints.
"""
import contextlib
import json
import os
import shutil

import numpy as np


def staging(out):
    return out.rstrip("/") + ".partial"


CHECKPOINTS = "checkpoints"  # the folder of a job's checkpoints, inside its OUT.partial
MIN_FREE_BYTES = 256 << 20  # refuse to start a job with less free disk than this beside OUT


def check_output(out, resume=False, min_free=MIN_FREE_BYTES):
    """Checks made before any work: ``out`` is a folder or does not exist yet, the folder it will be
    made in (its nearest existing ancestor; missing parents are created) is writable with ``min_free``
    bytes free, and (``resume``) a staged ``OUT.partial`` exists. Raises ``ValueError`` naming the path."""
    out = out.rstrip("/") or "/"
    for path in (out, staging(out)):
        if os.path.exists(path) and not os.path.isdir(path):
            raise ValueError(f"{path}: exists and is not a folder (output folders are replaced whole; move the "
                             "file away or choose another --out)")
    parent = os.path.dirname(os.path.abspath(out))
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        raise ValueError(f"{parent}: is a file, so {out} cannot be made")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{parent}: not writable, so {out} cannot be made")
    free = shutil.disk_usage(parent).free
    if free < min_free:
        raise ValueError(f"{parent}: only {free >> 20} MiB free on this disk; a run needs at least {min_free >> 20}")
    if resume and not os.path.isdir(staging(out)):
        raise ValueError(f"{staging(out)}: nothing to resume (no staged output)")


@contextlib.contextmanager
def staged(out, resume=False, keep_checkpoints=False):
    """``with staged(OUT, resume) as stage:`` write everything into ``stage``; on leaving the block
    without an exception it replaces ``OUT``. ``resume``: continue an existing ``OUT.partial``.
    A failed job leaves ``OUT`` as it was, and its ``OUT.partial`` only if it holds a checkpoint to
    resume from; a finished one drops its ``checkpoints/`` (what it made is written beside them)
    unless ``keep_checkpoints``."""
    check_output(out, resume)
    stage = staging(out)
    if not resume:
        shutil.rmtree(stage, ignore_errors=True)
    os.makedirs(stage, exist_ok=True)
    try:
        yield stage
    except BaseException:
        if not _has_checkpoint(stage):
            shutil.rmtree(stage, ignore_errors=True)
        raise
    commit(stage, out)
    if not keep_checkpoints:
        shutil.rmtree(os.path.join(out, CHECKPOINTS), ignore_errors=True)


def _has_checkpoint(stage):
    return any(f.endswith(".npz") for _, _, files in os.walk(stage) for f in files)


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
    """Write ``data`` as strict JSON via a temporary file (never half-written); NaN and infinities,
    which JSON cannot hold, become null."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(_finite(data), f, indent=1, allow_nan=False)
    os.replace(tmp, path)


def _finite(x):
    """``x`` with NumPy scalars and arrays as Python values and non-finite floats as None."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, np.ndarray):
        return _finite(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


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
