"""Crash-safe output folders: guarded, staged, checkpointed, swapped into place whole.

Every job that writes a folder (a fit, a task, a rendered dataset, masks, renders, exports) writes
into ``OUT.partial`` and, once complete, renames it to ``OUT`` (an existing ``OUT`` is first renamed
to ``OUT.old`` and removed after the swap), so ``OUT`` is never half-written and a failure leaves it
as it was. A killed job leaves its ``OUT.partial`` with its checkpoints for ``resume``; a finished
job's ``OUT`` holds no checkpoints.

Nothing a user has is lost: before any work :func:`check_output` refuses an ``OUT`` that is, holds
or lies inside one of the job's inputs (real paths, so symbolic links count), an ``OUT`` that is a
symbolic link, an existing ``OUT``, ``OUT.old`` or ``OUT.partial`` that no mi-voldis job made
(every folder a job stages holds :data:`MARKER`, naming the program and recording the job), and a
job's ``OUT`` or ``OUT.old`` that holds anything its job did not write (the marker lists what the job
left when it was swapped into place: a file the user added, or another job's output made inside it,
such as a task's ``RUN/removal``); a resumable ``OUT.partial`` is kept unless ``restart``. ``OUT.lock``
(the pid of the job) keeps a second job off the same ``OUT``; ``resume`` continues only the very job that
was staged (:func:`check_resume`).
"""
import contextlib
import hashlib
import json
import os
import secrets
import shutil
import xml.etree.ElementTree as ET

import numpy as np


def staging(out):
    return out.rstrip("/") + ".partial"


CHECKPOINTS = "checkpoints"  # the folder of a job's checkpoints, inside its OUT.partial
MIN_FREE_BYTES = 256 << 20  # refuse to start a job with less free disk than this beside OUT
MARKER = ".mi-voldis"  # in every folder a job staged: {"made_by": program, "job": what it was asked to do}
RESUMABLE = "holds the checkpoint of an unfinished job: --resume continues it, --restart discards it"


def _old(out):
    return out.rstrip("/") + ".old"


LOCK_OWNER = "mi-voldis"  # a lock holds "mi-voldis PID": only such a file, its process gone, is taken over


def _lock(out):
    return out.rstrip("/") + ".lock"


def read_marker(folder):
    """The record :data:`MARKER` holds in ``folder``, or None where there is none."""
    try:
        with open(os.path.join(folder, MARKER)) as f:
            record = json.load(f)
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def write_marker(folder, made_by, job=None):
    write_json(os.path.join(folder, MARKER), {"made_by": made_by, "job": job})


def made_by(folder):
    """The program that wrote ``folder`` as the set its :data:`MARKER` names; empty when there is no
    marker. A folder is never taken for a job's by its look (a user's scene folder may hold a
    ``scene.xml`` and a ``config.json`` too)."""
    record = read_marker(folder)
    return set() if record is None else {record.get("made_by")}


def made_here(folder):
    """Whether ``folder`` was written by a mi-voldis job (:func:`made_by`)."""
    return bool(made_by(folder))


def claim(out, program):
    """Make ``out`` a folder of ``program``, which writes into it in place (not staged): it must be new,
    empty, or made by ``program`` before (its :data:`MARKER`); anything else raises ``ValueError`` and is
    left as it is."""
    if os.path.exists(out) and not os.path.isdir(out):
        raise ValueError(f"{out}: exists and is not a folder; choose another output folder")
    if os.path.isdir(out) and os.listdir(out) and made_by(out) != {program}:
        raise ValueError(f"{out}: exists and was not written by {program} (no {MARKER} naming it), so nothing is "
                         "written into it; move it away or choose another output folder")
    os.makedirs(out, exist_ok=True)
    if not made_by(out):
        write_marker(out, program)


def _entries(folder):
    """Every path under ``folder`` (folders, files, links; links not followed), relative to it, but the
    marker."""
    found = []
    for d, dirs, files in os.walk(folder):
        found += [os.path.relpath(os.path.join(d, e), folder) for e in dirs + files]
    return sorted(e for e in found if e != MARKER)


def foreign(folder, shown=3):
    """The first ``shown`` paths in the job folder ``folder`` that its job did not leave there (outermost
    only: a foreign folder is named, not its contents), by the list its :data:`MARKER` records when the
    job is swapped into place (:func:`commit`); a folder written before jobs kept that list has none."""
    record = read_marker(folder)
    left = record.get("files") if isinstance(record, dict) else None
    if not isinstance(left, list):
        return []
    left, found = set(left), []
    for d, dirs, files in os.walk(folder):
        rel = os.path.relpath(d, folder)
        for e in sorted(dirs + files):
            path = os.path.normpath(os.path.join(rel, e))
            if path not in left and path != MARKER:
                found.append(path)
        dirs[:] = [e for e in dirs if os.path.normpath(os.path.join(rel, e)) in left]
        if len(found) >= shown:
            break
    return found[:shown]


