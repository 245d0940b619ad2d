"""The files results are written to and read from: checks that answer with a `LagcompError` naming the path."""

from __future__ import annotations

import os
from pathlib import Path

from lagcomp.errors import OptionError


def output_path(path, what: str) -> Path:
    """`path` as a Path, after checking that its directory exists (`what` names the call in the message).

    numpy's savez would otherwise fail inside zipfile with a bare FileNotFoundError, after the work.
    """
    try:
        target = Path(os.fspath(path)).expanduser()
    except TypeError as err:
        raise OptionError(f"{what}: the path must be a str or pathlib.Path, got {path!r}.") from err
    folder = target.parent
    if not folder.is_dir():
        raise OptionError(f"{what}: cannot write {target}: the directory {folder} does not exist (create it "
                          "first, or give another path).")
    return target
