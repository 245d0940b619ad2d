"""Writing a run or a sweep to the file the user named, in the format its suffix names.

The suffix decides the format, and an unknown suffix is refused before any work (never a file
written under another name): ``.npz`` (numpy, every array: `Solution.save_npz`, `Sweep.save_npz`),
``.csv`` (one row per saved time of a run, or per trajectory of a sweep, with a header naming the
columns; numbers written with 17 significant digits, so they read back bit for bit) and ``.nc``
(netCDF through xarray: `Solution.to_xarray`, `Sweep.to_xarray`; needs the ``xarray`` extra).
Plots go to any image format matplotlib writes, named by the suffix as well.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from lagcomp.errors import LagcompError

#: Result formats by suffix.
RESULT_SUFFIXES = (".npz", ".csv", ".nc")


def check_writable(path: str | None, what: str) -> None:
    """Refuse an output path that cannot be written, before any work whose results it would hold."""
    if path is None:
        return
    target = Path(path)
    if target.is_dir():
        raise LagcompError(f"{what} {path} is a directory; give a file name.")
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise LagcompError(f"{what} {path}: the directory {folder} does not exist; create it first.")
    if not os.access(folder, os.W_OK) or (target.exists() and not os.access(target, os.W_OK)):
        raise LagcompError(f"{what} {path} cannot be written (permission denied).")


def check_result_path(path: str | None, what: str = "--out") -> None:
    """Refuse a result file whose suffix names no format lagcomp writes, or that cannot be written."""
    if path is None:
        return
    check_writable(path, what)
    suffix = Path(path).suffix.lower()
    if suffix not in RESULT_SUFFIXES:
        raise LagcompError(f"{what} {path}: the suffix names the format; use .npz (numpy), .csv (a table) or "
                           ".nc (netCDF, needs xarray).")
    if suffix == ".nc":
        import importlib.util

        if importlib.util.find_spec("xarray") is None:
            raise LagcompError(f"{what} {path}: netCDF is written through xarray: pip install 'lagcomp[xarray]', "
                               "or save to .npz or .csv.")


def check_plot_path(path: str | None, what: str = "--plot") -> None:
    """Refuse a plot file before the run: no matplotlib, or a suffix that is no image format it writes."""
    if path is None:
        return
    check_writable(path, what)
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:  # known before the run, not after it
        raise LagcompError(f"{what} needs matplotlib: pip install 'lagcomp[plots]'.")
    from matplotlib.backend_bases import FigureCanvasBase

    formats = sorted(FigureCanvasBase.get_supported_filetypes())
    if Path(path).suffix.lower().lstrip(".") not in formats:
        raise LagcompError(f"{what} {path}: the suffix names the image format; use one matplotlib writes: "
                           f"{', '.join('.' + f for f in formats)} (e.g. {Path(path).stem}.png).")


def _write_table(path: Path, header: list[str], columns: list[np.ndarray]) -> None:
    table = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    np.savetxt(path, table, delimiter=",", header=",".join(header), comments="", fmt="%.17g")


def solution_columns(sol) -> tuple[list[str], list[np.ndarray]]:
    """The CSV columns of a run: t, the state (`Solution.state_names`), energy, energy_function, reactions."""
    header, columns = ["t", *sol.state_names], [sol.t, *sol.y.T]
    header += ["energy", "energy_function"]
    columns += [sol.energy, sol.energy_function]
    for name, values in sol.reactions.items():
        header.append(f"reaction_{name}")
        columns.append(values)
    return header, columns


def write_solution(sol, path: str) -> Path:
    """Write `sol` to `path` in the format its suffix names; the path written."""
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix == ".npz":
        with target.open("wb") as handle:  # a file object: numpy appends no suffix of its own
            np.savez_compressed(handle, **sol.to_dict())
    elif suffix == ".csv":
        _write_table(target, *solution_columns(sol))
    else:
        sol.to_xarray().to_netcdf(target)
    return target


def sweep_columns(sweep) -> tuple[list[str], list[np.ndarray]]:
    """The CSV columns of a sweep, one row per trajectory: the swept values, status, t_final, the final state,
    and the largest energy error when the sweep kept it."""
    if sweep.combine == "product":
        grids = np.meshgrid(*(sweep.axes[name] for name in sweep.names), indexing="ij")
        swept = [grid.ravel() for grid in grids]
    else:
        swept = [np.asarray(sweep.axes[name]).ravel() for name in sweep.names]
    state = list(sweep.coordinates) + (list(sweep.speeds) or [f"{c}_dot" for c in sweep.coordinates])
    final = sweep.final.reshape(-1, sweep.final.shape[-1])
    header = [*sweep.names, "status", "t_final", *(f"final_{name}" for name in state)]
    columns = [*swept, sweep.status.ravel(), sweep.t_final.ravel(), *final.T]
    if sweep.energy_error is not None:
        header.append("energy_error")
        columns.append(sweep.energy_error.ravel())
    return header, columns


def write_sweep(sweep, path: str) -> Path:
    """Write `sweep` to `path` in the format its suffix names; the path written."""
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix == ".npz":
        with target.open("wb") as handle:
            np.savez_compressed(handle, **sweep.to_numpy())
    elif suffix == ".csv":
        _write_table(target, *sweep_columns(sweep))
    else:
        sweep.to_xarray().to_netcdf(target)
    return target