def _refuse_foreign(path, verb, shown=3):
    extra = foreign(path, shown + 1)
    if extra:
        program = " or ".join(sorted(str(p) for p in made_by(path)))
        named = ", ".join(extra[:shown]) + (" and more" if len(extra) > shown else "")
        raise ValueError(f"{path}: holds {named}, which the {program} job that wrote it did not write, so it is not "
                         f"{verb}; move {'it' if len(extra) == 1 else 'them'} away or choose another output folder")


def _inside(path, folder):
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def check_inputs(out, inputs):
    """Refuse an ``out`` that is, holds or lies inside one of ``inputs`` (paths, (path, what it is) or
    (path, what, :data:`MAY_HOLD`) where ``out`` may be made inside it), compared as real paths, so
    that replacing ``out`` whole cannot touch what the job reads."""
    real = os.path.realpath(out)
    for item in inputs:
        path, what, how = (tuple(item) + ("input", None))[:3] if isinstance(item, tuple) else (item, "input", None)
        if path is None:
            continue
        other = os.path.realpath(path)
        relation = "is" if real == other else "holds" if _inside(other, real) else \
            "lies inside" if _inside(real, other) and how != MAY_HOLD else None
        if relation:
            raise ValueError(f"{out}: {relation} the {what} {path}, which this job reads; choose an output folder "
                             "apart from its inputs")


MAY_HOLD = "may hold"  # an input folder an output may be made in, beside what it holds


def dataset_inputs(root, replaceable=()):
    """The inputs that keep a dataset folder ``root`` whole: the folder (an output may be made in it)
    and every entry in it but the folders of mi-voldis jobs (:func:`fingerprint` leaves out the same)
    and the names in ``replaceable``."""
    items = [(root, "dataset", MAY_HOLD)]
    if os.path.isdir(root):
        items += [(os.path.join(root, e), "dataset's file") for e in sorted(os.listdir(root))
                  if e not in replaceable and not e.endswith(".lock") and not _job_folder(os.path.join(root, e), ())]
    return items


def check_output(out, inputs=(), resume=False, restart=False, min_free=MIN_FREE_BYTES, program=None):
    """Checks made before any work: ``out`` names a folder apart from the job's ``inputs``
    (:func:`check_inputs`), is not a symbolic link, and is a folder made by a mi-voldis job (or empty)
    or does not exist yet (made by ``program``, when given: a render never replaces a run); ``OUT.old``
    and ``OUT.partial`` were made by a job if they exist; a resumable ``OUT.partial`` is kept unless
    ``restart`` (``resume``: it must exist); the folder ``out`` will be made in (its nearest existing
    ancestor; missing parents are created) is writable with ``min_free`` bytes free. Raises
    ``ValueError`` naming the path."""
    if not isinstance(out, str) or not out.strip():
        raise ValueError(f"the output folder must be a path, got {out!r}")
    if os.path.basename(os.path.normpath(out)) in ("", ".", ".."):
        raise ValueError(f"{out}: names the current folder, its parent or the root, which cannot be replaced whole; "
                         "give a folder inside it")
    if resume and restart:
        raise ValueError("--resume and --restart exclude each other (continue the staged job, or discard it)")
    out = out.rstrip("/")
    check_inputs(out, inputs)
    if os.path.islink(out):
        raise ValueError(f"{out}: is a symbolic link (to {os.readlink(out)}), which would be replaced by a folder; "
                         "give the folder it points to or another output folder")
    stage = staging(out)
    for path in (out, stage, _old(out)):
        if os.path.exists(path) and not os.path.isdir(path):
            raise ValueError(f"{path}: exists and is not a folder (output folders are replaced whole; move the "
                             "file away or choose another --out)")
        verb = "replaced" if path == out else "removed"
        if os.path.isdir(path) and os.listdir(path) and not made_here(path):
            raise ValueError(f"{path}: exists and was not written by mi-voldis (no {MARKER} in it), so it is not "
                             f"{verb}; move it away or choose another output folder")
        if os.path.isdir(path):
            _refuse_foreign(path, verb)
    if program and os.path.isdir(out) and os.listdir(out) and program not in made_by(out):
        raise ValueError(f"{out}: holds the output of {' or '.join(sorted(made_by(out)))}, not of {program}, so it "
                         "is not replaced; choose another output folder")
    if resume and not os.path.isdir(stage):
        raise ValueError(f"{stage}: nothing to resume (no staged output)")
    if not resume and not restart and _has_checkpoint(stage):
        raise ValueError(f"{stage}: {RESUMABLE}")
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


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


