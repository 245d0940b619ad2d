"""Timing, peers and the markdown table: what every section of `python -m bench` shares."""

from __future__ import annotations

import importlib
import statistics
import time
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Stat:
    """Median, min and max of repeated measurements (seconds, or any unit)."""

    median: float
    low: float
    high: float
    repeats: int

    def scaled(self, factor: float) -> "Stat":
        return Stat(self.median * factor, self.low * factor, self.high * factor, self.repeats)

    def ratio(self, base: "Stat") -> "Stat":
        """self / base: median over median, the range from the extremes of both."""
        return Stat(self.median / base.median, self.low / base.high, self.high / base.low, self.repeats)


def measure(run, repeats: int = 5, warmup: int = 1, per_call: int = 1) -> Stat:
    """Wall time of `run()` over `repeats` runs after `warmup` untimed ones, divided by `per_call`."""
    for _ in range(warmup):
        run()
    times = []
    for _ in range(max(repeats, 1)):
        start = time.perf_counter()
        run()
        times.append((time.perf_counter() - start) / per_call)
    return Stat(statistics.median(times), min(times), max(times), len(times))


def stat_of(values: list[float]) -> Stat:
    return Stat(statistics.median(values), min(values), max(values), len(values))


def no_events(method, n: int) -> tuple:
    """The event arguments of an embedded driver's call without events, as `lagcomp.integrate.simulate` passes
    them: directions and actions, the buffers of event times, states and indices, and for a driver that
    applies resets (``event_reset`` among `method`'s kernels) the states after them and which events are at
    their zero.  For the bench scripts that call a driver directly (bench_dop853, bench_call_cost)."""
    import numpy as np

    arguments = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.empty(1), np.empty((1, n)), np.empty(1, np.int64))
    if "event_reset" in method.kernels:
        arguments += (np.empty((1, n)), np.zeros(0, np.int64))
    return arguments


def peer(module: str):
    """The peer's module, or None when it is not installed (the table then says so)."""
    try:
        return importlib.import_module(module)
    except Exception:  # an ImportError, or a broken install of a compiled extension
        return None


SKIPPED = "skipped: not installed"


def fmt(value: float, unit: str = "") -> str:
    if value != value:  # nan
        return "–"
    if value == 0:
        return f"0{unit}"
    a = abs(value)
    if a >= 1e4 or a < 1e-3:
        text = f"{value:.2e}"
    elif a >= 100:
        text = f"{value:,.0f}"
    elif a >= 10:
        text = f"{value:.1f}"
    else:
        text = f"{value:.3g}"
    return f"{text}{unit}"


def fmt_stat(s: Stat, unit: str = "") -> str:
    if unit == "×":  # ratios: two decimals where they matter
        def r(x):
            return f"{x:.2f}" if x < 100 else fmt(x)
        return f"{r(s.median)}× ({r(s.low)}–{r(s.high)})"
    return f"{fmt(s.median, unit)} ({fmt(s.low)}–{fmt(s.high)})"


@dataclass
class Table:
    """One markdown table: a title, a note, column names and rows of strings."""

    title: str
    columns: list[str]
    note: str = ""
    rows: list[list[str]] = field(default_factory=list)

    def add(self, *cells) -> None:
        self.rows.append([str(c) for c in cells])

    def markdown(self) -> str:
        lines = [f"### {self.title}", ""]
        if self.note:
            lines += [self.note, ""]
        lines.append("| " + " | ".join(self.columns) + " |")
        lines.append("|" + "---|" * len(self.columns))
        lines += ["| " + " | ".join(r) + " |" for r in self.rows]
        return "\n".join(lines) + "\n"


@dataclass
class Target:
    """One of issue 8's targets: what it says, and whether this run met it."""

    name: str
    wanted: str
    measured: str = "not measured"
    met: bool | None = None
    verdict: str = ""  # overrides met/missed where one word would mislead (e.g. absolute vs relative)

    def row(self) -> list[str]:
        verdict = self.verdict or {True: "met", False: "missed",
                                   None: "not measured" if self.measured == "not measured" else "reported"}[self.met]
        return [self.name, self.wanted, self.measured, verdict]


def interleaved_times(runs: list, repeats: int = 5, warmup: int = 1, per_call: list | None = None) -> list[list[float]]:
    """Per-round times of `runs`, timed round-robin for `repeats` rounds after `warmup` untimed calls each.

    On a shared machine the load changes from second to second: timing the
    baseline and the others in alternation, and taking the median of the
    per-round ratios (`paired`), keeps a load spike from landing on one side only.
    """
    per_call = per_call or [1] * len(runs)
    for run in runs:
        for _ in range(warmup):
            run()
    times = [[] for _ in runs]
    for _ in range(max(repeats, 1)):
        for i, run in enumerate(runs):
            start = time.perf_counter()
            run()
            times[i].append((time.perf_counter() - start) / per_call[i])
    return times


def paired(a: list[float], b: list[float]) -> Stat:
    """Median (min–max) of the per-round ratios a_i / b_i."""
    return stat_of([x / y for x, y in zip(a, b)])


def interleaved(runs: list, repeats: int = 5, warmup: int = 1, per_call: list | None = None) -> tuple[list[Stat], list[Stat]]:
    """Each run's time Stat and its paired ratio Stat to runs[0] (see `interleaved_times`)."""
    times = interleaved_times(runs, repeats, warmup, per_call)
    return [stat_of(t) for t in times], [paired(t, times[0]) for t in times]
