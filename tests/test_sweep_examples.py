"""The sweep scripts in examples/ on small grids, against what physics says of them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _script(name: str):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_flip_map_never_flips_where_energy_forbids_it(cache_dir):
    script = _script("double_pendulum_flip")
    sweep, flip_time, forbidden = script.flip_map(side=16, t_end=5.0, cache_dir=cache_dir)
    flipped = np.isfinite(flip_time)
    assert forbidden.any() and not (flipped & forbidden).any()
    assert flipped[~forbidden].mean() > 0.3  # most high-energy starts flip within 5 s
    # a flip stops the run at the event: the flipping rod is at ±π there
    theta = sweep.final[..., :2]
    at_top = np.isclose(np.abs(theta), np.pi, rtol=0, atol=1e-9).any(axis=-1)
    np.testing.assert_array_equal(at_top, flipped)


def test_kapitza_map_follows_the_high_frequency_boundary(cache_dir):
    script = _script("kapitza_map")
    sweep, stable, predicted = script.stability_map(side=8, t_end=5.0, cache_dir=cache_dir)
    assert stable.any() and not stable.all()
    A, W = np.meshgrid(sweep.axes["A"], sweep.axes["Omega"], indexing="ij")
    margin = np.abs(A * W / np.sqrt(2 * script.G * script.L) - 1) > 0.15  # away from the boundary
    np.testing.assert_array_equal(stable[margin], predicted[margin])

