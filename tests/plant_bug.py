"""Plant one bug in lagcomp's source, run the tests that should notice it, and put the source back.

Usage (from the repository root; docs/testing.md says when and why)::

    python tests/plant_bug.py src/lagcomp/kernel_support/impacts.py \\
        "abs(p_t) > static * p_n" "abs(p_t) > kinetic * p_n" -- tests/test_contact_friction.py -k oblique

The change is a plain text replacement that must match exactly once.  The file is restored in a ``finally``
block (also on Ctrl-C), byte for byte, with its modification time, so numba's cache stamp of the restored file
is the original one.  The tests run in a subprocess with ``-n 0 -x`` added and the pytest arguments after
``--``.  The exit code is 0 when the tests FAILED with the bug planted (they notice it), 1 when they passed (the
bug survives), 2 on a usage error.  ``--fresh-numba-cache`` runs the tests with an empty ``NUMBA_CACHE_DIR``
(slower: everything compiles) for code that lagcomp's own cache refresh does not cover.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path


def plant(path: Path, old: str, new: str, pytest_args: list[str], fresh_numba_cache: bool = False) -> bool:
    """Replace `old` by `new` in `path` (exactly one occurrence), run pytest with `pytest_args`, restore the file.

    Returns whether the tests failed with the bug planted; raises ValueError if `old` does not occur exactly once.
    """
    original = path.read_bytes()
    stat = path.stat()
    text = original.decode("utf-8")
    if text.count(old) != 1:
        raise ValueError(f"{old!r} occurs {text.count(old)} times in {path}, not once.")
    env = dict(os.environ)
    with tempfile.TemporaryDirectory(prefix="planted-numba-") as numba_cache:
        if fresh_numba_cache:
            env["NUMBA_CACHE_DIR"] = numba_cache
        try:
            path.write_bytes(text.replace(old, new).encode("utf-8"))
            run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-x", "-p", "no:cacheprovider",
                                  *pytest_args], env=env)
        finally:
            path.write_bytes(original)
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    return run.returncode not in (0, 5)  # 5: no test collected, which notices nothing


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file", type=Path, help="the source file to plant the bug in")
    parser.add_argument("old", help="the exact text to replace (must occur once)")
    parser.add_argument("new", help="the text that replaces it: the bug")
    parser.add_argument("--fresh-numba-cache", action="store_true", help="run with an empty NUMBA_CACHE_DIR")
    parser.add_argument("pytest_args", nargs=argparse.REMAINDER, help="-- then the tests that should notice it")
    args = parser.parse_args(argv)
    pytest_args = args.pytest_args[1:] if args.pytest_args[:1] == ["--"] else args.pytest_args
    if not pytest_args:
        parser.error("name the tests that should notice the bug after `--`.")
    try:
        noticed = plant(args.file, args.old, args.new, pytest_args, args.fresh_numba_cache)
    except ValueError as err:
        parser.error(str(err))
    print(f"\nplanted in {args.file}: {args.old!r} -> {args.new!r}: "
          + ("NOTICED (the tests failed)" if noticed else "SURVIVED (the tests passed)"))
    return 0 if noticed else 1


if __name__ == "__main__":
    sys.exit(main())
