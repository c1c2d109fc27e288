"""Limits known before the work: the memory a job will take and Dr.Jit's entries per array.

A render, a dataset or an export that cannot fit is refused before it starts, in one line giving the
estimate, instead of failing (or swapping) after minutes of work. Standard library only.
"""
GIB = 1 << 30
MAX_ENTRIES = 1 << 32  # Dr.Jit indexes an array with 32-bit integers (and Mitsuba its sample wavefront)


def available_memory(meminfo="/proc/meminfo"):
    """Bytes the kernel says a new job can take without swapping (``MemAvailable``); None where the
    system does not say (not Linux): then nothing is refused."""
    try:
        with open(meminfo) as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def gib(n):
    """``n`` bytes in GiB, one decimal."""
    return f"{n / GIB:.1f}"


def check_memory(what, bytes_needed):
    """Refuse a job needing more than the memory available: ``ValueError`` "<what> needs about N GiB
    (M GiB available)". ``what`` names the flag or file and the job, e.g. "--res: a 30000x30000 dataset"."""
    available = available_memory()
    if available is not None and bytes_needed > available:
        raise ValueError(f"{what} needs about {gib(bytes_needed)} GiB ({gib(available)} GiB available)")


def check_entries(what, entries):
    """Refuse a job whose largest array would hold ``entries`` values, at or above Dr.Jit's 2^32."""
    if entries >= MAX_ENTRIES:
        raise ValueError(f"{what} needs {entries:,} entries in one array, more than Dr.Jit's 2^32 "
                         f"({MAX_ENTRIES:,})")
