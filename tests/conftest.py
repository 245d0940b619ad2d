"""Shared fixtures: one cache directory per test run, compiled models shared across tests.

numba compilation dominates the test time, so every model is compiled once
per session (and its numba machine code is cached in the per-run directory).
"""

from __future__ import annotations

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


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