@contextlib.contextmanager
def locked(out):
    """Hold ``OUT.lock`` (made with O_EXCL, holding :data:`LOCK_OWNER` and this process's id) while the
    block runs: a second job on the same ``OUT`` is refused; a lock a job left whose process is gone is
    taken over (any other file of that name is left alone, and the job refused)."""
    path = _lock(out)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    while True:
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            break
        except FileExistsError:
            try:
                with open(path) as f:
                    owner, pid = f.read().split()
                pid = int(pid) if owner == LOCK_OWNER else None
            except (OSError, ValueError):
                pid = None
            if pid is None:  # not a lock a job wrote: it is not taken over
                raise ValueError(f"{path}: another job holds {out} (or the lock is not a mi-voldis job's; remove it "
                                 "if no job is writing there)") from None
            if _alive(pid):
                raise ValueError(f"{out}: another job (pid {pid}) is writing it; wait for it to finish or choose "
                                 "another output folder") from None
            with contextlib.suppress(FileNotFoundError):
                os.remove(path)  # stale: the process that held it is gone
    with os.fdopen(fd, "w") as f:
        f.write(f"{LOCK_OWNER} {os.getpid()}\n")
    try:
        yield
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)


def check_resume(stage, job, may_change=()):
    """Refuse to resume ``stage`` for another job than the one staged there: ``job`` (a dict of what
    the job depends on: settings, options, input fingerprints) against the one its :data:`MARKER`
    records, except the keys in ``may_change``. The message names the differences."""
    record = read_marker(stage)
    if job is None or record is None or record.get("job") is None:
        return
    before, now = _flat(record["job"]), _flat(_finite(job))
    changed = [k for k in sorted(set(before) | set(now)) if before.get(k) != now.get(k)
               and k.split(".")[-1] not in may_change and k.split(".")[0] not in may_change]
    if changed:
        shown = "; ".join(f"{k}: {_short(before.get(k))} -> {_short(now.get(k))}" for k in changed[:4])
        more = f" and {len(changed) - 4} more" if len(changed) > 4 else ""
        raise ValueError(f"{stage}: --resume of another job than the one staged ({shown}{more}); give the same "
                         "dataset, settings and options, or --restart to discard the checkpoint")


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            out.update(_flat(v, key + "."))
        else:
            out[key] = v
    return out


def _short(value):
    text = "(none)" if value is None else json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def content_stamp(path):
    """[size, the first 16 hex digits of the SHA-256 of its bytes] of the file ``path``: what tells a
    changed input (a dataset's photo, a run's field), whatever its modification time (a copy, a re-staged
    or touched file keeps it)."""
    with open(path, "rb") as f:
        return [os.fstat(f.fileno()).st_size, hashlib.file_digest(f, "sha256").hexdigest()[:16]]


def fingerprint(root, skip=()):
    """{relative path: :func:`content_stamp`} of the files under ``root``, leaving out ``skip`` and the
    folders of mi-voldis jobs in it (stages, old and locked outputs, runs and tasks; a
    ``make_masks`` folder is kept: its masks are a dataset's) and whatever is not a regular file (a
    named pipe would block the read, a dangling link has nothing to read). Contents, not times: a resumed
    fit needs the same pixels, and a dataset copied or staged again (new times) has them."""
    skip = {os.path.realpath(s) for s in skip}
    out = {}
    for d, dirs, files in os.walk(root):
        dirs[:] = sorted(x for x in dirs if not _job_folder(os.path.join(d, x), skip))
        for f in sorted(files):
            path = os.path.join(d, f)
            if f.endswith(".lock") or not os.path.isfile(path):
                continue
            out[os.path.relpath(path, root)] = content_stamp(path)
    return out


def _job_folder(path, skip):
    if os.path.realpath(path) in skip or path.endswith((".partial", ".old")):
        return True
    record = read_marker(path)
    return record is not None and record.get("made_by") != "make_masks"


def scene_files(path):
    """The scene file ``path`` and the files it refers to (``<string value=...>`` and
    ``<include filename=...>`` naming an existing file, relative to the scene's folder)."""
    files = [path]
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return files
    folder = os.path.dirname(os.path.abspath(path))
    for el in root.iter():
        value = el.get("value") if el.tag == "string" else el.get("filename") if el.tag == "include" else None
        if value and os.path.isfile(os.path.join(folder, value)):
            files.append(os.path.normpath(os.path.join(folder, value)))
    return files


def run_files(run_dir):
    """The files of a run folder that tasks, renders and scores read, as inputs: its scene, the
    fields the scene refers to, and its settings."""
    scene = os.path.join(run_dir, "scene.xml")
    files = scene_files(scene) if os.path.isfile(scene) else []
    config = os.path.join(run_dir, "config.json")
    return [(p, "run's file") for p in files + ([config] if os.path.isfile(config) else [])]


