"""The `inputs` a user passes to a run, keyed by name (what `lagcomp.integrate.inputs` packs into p and
`lagcomp.integrate.function_inputs` wraps the kernels for both read)."""

from __future__ import annotations

from collections.abc import Mapping

from lagcomp.errors import OptionError


def inputs_by_name(inputs: Mapping) -> dict:
    """`inputs` keyed by name: an input u(t) itself (`lagcomp.Input`) stands for its name, as a Symbol does
    for a parameter's in `params`."""
    named = {}
    for key, value in inputs.items():
        function = getattr(key, "func", None)
        name = function.__name__ if getattr(function, "lagcomp_input", False) else key
        if not isinstance(name, str):
            raise OptionError(f"`inputs` keys must be input names (or the inputs themselves), got {key!r}.")
        if name in named:
            raise OptionError(f"`inputs` gives input `{name}` twice (by name and as the input).")
        named[name] = value
    return named
