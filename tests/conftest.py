"""Shared fixtures: one cache directory per test run, compiled models shared across tests.

numba compilation dominates the test time, so every model is compiled once
per session (and its numba machine code is cached in the per-run directory,
which pytest-xdist's workers share).
"""

from __future__ import annotations

import gc
import os
import warnings

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import examples


def pytest_collection_modifyitems(items):
    """The heaviest files first, so that xdist's workers finish together (tests/suite_order.py)."""
    import suite_order

    suite_order.order(items)


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    """The run's cache directory.  Under pytest-xdist (the default: ``-n auto`` in pyproject.toml) one directory
    for all workers, in the run's shared temporary root, so that a model one worker compiled the others load
    (the cache is safe for processes compiling at once: tests/test_cache_faults.py)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = tmp_path_factory.getbasetemp().parent / "lagcomp-cache"
        shared.mkdir(exist_ok=True)
        return shared
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
def tree_pair(cache_dir):
    """`tree_pair(name)` -> (the model of the tree `multibody_models.PAIRS[name]`, the model of the same system on
    the Lagrangian path, `multibody_models.lagrangian_system`), compiled once per session."""
    import multibody_models

    pairs = {}

    def get(name: str) -> tuple[lc.Model, lc.Model]:
        if name not in pairs:
            tree = multibody_models.PAIRS[name]()
            pairs[name] = (lc.compile(tree, cache_dir=cache_dir),
                           lc.compile(multibody_models.lagrangian_system(tree), cache_dir=cache_dir))
        return pairs[name]

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
