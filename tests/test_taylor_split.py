"""A large Taylor program emitted as chunks of numba functions (`lagcomp.codegen.taylor_split`, issues 35 and 39).

The split must change nothing but the compile time: the same operations in the same order on the same rows of X
and W, with the same fastmath flags, so its coefficients are bitwise the unsplit function's (checked here on programs
forced to split by a small threshold, with pivot tests and explicit time), and a tree too large for one function
(a 6-link planar chain, refused before the split) gets its coefficients right against the tree's equations in
40 digits (`lagcomp.accuracy.tree_reference`) and runs with ``method="taylor"``.
"""

from __future__ import annotations

import importlib.util

import multibody_models as mm
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.codegen.lower import lower
from lagcomp.codegen.taylor import decompose, emit_taylor, taylor_program
from lagcomp.codegen.taylor_ops import support_import_lines
from lagcomp.codegen.taylor_split import (
    CHUNK_OPERATIONS,
    SPLIT_OPERATIONS,
    counted,
    split_body,
)
from lagcomp.codegen.tree_locals import tree_locals
from lagcomp.codegen.tree_taylor import tree_taylor_decomposition
from lagcomp.examples import get
from lagcomp.mechanics.lagrange import derive

ORDER = 24


@pytest.fixture(scope="module")
def programs():
    """Taylor programs of Systems below the split threshold: pivot tests of M's LDLᵀ (a 3-link pendulum) and
    explicit time (a driven pendulum)."""
    return {name: decompose(ir.kernel("rhs"), ir.n)
            for name, ir in ((name, lower(derive(get(name)))) for name in ("n_link_pendulum", "driven_pendulum"))}


def _module(tmp_path, name: str, program, **split):
    """`program` emitted (``emit_taylor`` with `split`) as the module `name` in `tmp_path`, imported."""
    path = tmp_path / f"{name}.py"
    head = "import math\n\nimport numpy as np\nfrom numba import njit\n\n"
    path.write_text(head + support_import_lines(taylor_program(program), lanes=False) + emit_taylor(program, **split))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _coefficients(module, n_state: int, t: float, y, p) -> np.ndarray:
    X, W = np.empty((n_state, ORDER + 1)), np.empty((module.TAYLOR_WORK, ORDER + 1))
    assert module.taylor_coefficients(t, np.asarray(y, dtype=float), p, X, W) == 0
    return X


@settings(max_examples=40, deadline=None)
@given(chunk=st.integers(1, 40), name=st.sampled_from(["n_link_pendulum", "driven_pendulum"]))
def test_chunks_cover_the_program_in_order(programs, chunk, name):
    """The chunks are the program's operations in order, each of `chunk` series operations or more up to twice that
    (the last may hold fewer), cut before a statement of rhs unless one is longer than that."""
    body = programs[name].body
    chunks = split_body(body, chunk)
    assert [op for part in chunks for op in part] == body
    sizes = [sum(map(counted, part)) for part in chunks]
    assert all(chunk <= size <= 2 * chunk for size in sizes[:-1]) and 0 < sizes[-1] <= 2 * chunk
    assert all(part[0].kind == "comment" or sizes[i - 1] == 2 * chunk for i, part in enumerate(chunks) if i)


def test_small_programs_are_one_function(programs):
    """Below the threshold the program is one function (every bundled example's source unchanged: the generated
    modules' check); above, chunk functions that taylor_coefficients calls in order."""
    program = programs["n_link_pendulum"]
    assert program.operation_count <= SPLIT_OPERATIONS
    assert "_taylor_coefficients_part" not in emit_taylor(program)
    source = emit_taylor(program, split_operations=10, chunk_operations=8)
    calls = [f"_taylor_coefficients_part{i}(" for i in range(len(split_body(program.body, 8)))]
    assert all(source.count(f"def {call}") == 1 for call in calls)
    loop = source[source.index("def taylor_coefficients("):]
    assert [loop.index(call) for call in calls] == sorted(loop.index(call) for call in calls)


def _assert_bitwise(tmp_path, name: str, program, chunk: int, rng, parameters: int = 16) -> None:
    """`program` forced to split into chunks of `chunk` operations: coefficients to order 24 bitwise the unsplit
    function's at 5 random states, parameters and times."""
    whole = _module(tmp_path, f"{name}_whole", program, split_operations=program.operation_count)
    split = _module(tmp_path, f"{name}_split", program, split_operations=1, chunk_operations=chunk)
    parts = len(split_body(program.body, chunk))
    assert parts > 1 and f"_taylor_coefficients_part{parts - 1}" in vars(split)
    assert "_taylor_coefficients_part0" not in vars(whole)
    for _ in range(5):
        y = rng.uniform(-1.5, 1.5, program.n_state)
        p = rng.uniform(0.5, 2.0, parameters)
        t = rng.uniform(0.0, 3.0)
        got = _coefficients(split, program.n_state, t, y, p)
        want = _coefficients(whole, program.n_state, t, y, p)
        assert np.array_equal(got, want)


@pytest.mark.parametrize(("name", "chunk"), [("n_link_pendulum", 48), ("driven_pendulum", 4)])
def test_a_split_program_is_bitwise_the_unsplit_one(programs, tmp_path, name, chunk, rng):
    """Forced to split, the coefficients are bitwise the unsplit function's (time too: the driven pendulum's rhs
    depends on it; M's pivot tests: the pendulum's).  (Bitwise holds for the code numba's LLVM makes of these cuts:
    `fastmath={"contract"}` lets LLVM fuse a product into a sum where both land in one basic block, which depends on
    the code around; cut into chunks of 8 to 32, the 3-link pendulum's W differs in its last bit at a few orders.)"""
    _assert_bitwise(tmp_path, name, programs[name], chunk, rng)