@contextlib.contextmanager
def staged(out, resume=False, keep_checkpoints=False, inputs=(), restart=False, made_by="mi-voldis", job=None,
           may_change=()):
    """``with staged(OUT, resume) as stage:`` write everything into ``stage``; on leaving the block
    without an exception it replaces ``OUT``. Checked first (:func:`check_output` against the job's
    ``inputs``) and locked (:func:`locked`) while it runs. ``resume``: continue an existing
    ``OUT.partial`` staged for the same ``job`` (:func:`check_resume`, but for ``may_change``);
    ``restart``: discard a resumable one. A failed job leaves ``OUT`` as it was, and its
    ``OUT.partial`` only if it holds a checkpoint to resume from; a finished one drops its
    ``checkpoints/`` (what it made is written beside them) unless ``keep_checkpoints``. ``made_by``
    and ``job`` are recorded in :data:`MARKER`."""
    out = out.rstrip("/")
    check_output(out, inputs, resume, restart, program=made_by)
    stage = staging(out)
    with locked(out):
        check_output(out, inputs, resume, restart, program=made_by)  # again, now that no other job can change them
        if resume:
            check_resume(stage, job, may_change)
        elif os.path.isdir(stage):
            shutil.rmtree(stage)  # made by a job (checked above), and resumable only with restart
        os.makedirs(stage, exist_ok=True)
        write_marker(stage, made_by, job)
        try:
            yield stage
        except BaseException:
            if not _has_checkpoint(stage):
                shutil.rmtree(stage, ignore_errors=True)
            raise
        commit(stage, out, made_by)
        if not keep_checkpoints:
            shutil.rmtree(os.path.join(out, CHECKPOINTS), ignore_errors=True)


def _has_checkpoint(stage):
    return os.path.isdir(stage) and any(f.endswith(".npz") for _, _, files in os.walk(stage) for f in files)


def commit(stage, out, program="mi-voldis"):
    """Replace ``out`` (made by a job, or empty: :func:`check_output`) by the finished ``stage`` with
    renames only, first recording in the stage's :data:`MARKER` what the job leaves (:func:`foreign`).
    ``OUT.old`` is removed only when a job made it and holds nothing else."""
    old = _old(out)
    for folder in (old, out):
        if os.path.isdir(folder) and os.listdir(folder) and not made_here(folder):
            raise ValueError(f"{folder}: appeared while the job ran and was not written by mi-voldis; the result "
                             f"stays in {stage}")
        if os.path.isdir(folder) and foreign(folder):
            raise ValueError(f"{folder}: {', '.join(foreign(folder))} appeared in it while the job ran; the result "
                             f"stays in {stage}")
    record = read_marker(stage) or {"made_by": program, "job": None}
    write_json(os.path.join(stage, MARKER), {**record, "files": _entries(stage)})
    shutil.rmtree(old, ignore_errors=True)
    if os.path.exists(out):
        if read_marker(out) is None:  # an earlier version's output, or an empty folder: marked before it moves
            write_marker(out, program)
        os.replace(out, old)
    os.replace(stage, out)
    shutil.rmtree(old, ignore_errors=True)


class Checkpoint:
    """One file holding arrays and a JSON header, replaced atomically (a kill -9 leaves the previous one)."""

    def __init__(self, path):
        self.path = path

    def save(self, arrays, meta):
        os.makedirs(os.path.dirname(self.path), exist_ok=True)
        tmp = temp_beside(self.path, ".npz")
        np.savez(tmp, __meta__=np.frombuffer(json.dumps(meta).encode(), np.uint8), **arrays)
        os.replace(tmp, self.path)

    def load(self):
        if not os.path.isfile(self.path):
            return None
        with np.load(self.path) as f:
            meta = json.loads(bytes(f["__meta__"]).decode())
            arrays = {k: f[k] for k in f.files if k != "__meta__"}
        return arrays, meta


def temp_beside(path, suffix=""):
    """A new, unused name in ``path``'s folder for the temporary file a writer then renames to ``path``
    (hidden, random, ending in ``suffix`` so that writers that choose a format by extension keep it): no
    fixed name that could be a user's file."""
    folder, name = os.path.split(path)
    while True:
        tmp = os.path.join(folder, f".{name}.{secrets.token_hex(4)}.tmp{suffix}")
        if not os.path.lexists(tmp):
            return tmp


def write_json(path, data):
    """Write ``data`` as strict JSON via a temporary file (never half-written); NaN and infinities,
    which JSON cannot hold, become null."""
    tmp = temp_beside(path)
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
