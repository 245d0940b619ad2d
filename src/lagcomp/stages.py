"""Progress over the named stages of long work that reports nothing itself: derivation, CSE, numba.

A 50-link chain derives for about a minute in sympy, and numba compiles a
large model's kernels for as long; neither says anything meanwhile.
`Stages` follows the rule of the runs' progress bars
(`lagcomp.integrate.run_control.LazyProgress`): ``progress`` True shows it
from the start, False never, None (the default) once the work has lasted
`PROGRESS_DELAY` seconds.  The bar names the current stage and its elapsed
time moves while a stage runs (a background thread refreshes it once a second),
so a silent minute in sympy reads "deriving the equations (sympy) [00:41]".
"""

from __future__ import annotations

import threading

from lagcomp.integrate.run_control import PROGRESS_DELAY

#: Seconds between refreshes of a shown bar (its elapsed time) while a stage runs.
REFRESH_SECONDS = 1.0


class Stages:
    """A context manager: ``with Stages("compiling x", names) as stages: stages.start(names[0]); ...``."""

    def __init__(self, title: str, names: tuple[str, ...], progress=None):
        self.title, self.names, self.progress = title, tuple(names), progress
        self.done, self.current = 0, ""
        self.bar = None
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self._thread = None

    def __enter__(self):
        if self.progress is not False:
            self._thread = threading.Thread(target=self._watch, daemon=True, name="lagcomp-stages")
            self._thread.start()
        return self

    def _watch(self) -> None:
        """Open the bar after the delay (at once if ``progress`` is true), then keep its clock moving."""
        if self._stopped.wait(0.0 if self.progress else PROGRESS_DELAY):
            return
        with self._lock:
            if self._stopped.is_set():
                return
            from tqdm.auto import tqdm

            self.bar = tqdm(total=len(self.names), initial=self.done, desc=self.title, unit="stage", leave=False,
                            bar_format="{desc}: {n}/{total} [{elapsed}] {postfix}")
            self.bar.set_postfix_str(self.current)
        while not self._stopped.wait(REFRESH_SECONDS):
            with self._lock:
                if self.bar is not None:
                    self.bar.refresh()

    def start(self, name: str) -> None:
        """Mark the start of stage `name` (one of `names`): the stages before it are done."""
        with self._lock:
            self.done, self.current = self.names.index(name), name
            if self.bar is not None:
                self.bar.n = self.done
                self.bar.set_postfix_str(name)

    def __exit__(self, *exc):
        self._stopped.set()
        if self._thread is not None:
            self._thread.join()
        if self.bar is not None:
            self.bar.close()
        return False


def numba_stage(dispatcher, what: str, title: str, progress) -> Stages | None:
    """The `Stages` shown around the first call of `dispatcher` while numba compiles it (and `what` it
    calls), or None when it is compiled in this process already or progress is off.  A dispatcher numba
    loads from its disk cache takes well under the delay, so nothing shows then."""
    if progress is False or getattr(dispatcher, "signatures", None):
        return None
    return Stages(title, (f"numba: compiling {what} (once; cached for later runs)",), progress)
