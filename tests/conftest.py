"""Shared fixtures: one cache directory per test run, compiled models shared across tests.

numba compilation dominates the test time, so every model is compiled once
per session (and its numba machine code is cached in the per-run directory).
"""

from __future__ import annotations

import gc
import warnings

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import examples


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("lagcomp-cache")


@pytest.fixture(scope="session")
def compiled(cache_dir):
    """`compiled(name, **factory_kwargs)` -> Model, compiled once per session."""
    models = {}

    def get(name: str, **kwargs) -> lc.Model:
        key = (name, tuple(sorted(kwargs.items())))
        if key not in models:
            models[key] = lc.compile(examples.get(name, **kwargs), cache_dir=cache_dir)
        return models[key]

    return get


@pytest.fixture(scope="session")
def whipple_bicycle(cache_dir):
    """sympy's test_kane3 bicycle: (its KanesMethod, the model `lc.compile(km)` makes of it), built once."""
    import kane_models

    km, values, _ = kane_models.bicycle()
    return km, lc.compile(km, cache_dir=cache_dir, name="whipple_bicycle", defaults=values)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def animations_freed_quietly():
    """Collect the test's animations when it ends, without matplotlib's warning that they were never run
    (the tests draw frames by hand, `MechanismAnimation.draw`, rather than running the animation)."""
    yield
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Animation was deleted without rendering anything")
        gc.collect()
