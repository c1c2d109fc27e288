"""Progress of long jobs: a bar on a terminal, and plain lines in a log.

tqdm draws a bar when stderr is a terminal; when it is not (a batch job, ``2> log``), a bar's
carriage returns make an unreadable log, so :class:`Progress` writes a line every
:data:`LOG_SECONDS` seconds and one at the end instead: ``desc: k/n (p%) 12 s  loss=0.01``.
"""
import sys
import time

from tqdm import tqdm

LOG_SECONDS = 30.0


class Progress:
    """``update(n)``, ``set_postfix(dict)``, ``close()``; ``total`` may change while it runs.
    ``enabled`` False: silent."""

    def __init__(self, total, desc, enabled=True, stream=None):
        self.stream = stream or sys.stderr
        self.total, self.desc, self.count, self.postfix = total, desc, 0, {}
        self.enabled = enabled
        self.bar = None
        if enabled and self.stream.isatty():
            self.bar = tqdm(total=total, desc=desc, dynamic_ncols=True, leave=False, mininterval=0.5, file=self.stream)
        self.t0 = self.last = time.perf_counter()

    def update(self, n=1):
        self.count += n
        if self.bar is not None:
            self.bar.total = self.total
            self.bar.update(n)
        elif self.enabled and time.perf_counter() - self.last >= LOG_SECONDS:
            self._line()

    def set_postfix(self, values):
        self.postfix = dict(values)
        if self.bar is not None:
            self.bar.set_postfix(self.postfix)

    def close(self):
        if self.bar is not None:
            self.bar.close()
        elif self.enabled and self.count:
            self._line()

    def _line(self):
        self.last = time.perf_counter()
        share = f" ({100 * self.count / self.total:.0f}%)" if self.total else ""
        extra = "".join(f"  {k}={v}" for k, v in self.postfix.items())
        print(f"{self.desc}: {self.count}/{self.total}{share} {self.last - self.t0:.0f} s{extra}", file=self.stream,
              flush=True)


def progress_iter(items, desc, enabled=True):
    """``items`` with a :class:`Progress` over them."""
    items = list(items)
    p = Progress(len(items), desc, enabled)
    for item in items:
        yield item
        p.update(1)
    p.close()
