"""Run control shared by long runs, sweeps and analyses: Ctrl-C between compiled calls, progress bars."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

#: Runs longer than this (seconds) show a progress bar (unless ``progress=False``).
PROGRESS_DELAY = 2.0


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
    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)


class _NoProgress:
    """What `progress_bar` returns for ``progress=False``: the bar's interface, doing nothing (a tqdm
    object costs about 60 µs to make, a tenth of a short run's fixed cost)."""

    n = 0

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def update(self, amount):
        pass


def progress_bar(t0: float, t1: float, progress):
    if progress is False:
        return _NoProgress()
    from tqdm.auto import tqdm

    return tqdm(total=t1 - t0, unit="t", unit_scale=True, leave=False, disable=progress is False, mininterval=0.5,
                delay=0.0 if progress else PROGRESS_DELAY, bar_format="{l_bar}{bar}| t = {n:.4g}/{total:.4g} [{elapsed}<{remaining}]")
