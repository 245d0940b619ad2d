"""The absolute tolerance ``atol`` of a run: one number, or one per state component in that component's units.

A position and a velocity have different units (metres and metres per second, radians and radians per
second), so no single absolute tolerance means the same in every unit system: change the unit of time and
the velocities' sizes change while the positions' do not.  `simulate` and `sweep` therefore take ``atol`` as

* a number: the same bound for every component (the drivers' historic behaviour, bit for bit);
* an array of the state's length 2n, ordered as ``model.state_names`` (the coordinates q, then their
  velocities q̇; `Solution.y`'s columns): ``atol[i]`` in the units of component i;
* a mapping ``{coordinate: (atol of q, atol of q̇)}`` with every coordinate of the model, each pair in the
  coordinate's unit and that unit per time unit.

The drivers take the array form always (`driver_atol`): a component's error is measured against
``atol_i + rtol |y_i|`` (the embedded pairs, Radau's differential components, the DOP853 lanes) or, for the
Taylor method, in the max norm weighted by 1/atol_i (`lagcomp.integrate.drivers.taylor`).  One number is
spread over the array, which gives the same bits as a scalar would.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from lagcomp.errors import OptionError


def absolute_tolerance(atol, state_names) -> float | np.ndarray:
    """`atol` checked against a model whose state is labelled `state_names` (q's names, then ``<q>_dot``).

    Returns a float for a number and a read-only float64 array (2n,) otherwise; raises `OptionError` naming
    ``atol`` for a wrong length, a missing or unknown coordinate, or an entry that is not positive and finite.
    """
    if isinstance(atol, Mapping):
        atol = _from_mapping(atol, state_names)
    elif np.ndim(atol) == 0:
        return _positive_number(atol)
    try:
        values = np.array(atol, dtype=float)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`atol` must be a number or an array of numbers, got {atol!r}.") from err
    if any(isinstance(a, (bool, np.bool_)) for a in np.ravel(np.asarray(atol, dtype=object))):
        raise OptionError(f"`atol` must hold numbers, got {atol!r}.")
    size = len(state_names)
    if values.shape != (size,):
        raise OptionError(f"`atol` has shape {values.shape}; one per state component needs ({size},), ordered as "
                          f"the state {list(state_names)} (or pass one number, or {{coordinate: (atol of q, "
                          "atol of q̇)}}).")
    bad = np.flatnonzero(~(np.isfinite(values) & (values > 0)))
    if bad.size:
        i = int(bad[0])
        raise OptionError(f"`atol` must be positive and finite in every component; `atol[{i}]` "
                          f"({state_names[i]}) is {values[i]}.")
    values.flags.writeable = False
    return values


def _positive_number(atol) -> float:
    if isinstance(atol, (bool, np.bool_)):
        raise OptionError(f"`atol` must be a number, got {atol!r}.")
    return positive(atol, "atol")


def positive(value, name: str) -> float:
    """`value` as a float, refused (OptionError naming `name`) unless it is a positive finite number."""
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`{name}` must be a number, got {value!r}.") from err
    if not (value > 0 and math.isfinite(value)):
        raise OptionError(f"`{name}` must be positive and finite, got {value}.")
    return value


def _from_mapping(atol: Mapping, state_names) -> list:
    """The array form of ``{coordinate: (atol of q, atol of q̇)}``: every coordinate once, a pair each."""
    coordinates = list(state_names[:len(state_names) // 2])
    if list(state_names[len(coordinates):]) != [f"{c}_dot" for c in coordinates]:
        raise OptionError(f"`atol` as a mapping {{coordinate: (atol of q, atol of q̇)}} needs a state (q, q̇); this "
                          f"model's is {list(state_names)}: pass one atol per state component in that order.")
    keys = [getattr(key, "name", key) if not isinstance(key, str) else key for key in atol]
    unknown = [key for key in keys if key not in coordinates]
    missing = [c for c in coordinates if c not in keys]
    if unknown or missing:
        raise OptionError(f"`atol` as a mapping needs every coordinate {coordinates} once, with the pair (atol of q, "
                          f"atol of q̇); unknown: {unknown}, missing: {missing}.")
    pairs = dict(zip(keys, atol.values(), strict=True))
    for name, pair in pairs.items():
        if np.ndim(pair) != 1 or len(pair) != 2:
            raise OptionError(f"`atol[{name!r}]` must be a pair (atol of {name}, atol of {name}_dot), in {name}'s "
                              f"unit and that unit per time unit; got {pair!r}.")
    return [pairs[c][0] for c in coordinates] + [pairs[c][1] for c in coordinates]


def driver_atol(atol, size: int) -> np.ndarray:
    """The (size,) float64 array a driver takes for a run's checked `atol` (`absolute_tolerance`).

    One number fills it.  An array of the state's 2n entries is repeated over a longer driver state: a
    sensitivity run's columns S_ij = ∂y_i/∂w_j each get atol_i, the row's (their layout is N entries per column,
    `lagcomp.integrate.sensitivities.initial_state`); a DAE's algebraic components get entries Radau does not
    read (it scales them from the differential ones: `lagcomp.integrate.drivers.radau._algebraic_scales`).
    """
    if np.ndim(atol) == 0:
        return np.full(size, float(atol))
    return np.resize(np.asarray(atol, dtype=float), size)


def smallest(atol) -> float:
    """The smallest entry of a checked `atol` (the number itself for one number)."""
    return float(np.min(atol))


def uniform(atol) -> float | None:
    """The one value of a checked `atol` when all its entries are equal, else None."""
    if np.ndim(atol) == 0:
        return float(atol)
    values = np.asarray(atol)
    return float(values[0]) if values.size and bool(np.all(values == values[0])) else None
