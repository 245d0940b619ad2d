"""Input signals supplied at run time: checked, interpolated, and packed into the parameter vector.

``model.simulate(..., inputs={"x_s": signal})`` takes, per input of the model
(`lagcomp.Input` without a law), one of

* ``Tabulated(times, values, kind="cubic" | "linear")``: samples of the signal,
  interpolated by `scipy.interpolate.CubicSpline` (not-a-knot ends) or
  piecewise linearly;
* a pair ``(times, values)``: the same as ``Tabulated(times, values)`` (cubic);
* a scipy piecewise polynomial of degree ≤ 3 (``CubicSpline``, ``PchipInterpolator``,
  ``Akima1DInterpolator``, ``PPoly``): used as it is;
* a number: a constant signal;
* a numba function ``u(t, y, p) -> float`` of the time, the state and the
  parameters (a controller): `lagcomp.integrate.function_inputs`.

`pack_inputs` writes them after the parameters in the layout the kernels read
(`lagcomp.kernel_support.inputs`).  A table is data: changing it never recompiles.
A function packs as a one-piece constant table whose constant (NaN until then)
the run writes before each kernel call.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from lagcomp.errors import OptionError
from lagcomp.integrate import function_inputs
from lagcomp.integrate.input_names import inputs_by_name

#: The interpolants a `Tabulated` signal may use.
KINDS = ("cubic", "linear")


class Tabulated:
    """A signal sampled at increasing `times`, interpolated by `kind` ("cubic" or "linear").

    Parameters
    ----------
    times : array_like, shape (m + 1,)
        Strictly increasing, finite sample times, at least two.
    values : array_like, shape (m + 1,)
        The signal at `times`, finite.
    kind : {"cubic", "linear"}
        "cubic": `scipy.interpolate.CubicSpline` with not-a-knot ends (u, u̇, ü continuous;
        error O(Δ⁴) in u, O(Δ²) in ü for samples Δ apart of a smooth signal); "linear": the
        piecewise-linear interpolant (continuous u, u̇ piecewise constant, ü zero: refused for
        an input whose second derivative enters the equations).
    name : str, optional
        The input the table is for, named in error messages (`pack_inputs` gives it).

    Attributes
    ----------
    breakpoints : ndarray, shape (m + 1,)
    coefficients : ndarray, shape (4, m)
        Row k multiplies (t − x_i)^(3 − k) on piece i (scipy's ``PPoly.c``).
    """

    def __init__(self, times, values, kind: str = "cubic", name: str | None = None):
        what = "lagcomp.Tabulated" if name is None else f"Input `{name}`"  # (`name`: the input being supplied)
        if kind not in KINDS:
            raise OptionError(f"{what}: `kind` must be one of {KINDS}, got {kind!r}.")
        x, y = _samples(times, "times", what), _samples(values, "values", what)
        if x.size != y.size:
            raise OptionError(f"{what}: {x.size} times but {y.size} values; give one value per time.")
        if x.size < 2:
            raise OptionError(f"{what}: a table needs at least two samples, got {x.size}.")
        if not np.all(np.diff(x) > 0):
            i = int(np.argmin(np.diff(x) > 0))
            raise OptionError(f"{what}: times must be strictly increasing; times[{i}] = {x[i]} is followed "
                              f"by {x[i + 1]}.")
        self.kind, self.breakpoints = kind, x
        if kind == "cubic":
            from scipy.interpolate import CubicSpline

            self.coefficients = np.ascontiguousarray(CubicSpline(x, y).c)
        else:
            slopes = np.diff(y) / np.diff(x)
            self.coefficients = np.vstack([np.zeros_like(slopes), np.zeros_like(slopes), slopes, y[:-1]])

    def __repr__(self) -> str:
        x = self.breakpoints
        return f"Tabulated({x.size} samples on [{x[0]}, {x[-1]}], kind={self.kind!r})"


def _samples(values, field: str, what: str) -> np.ndarray:
    """`values` as a finite 1-D float array, or an OptionError naming `what` (the table) and the `field`."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise OptionError(f"{what}: `{field}` must be numbers, got {values!r}.") from err
    if array.ndim != 1:
        raise OptionError(f"{what}: `{field}` must be one-dimensional, got shape {array.shape}.")
    if not np.all(np.isfinite(array)):
        raise OptionError(f"{what}: `{field}` holds non-finite values (NaN or inf) at "
                          f"{np.flatnonzero(~np.isfinite(array))[:5].tolist()}.")
    return array


def _signal(value, name: str) -> tuple[np.ndarray, np.ndarray, str]:
    """(breakpoints, coefficients (4, m), kind) of one supplied signal; kind "constant" for a number."""
    if isinstance(value, Tabulated):
        return value.breakpoints, value.coefficients, value.kind
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise OptionError(f"Input `{name}` is the constant {value}; it must be finite.")
        return np.array([0.0, 1.0]), np.array([[0.0], [0.0], [0.0], [float(value)]]), "constant"
    if hasattr(value, "c") and hasattr(value, "x") and hasattr(value, "extrapolate"):  # a scipy PPoly
        c = np.asarray(value.c, dtype=float)
        if c.ndim != 2 or c.shape[0] > 4:
            raise OptionError(f"Input `{name}`: a piecewise polynomial must be scalar and of degree ≤ 3, got "
                              f"coefficients of shape {c.shape}.")
        table = Tabulated(value.x, np.zeros(len(value.x)), "linear", name)  # checks the breakpoints
        return table.breakpoints, np.vstack([np.zeros((4 - c.shape[0], c.shape[1])), c]), "cubic"
    if isinstance(value, tuple) and len(value) == 2:
        table = Tabulated(*value, name=name)
        return table.breakpoints, table.coefficients, table.kind
    raise OptionError(f"Input `{name}` must be lagcomp.Tabulated(times, values, kind), a pair (times, values), "
                      f"a scipy CubicSpline / PPoly, a number or a numba function {function_inputs.SIGNATURE_TEXT}, "
                      f"got {type(value).__name__}.")


def pack_inputs(names, orders, inputs, span, first: int) -> np.ndarray:
    """The headers and tables of the model's inputs, to append to p (`lagcomp.kernel_support.inputs`).

    Parameters
    ----------
    names, orders : tuple
        The model's inputs in header order and the highest derivative of each its kernels read.
    inputs : mapping of str to signal, or None
        What the user supplied (module docstring).
    span : (float, float) or None
        The run's start and end times, which every table must cover; None skips the check
        (evaluating a kernel at one time, `Model.rhs`).
    first : int
        Where the headers start in p (the length of p before them).
    """
    if inputs is None:
        inputs = {}
    if not isinstance(inputs, Mapping):
        raise OptionError(f"`inputs` must be a mapping of input name to signal, like {{{names[0]!r}: (times, values)}}"
                          f", got {type(inputs).__name__}.")
    inputs = inputs_by_name(inputs)
    unknown = sorted(set(inputs) - set(names), key=str)
    if unknown:
        raise OptionError(f"Unknown input(s) {unknown}; the model's inputs are {list(names)}.")
    missing = [name for name in names if name not in inputs]
    if missing:
        raise OptionError(f"Missing input(s) {missing}: pass `inputs={{name: lagcomp.Tabulated(times, values)}}` "
                          "(or a pair (times, values), a number, or a numba function) for every input of the model.")
    headers, tables = np.empty(len(names)), []
    start = first + len(names)
    for j, (name, order) in enumerate(zip(names, orders, strict=True)):
        if function_inputs.is_function(inputs[name]):  # a constant the run writes (NaN: read unwrapped, it shows)
            function_inputs.check(inputs[name], name, order)
            x, c, kind = np.array([0.0, 1.0]), np.array([[0.0], [0.0], [0.0], [math.nan]]), "function"
        else:
            x, c, kind = _signal(inputs[name], name)
        if kind == "linear" and order >= 2:
            raise OptionError(f"Input `{name}` enters the equations through its second derivative, which a linear "
                              "table has not (it would be zero between samples and infinite at them): use "
                              "kind=\"cubic\".")
        if kind not in ("constant", "function") and span is not None:
            lo, hi = min(span), max(span)
            if x[0] > lo or x[-1] < hi:
                raise OptionError(f"Input `{name}`'s table covers [{x[0]}, {x[-1]}], not the run's time span "
                                  f"[{lo}, {hi}]: extend the table.")
        table = np.concatenate([[x.size - 1], x, c.T.ravel()])
        headers[j] = start
        tables.append(table)
        start += table.size
    return np.concatenate([headers, *tables])
