"""Where the test suite's CPU goes: a pytest plugin that records it per test, and a report of it per file.

The machines the tests run on are shared, so wall times (``--durations``) are noisy; CPU time is not. With
this plugin (``-p tests.cpu_profile``, from the repository root) every process of the run, each xdist worker,
appends one JSON line per test to ``<DIR>/<worker>-<pid>.jsonl`` (DIR from ``$LAGCOMP_CPU_PROFILE``):

- ``cpu``: the test's CPU seconds in its process (`time.process_time`: setup, call, teardown; a module
  fixture's work counts in the first test that asks for it), ``child``: those of the subprocesses it waited for;
- ``numba``: the CPU seconds numba spent compiling (cache misses only), by the module of the compiled function:
  a generated module's name holds the model's name and key, so the same key in two workers or two tests is
  compiled twice; ``kernels``: the same for each kernel of a generated module (``module.function``), which the
  report's last list reads: a kernel compiled in two files or two workers is work done twice;
- ``builds``: lagcomp's derivations, lowerings and emissions (``lagcomp.runtime.build``, a tree's
  ``lagcomp.tree_model._build``, the companion's).

``python tests/cpu_profile.py DIR`` prints the totals, the files and the models by CPU::

    LAGCOMP_CPU_PROFILE=/tmp/prof nice -n 10 python -m pytest -p tests.cpu_profile
    python tests/cpu_profile.py /tmp/prof
"""

from __future__ import annotations

import collections
import glob
import json
import os
import re
import resource
import sys
import time

import pytest


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


class _Recorder:
    """numba's compile events and lagcomp's builds since the last `reset`."""

    def __init__(self):
        self.numba: dict[str, list] = {}
        self.kernels: dict[str, float] = {}
        self.builds: list = []
        self._depth, self._start = 0, 0.0

    def reset(self) -> None:
        self.numba, self.kernels, self.builds = {}, {}, []

    def compile_started(self) -> None:
        if self._depth == 0:
            self._start = time.process_time()
        self._depth += 1

    def compile_ended(self, dispatcher) -> None:
        self._depth -= 1
        if self._depth == 0:        # a nested compile (a callee) counts in its caller's
            module = getattr(dispatcher.py_func, "__module__", None) or "?"
            seconds = time.process_time() - self._start
            entry = self.numba.setdefault(module, [0.0, 0])
            entry[0] += seconds
            entry[1] += 1
            if module.startswith("lagcomp_generated_"):
                kernel = f"{module}.{dispatcher.py_func.__name__}"
                self.kernels[kernel] = self.kernels.get(kernel, 0.0) + seconds

    def timed(self, kind: str, function, name_of):
        """`function` wrapped to record its CPU seconds under (kind, name_of(args))."""
        def wrapper(*args, **kwargs):
            start = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                self.builds.append((kind, name_of(args), time.process_time() - start))
        return wrapper


_RECORDER = _Recorder()
_OUT = []


def _install() -> None:
    from numba.core import event

    import lagcomp.companion as companion
    import lagcomp.runtime as runtime
    import lagcomp.tree_model as tree_model

    class Listener(event.Listener):
        def on_start(self, ev):
            _RECORDER.compile_started()

        def on_end(self, ev):
            _RECORDER.compile_ended(ev.data["dispatcher"])

    event.register("numba:compile", Listener())
    runtime.build = _RECORDER.timed("eager", runtime.build, lambda args: getattr(args[0], "name", "?"))
    companion.build_companion = _RECORDER.timed("companion", companion.build_companion, lambda args: args[3])
    tree_model._build = _RECORDER.timed("tree", tree_model._build, lambda args: getattr(args[0], "name", "?"))


def pytest_configure(config):
    directory = os.environ.get("LAGCOMP_CPU_PROFILE")
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    if not directory or (worker == "main" and getattr(config.option, "numprocesses", None)):
        return      # (the controller of an xdist run runs no test)
    os.makedirs(directory, exist_ok=True)
    _install()
    _OUT.append(open(os.path.join(directory, f"{worker}-{os.getpid()}.jsonl"), "a", encoding="utf-8"))  # noqa: SIM115


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    if not _OUT:
        yield
        return
    _RECORDER.reset()
    cpu, child, wall = time.process_time(), _children_cpu(), time.perf_counter()
    yield
    record = {"id": item.nodeid, "file": item.nodeid.split("::")[0], "cpu": time.process_time() - cpu,
              "child": _children_cpu() - child, "wall": time.perf_counter() - wall,
              "numba": _RECORDER.numba, "kernels": _RECORDER.kernels, "builds": _RECORDER.builds,
              "worker": os.environ.get("PYTEST_XDIST_WORKER", "main")}
    _OUT[0].write(json.dumps(record) + "\n")
    _OUT[0].flush()