@pytest.mark.slow     # (numba compiles the program twice: about 50 s of CPU)
def test_a_four_link_chain_split_is_bitwise_the_unsplit_one(tmp_path, rng):
    """The 4-link planar chain (298 operations per order, the largest the old bound took) in the chunks it gets by
    default (`CHUNK_OPERATIONS`) against one function."""
    chain = mm.planar_chain(4)
    _assert_bitwise(tmp_path, "chain4", tree_taylor_decomposition(chain, tree_locals(chain)), CHUNK_OPERATIONS, rng,
                    parameters=len(chain.parameter_names) + 4)


def test_a_long_chain_has_a_program_in_chunks():
    """A 10-link planar chain (934 series operations per order: one function took numba 399 s and 4.5 GB, and trees
    were refused above 500) has a program, emitted as chunks of at most twice `CHUNK_OPERATIONS` operations."""
    chain = mm.planar_chain(10)
    program = tree_taylor_decomposition(chain, tree_locals(chain))
    assert program.operation_count == 934
    chunks = split_body(program.body)
    assert max(sum(map(counted, part)) for part in chunks) <= 2 * CHUNK_OPERATIONS
    source = emit_taylor(program)
    assert all(f"def _taylor_coefficients_part{i}(k, X, W" in source for i in range(len(chunks)))


@pytest.mark.slow     # (numba compiles the 6-link chain's rhs and Taylor chunks: about a minute of CPU)
def test_a_six_link_chain_has_the_reference_series(cache_dir):
    """The 6-link chain's coefficients of orders 1 to 10 against the tree's q̈ in 40 digits along the series
    (`test_multibody_taylor._reference_coefficients`, 1e-12 normwise per order as there), and a Taylor run against
    dop853 at tight tolerance."""
    from test_multibody_taylor import _coefficients as coefficients
    from test_multibody_taylor import _reference_coefficients, _relative_by_order

    chain = mm.planar_chain(6)
    model = lc.compile(chain, cache_dir=cache_dir)
    params = {name: 0.4 + 0.1 * i for i, name in enumerate(chain.parameter_names)} | {"g": 9.81}
    y = np.array([0.3, -0.2, 0.5, 0.1, -0.4, 0.2, 0.5, -0.3, 0.2, 0.4, -0.1, 0.3])
    X = coefficients(model, 0.0, y, model.parameter_vector(params))
    want = _reference_coefficients(model, params, chain, 0.0, X, orders=10)
    got = X[6:, 1:11] * np.arange(1, 11)
    assert np.all(_relative_by_order(got, want) <= 1e-12)
    run = {"params": params, "q0": y[:6], "qd0": y[6:], "rtol": 1e-13, "atol": 1e-13, "progress": False}
    taylor, dop853 = model.simulate((0.0, 1.0), method="taylor", **run), model.simulate((0.0, 1.0), **run)
    assert np.max(np.abs(taylor.y[-1] - dop853.y[-1])) <= 1e-9


@pytest.mark.slow     # (numba compiles the model, its Taylor chunks, the variational and the lane kernels: minutes)
def test_a_split_model_runs_sensitivities_and_batched_sweeps(tmp_path, monkeypatch):
    """A System compiled with its Taylor program forced to split: the variational kernels (sensitivities) and the
    batched sweep's lane kernels, written from the stored program and not from ``taylor_coefficients``, still
    agree with dop853 at tight tolerance."""
    import sympy as sp

    from lagcomp.codegen import taylor_split
    from lagcomp.model import t

    monkeypatch.setattr(taylor_split, "SPLIT_OPERATIONS", 10)
    monkeypatch.setattr(taylor_split, "CHUNK_OPERATIONS", 12)
    x, z = lc.coordinates("x z")
    a, c = sp.symbols("a c", positive=True)
    T = ((c + sp.cos(z)) * x.diff(t) ** 2 + z.diff(t) ** 2 + x.diff(t) * z.diff(t) * sp.sin(z)) / 2
    system = lc.System([x, z], T=T, V=a * sp.exp(x / 3) + sp.sqrt(1 + z**2), name="taylor_split_twin",
                       defaults={"a": 1.0, "c": 2.0}, q0=(0.3, -0.2), qd0=(0.1, 0.4))
    model = lc.compile(system, cache_dir=tmp_path)
    assert hasattr(model.kernels, "taylor_coefficients") and model.operations["taylor_coefficients"] > 10
    assert hasattr(model.kernels.companion.module("taylor", "taylor_coefficients"), "_taylor_coefficients_part1")
    run = {"rtol": 1e-12, "atol": 1e-12, "progress": False, "sensitivities": ("q0", "qd0")}
    taylor, dop853 = model.simulate((0.0, 3.0), method="taylor", **run), model.simulate((0.0, 3.0), **run)
    assert np.max(np.abs(taylor.sensitivities[-1] - dop853.sensitivities[-1])) <= 1e-8
    grid = {"a": [0.8, 1.0], "c": [2.0, 2.5]}
    lanes = model.sweep((0.0, 3.0), grid, method="taylor", batched=True, rtol=1e-12, atol=1e-12)
    want = np.asarray(model.sweep((0.0, 3.0), grid, method="dop853", rtol=1e-12, atol=1e-12).final)
    assert np.all(lanes.status == 0)
    assert np.max(np.abs(np.asarray(lanes.final) - want)) <= 1e-9 * np.max(np.abs(want))
