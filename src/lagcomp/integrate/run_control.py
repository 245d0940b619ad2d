"""Run control shared by long runs, sweeps and analyses: Ctrl-C between compiled calls, progress bars."""

from __future__ import annotations

import _signal
import signal
import threading
import time
from contextlib import contextmanager

#: Runs longer than this (seconds) show a progress bar (unless ``progress=False``).
PROGRESS_DELAY = 2.0
#: Ctrl-C's signal number, as `_signal.signal` takes it.
SIGINT = int(signal.SIGINT)


@contextmanager
def deferred_interrupt():
    """Within the block, Ctrl-C sets ``flag[0]`` instead of raising, so no chunk is half-recorded.

    (numba code does not see signals anyway; this also covers the Python
    bookkeeping between calls.)  Only the main thread can install handlers;
    elsewhere Ctrl-C keeps its usual meaning.
    """
    flag = [False]
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def handler(signum, frame):
        flag[0] = True
    # `_signal.signal` is what `signal.signal` calls after converting its arguments and result to enums
    # (5 µs of a pair of calls, 4% of a short run's fixed cost); the handlers are the same either way.
    previous = _signal.signal(SIGINT, handler)
    try:
        yield flag
    finally:
        _signal.signal(SIGINT, previous)


class LazyProgress:
    """A tqdm progress bar that is only made once it is worth showing.

    ``progress`` true: shown from the start; False: never; None (the default): made at the first
    update after `PROGRESS_DELAY` seconds.  A tqdm object costs about 0.2 ms to make and close,
    4% of a 5 ms DOP853 run, so short runs make none.  The interface is tqdm's, as far as the
    callers use it: a context manager with ``n`` and ``update(amount)``; `options` go to tqdm.
    """

    def __init__(self, total: float, progress, **options):
        self.total, self.progress, self.options, self.n = total, progress, options, 0
        self.started = time.perf_counter()
        self.bar = None
        if progress:
            self._open()

    def _open(self):
        from tqdm.auto import tqdm

        self.bar = tqdm(total=self.total, initial=self.n, leave=False, mininterval=0.5, **self.options)

    def update(self, amount) -> None:
        self.n += amount
        if self.bar is not None:
            self.bar.update(amount)
        elif self.progress is not False and time.perf_counter() - self.started > PROGRESS_DELAY:
            self._open()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False


def progress_bar(t0: float, t1: float, progress) -> LazyProgress:
    """The progress bar of a run over [t0, t1], in units of t."""
    return LazyProgress(t1 - t0, progress, unit="t", unit_scale=True,
                        bar_format="{l_bar}{bar}| t = {n:.4g}/{total:.4g} [{elapsed}<{remaining}]")