def report(directory: str, top: int = 25) -> None:
    """Print the run's CPU: totals, the `top` files, the `top` models by numba's compile time."""
    records = [json.loads(line) for path in glob.glob(os.path.join(directory, "*.jsonl"))
               for line in open(path, encoding="utf-8")]
    numba = sum(c for r in records for c, _ in r["numba"].values())
    print(f"{len(records)} tests: {sum(r['cpu'] for r in records):.0f} s CPU in the test processes, "
          f"{sum(r['child'] for r in records):.0f} s in their subprocesses; numba compiling {numba:.0f} s, "
          f"lagcomp building {sum(b[2] for r in records for b in r['builds']):.0f} s")
    files = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0])
    for r in records:
        row = files[r["file"]]
        row[0] += r["cpu"]
        row[1] += r["child"]
        row[2] += sum(c for c, _ in r["numba"].values())
        row[3] += 1
    print(f"\n{'file':44s} {'cpu':>6s} {'child':>6s} {'numba':>6s} {'tests':>5s}")
    for name, (cpu, child, compiling, n) in sorted(files.items(), key=lambda kv: -(kv[1][0] + kv[1][1]))[:top]:
        print(f"{name:44s} {cpu:6.0f} {child:6.0f} {compiling:6.0f} {n:5d}")
    models = collections.defaultdict(lambda: [0.0, set(), set()])
    for r in records:
        for module, (seconds, _) in r["numba"].items():
            match = _GENERATED.match(module)
            if match:
                row = models[match.group(1)]
                row[0] += seconds
                row[1].add(match.group(3))
                row[2].add(r["file"].rsplit("/", 1)[-1])
    print(f"\n{len(models)} models compiled, {sum(m[0] for m in models.values()):.0f} s; the slowest:")
    for name, (seconds, keys, names) in sorted(models.items(), key=lambda kv: -kv[1][0])[:top]:
        print(f"  {name:40s} {seconds:6.1f} s  {len(keys)} module(s)  {', '.join(sorted(names)[:4])}")
    compiled_again(records, top)
    heaviest(files)


def heaviest(files: dict, threshold: float = 15.0) -> None:
    """Print the files of more than `threshold` CPU seconds (their processes' and subprocesses'), heaviest first,
    as `tests/suite_order.HEAVIEST` lists them."""
    rows = sorted(((cpu + child, name.rsplit("/", 1)[-1]) for name, (cpu, child, _, _) in files.items()
                   if cpu + child > threshold), reverse=True)
    print(f"\nsuite_order.HEAVIEST (files over {threshold:.0f} s):")
    for seconds, name in rows:
        quoted = f'"{name}",'
        print(f"    {quoted:40s} # {seconds:.0f}")


#: A generated module's name: the model's name, the on-demand kind of a companion module, the key.
_GENERATED = re.compile(r"lagcomp_generated_(.*?)(?:_on_demand_([a-z_]+?))?_([0-9a-f]{16})$")


def compiled_again(records: list, top: int) -> None:
    """Print the kernels of generated modules that numba compiled in more than one test file or worker (the same
    module, so the same key: the second compile is work a shared fixture or the shared cache would have saved),
    the `top` most costly, with the seconds after the first file's.  (Records without ``kernels``, from before it
    was recorded, count whole modules: two files may have compiled different kernels of one module.)"""
    where = collections.defaultdict(lambda: collections.defaultdict(float))
    for r in records:
        compiles = r.get("kernels") or {module: seconds for module, (seconds, _) in r["numba"].items()}
        for kernel, seconds in compiles.items():
            if _GENERATED.match(kernel.split(".")[0]):
                where[kernel][(r["worker"], r["file"].rsplit("/", 1)[-1])] += seconds
    again = {kernel: places for kernel, places in where.items() if len(places) > 1}
    extra = {kernel: sum(places.values()) - max(places.values()) for kernel, places in again.items()}
    print(f"\n{len(again)} generated kernels compiled in more than one file or worker, {sum(extra.values()):.0f} s "
          "after the first:")
    for kernel in sorted(again, key=lambda k: -extra[k])[:top]:
        files = ", ".join(f"{file} ({worker})" for worker, file in sorted(again[kernel])[:4])
        print(f"  {kernel[len('lagcomp_generated_'):]:70s} {extra[kernel]:6.1f} s  {files}")


if __name__ == "__main__":
    report(sys.argv[1], *(int(arg) for arg in sys.argv[2:3]))
