"""A run's parameters, initial state and input signals, from a file (``--config``) and from flags.

``--config run.toml`` (or ``run.json``) holds any of::

    t_start = 0.0                 # seconds (the model's units)
    t_end = 10.0
    q0 = [0.0, 3.1]               # one per coordinate, in the model's order
    qd0 = [0.0, 0.0]              # one per coordinate (u0: one per speed of a Kane model)
    [params]
    m = 1.0
    [inputs]
    F = "push.csv"                # a table: columns time,value
    G = "drive.csv:force"         # the column `force` against the column `time` (or `t`)
    H = 2.5                       # a constant

Flags given as well win: ``--param K=V`` over ``[params]``, ``--input`` over ``[inputs]``, ``--q0`` over
``q0`` and so on.  A table named in the file is found relative to the file's folder.  TOML is read
with the standard library's ``tomllib`` (Python ≥ 3.11; on 3.10 with ``tomli`` if installed, else use
JSON).

``--input NAME=SPEC`` gives one input signal (`lagcomp.Input` without a law): ``NAME=2.5`` a constant,
``NAME=push.csv`` a table whose two columns are time and value (a header row is optional),
``NAME=table.csv:force`` the column ``force`` of a table with a header, against its column ``time``
(or ``t``), ``NAME=controller.py:pd`` a numba function ``pd(t, y, p) -> float`` defined in that file
(`lagcomp.integrate.function_inputs`).  A table is interpolated by a cubic spline (`lagcomp.Tabulated`); end the spec with
``@linear`` for straight segments between the samples (``NAME=push.csv@linear``).
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lagcomp.cli_support.models import key_values
from lagcomp.errors import LagcompError

#: The keys a ``--config`` file may hold.
CONFIG_KEYS = ("params", "inputs", "q0", "qd0", "u0", "t_start", "t_end")
#: The names a table's time column may have.
TIME_COLUMNS = ("time", "t")


@dataclass
class RunValues:
    """What a command runs from: parameter values, initial state, input signals and time span (None: the
    model's own)."""

    params: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    q0: list | None = None
    qd0: list | None = None
    u0: list | None = None
    t_start: float | None = None
    t_end: float | None = None


def run_values(args, *, params_flag: str | None = "param") -> RunValues:
    """The values of `args.config` overridden by the flags `args` carries (``--param``, ``--input``, ``--q0``,
    ``--qd0``, ``--u0``, ``--t-start``, ``--t-end``); `params_flag` names the flag of fixed parameter values."""
    values = read_config(args.config) if getattr(args, "config", None) else RunValues()
    if params_flag is not None:
        values.params.update(key_values(getattr(args, params_flag, None), f"--{params_flag}"))
    for spec in getattr(args, "input", None) or []:
        name, signal = parse_input(spec, Path.cwd())
        values.inputs[name] = signal
    for key in ("q0", "qd0", "u0", "t_start", "t_end"):
        flag = getattr(args, key, None)
        if flag is not None:
            setattr(values, key, flag)
    return values


def read_config(path: str) -> RunValues:
    """A ``--config`` file (.toml or .json) as `RunValues`; a wrong file is a message naming it and the key."""
    file = Path(path)
    if not file.is_file():
        raise LagcompError(f"--config {path}: no such file.")
    data = _parse(file)
    if not isinstance(data, dict):
        raise LagcompError(f"--config {path}: expected a table of keys ({', '.join(CONFIG_KEYS)}), "
                           f"got a {type(data).__name__}.")
    unknown = sorted(set(data) - set(CONFIG_KEYS))
    if unknown:
        raise LagcompError(f"--config {path}: unknown key(s) {unknown}; the keys are {', '.join(CONFIG_KEYS)}.")
    values = RunValues()
    for key in ("params", "inputs"):
        table = data.get(key, {})
        if not isinstance(table, dict):
            raise LagcompError(f"--config {path}: `{key}` must be a table of name = value, got {table!r}.")
        if key == "params":
            values.params = {name: _number(value, f"--config {path}: params.{name}") for name, value in table.items()}
        else:
            values.inputs = {name: _signal(name, value, file.parent, f"--config {path}: inputs.{name}")
                             for name, value in table.items()}
    for key in ("q0", "qd0", "u0"):
        if key in data:
            entries = data[key] if isinstance(data[key], list) else [data[key]]
            setattr(values, key, [_number(v, f"--config {path}: {key}") for v in entries])
    for key in ("t_start", "t_end"):
        if key in data:
            setattr(values, key, _number(data[key], f"--config {path}: {key}"))
    return values


def _parse(file: Path):
    suffix = file.suffix.lower()
    if suffix == ".json":
        try:
            return json.loads(file.read_text(encoding="utf-8"))
        except ValueError as err:
            raise LagcompError(f"--config {file}: not valid JSON ({err}).") from err
    if suffix == ".toml":
        try:
            import tomllib
        except ImportError:  # Python 3.10
            try:
                import tomli as tomllib
            except ImportError as err:
                raise LagcompError(f"--config {file}: reading TOML on Python 3.10 needs tomli (pip install tomli); "
                                   "or write the file as JSON.") from err
        try:
            return tomllib.loads(file.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as err:
            raise LagcompError(f"--config {file}: not valid TOML ({err}).") from err
    raise LagcompError(f"--config {file}: the suffix names the format: .toml or .json.")


def _number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LagcompError(f"{what} must be a number, got {value!r}.")
    return float(value)


def _signal(name: str, value, folder: Path, what: str):
    if isinstance(value, str):
        return parse_input(f"{name}={value}", folder)[1]
    return _number(value, what)


def parse_input(spec: str, folder: Path) -> tuple[str, object]:
    """``NAME=2.5``, ``NAME=file.csv[:COLUMN][@linear]`` as (name, a number or a `lagcomp.Tabulated`); a
    relative file is found in `folder`."""
    name, sep, value = spec.partition("=")
    if not sep or not name or not value:
        raise LagcompError(f"--input {spec!r} must look like NAME=2.5, NAME=table.csv or NAME=table.csv:COLUMN.")
    try:
        return name, float(value)
    except ValueError:
        pass
    value, _, kind = value.partition("@")
    if kind not in ("", "cubic", "linear"):
        raise LagcompError(f"--input {spec!r}: @{kind}: the interpolation is @cubic (the default) or @linear.")
    file, column = value, ""
    if ":" in Path(value).name:  # a column after the file's name (not a drive letter)
        file, column = value.rsplit(":", 1)
    if file.endswith(".py"):
        return name, _function(folder / Path(file).expanduser(), column, spec)
    times, values = read_table(folder / Path(file).expanduser(), column or None, f"--input {name}")
    from lagcomp.integrate.inputs import Tabulated

    return name, Tabulated(times, values, kind=kind or "cubic", name=name)


def _function(path: Path, attribute: str, spec: str):
    """The numba function ``u(t, y, p) -> float`` named `attribute` in the file `path`."""
    from lagcomp.cli_support.models import import_file

    if not attribute:
        raise LagcompError(f"--input {spec!r}: name the function in the file: NAME=file.py:FUNCTION.")
    module = import_file(path, str(path))
    function = getattr(module, attribute, None)
    if function is None or not callable(function):
        raise LagcompError(f"--input {spec!r}: {path} defines no function {attribute!r}.")
    return function


def read_table(path: Path, column: str | None, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(times, values) of a CSV table: its two columns, or `column` against its time column."""
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = [[cell.strip() for cell in row] for row in csv.reader(handle) if any(c.strip() for c in row)]
    except OSError as err:
        raise LagcompError(f"{what}: cannot read {path} ({err.strerror or err}).") from err
    if not rows:
        raise LagcompError(f"{what}: {path} is empty.")
    header = None if _all_numbers(rows[0]) else rows[0]
    body = rows[1:] if header else rows
    if header is None and column is not None:
        raise LagcompError(f"{what}: {path} has no header row, so no column {column!r}; name its columns "
                           "in a first row (time,value,...).")
    if header is None or column is None:
        if len(header or rows[0]) != 2:
            raise LagcompError(f"{what}: {path} has {len(header or rows[0])} columns; give two (time,value) or "
                               f"name the column: {path}:COLUMN.")
        picked = (0, 1)
    else:
        times = [i for i, h in enumerate(header) if h.lower() in TIME_COLUMNS]
        if column not in header or not times:
            missing = repr(column) if column not in header else "time (or t)"
            raise LagcompError(f"{what}: {path} has no column {missing}; its columns: {', '.join(header)}.")
        picked = (times[0], header.index(column))
    table = np.empty((len(body), 2))
    for row_number, row in enumerate(body, start=2 if header else 1):
        try:
            table[row_number - (2 if header else 1)] = [float(row[i]) for i in picked]
        except (ValueError, IndexError):
            raise LagcompError(f"{what}: {path}, line {row_number}: {','.join(row)!r} is not a row of numbers.") \
                from None
    return table[:, 0], table[:, 1]


def _all_numbers(row: list[str]) -> bool:
    try:
        [float(cell) for cell in row]
    except ValueError:
        return False
    return True


def check_inputs(model, inputs: dict) -> None:
    """Refuse, before any run, input signals the model does not read or lacks (names the flag to give)."""
    needed = tuple(getattr(model, "inputs", ()))
    unknown = sorted(set(inputs) - set(needed))
    if unknown:
        raise LagcompError(f"--input {', '.join(unknown)}: {model.name!r} reads "
                           f"{'the inputs ' + ', '.join(needed) if needed else 'no inputs'}.")
    missing = [name for name in needed if name not in inputs]
    if missing:
        raise LagcompError(f"{model.name!r} reads the input(s) {', '.join(missing)} at run time: give each as "
                           f"--input {missing[0]}=table.csv (columns time,value), --input {missing[0]}=2.5 "
                           "(a constant), --input NAME=table.csv:COLUMN, or in --config's [inputs].")
