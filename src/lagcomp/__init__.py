"""lagcomp: compile Lagrangian mechanical systems into cached numba kernels, and simulate them.

    import lagcomp as lc
    th, = lc.coordinates("theta")
    system = lc.System([th], T=..., V=..., name="pendulum")
    model = lc.compile(system)            # derive, emit, cache, load
    sol = model.simulate((0, 10), q0=[1.0], params=dict(...))
    model = lc.load("pendulum")           # a later process: from the cache, no sympy
"""

__version__ = "0.1.0"

from lagcomp.animation import animate as animate
from lagcomp.errors import (
    CacheWarning as CacheWarning,
    CorruptCacheRecordError as CorruptCacheRecordError,
    InitialConditionError as InitialConditionError,
    IntegrationError as IntegrationError,
    LagcompError as LagcompError,
    LinearizationError as LinearizationError,
    ModelError as ModelError,
    OptionError as OptionError,
    ParameterError as ParameterError,
    ResetWarning as ResetWarning,
    SingularMassMatrixError as SingularMassMatrixError,
    StiffnessWarning as StiffnessWarning,
    UndeclaredSymbolError as UndeclaredSymbolError,
    UnknownEventError as UnknownEventError,
)
from lagcomp.integrate.inputs import Tabulated as Tabulated
from lagcomp.integrate.solution import Solution as Solution
from lagcomp.integrate.sweep import Sweep as Sweep
from lagcomp.runtime import Model as Model, compile as compile, load as load  # noqa: A004

#: The public names: `from lagcomp import *`, and what the API reference documents
#: (tests/test_docs_reference.py checks both).
__all__ = [
    "animate", "compile", "load", "Model", "Solution", "Sweep", "Tabulated", "kernel_accuracy",
    "Contact", "Damper", "Event", "Force", "Friction", "Gravity", "Holonomic", "Input", "MovingFrame", "Nonholonomic",
    "Particle", "RigidBody", "Spring", "System", "Torque", "body_rates", "coordinates", "from_kanes_method",
    "from_lagranges_method", "rotated", "t",
    "Tree", "Link", "Loop", "Revolute", "Prismatic", "Universal", "Cylindrical", "Planar", "Spherical", "Free",
    "from_urdf",
    "LagcompError", "ModelError", "UndeclaredSymbolError", "ParameterError", "OptionError", "InitialConditionError",
    "SingularMassMatrixError", "IntegrationError", "LinearizationError", "CorruptCacheRecordError", "CacheWarning",
    "StiffnessWarning", "ResetWarning", "UnknownEventError",
]

#: What `lagcomp.model` contributes to the namespace.  It is imported on first
#: use (PEP 562), because it imports sympy: a process that only runs a cached
#: model (`lagcomp.load`) starts without sympy's ~0.5 s import.
_MODEL_NAMES = (
    "Contact", "Damper", "Event", "Force", "Friction", "Gravity", "Holonomic", "Input", "MovingFrame", "Nonholonomic",
    "Particle", "RigidBody", "Spring", "System", "Torque", "body_rates", "coordinates", "from_kanes_method",
    "from_lagranges_method", "rotated", "t",
)


#: What `lagcomp.multibody` contributes (kinematic trees), imported on first use too (sympy).
_MULTIBODY_NAMES = ("Tree", "Link", "Loop", "Revolute", "Prismatic", "Universal", "Cylindrical", "Planar", "Spherical",
                    "Free")


#: Robots from URDF files (`lagcomp.multibody.urdf`), imported on first use too (sympy; yourdfpy when called).
_URDF_NAMES = ("from_urdf",)


#: Imported on first use too (sympy, mpmath): the kernel-accuracy check of `lagcomp.accuracy`.
_ACCURACY_NAMES = ("kernel_accuracy",)


#: Subpackages reachable as attributes (``lc.analysis.linearize(...)``) without an import of their own, imported
#: on first use (they import scipy, sympy or matplotlib).
_SUBMODULES = ("analysis", "plots")


def __getattr__(name: str):
    if name in _ACCURACY_NAMES:
        from lagcomp import accuracy

        globals()[name] = value = getattr(accuracy, name)
        return value
    if name in _MULTIBODY_NAMES:
        from lagcomp import multibody

        globals()[name] = value = getattr(multibody, name)
        return value
    if name in _SUBMODULES:
        import importlib

        globals()[name] = value = importlib.import_module(f"lagcomp.{name}")
        return value
    if name in _URDF_NAMES:
        from lagcomp.multibody import urdf

        globals()[name] = value = getattr(urdf, name)
        return value
    if name in _MODEL_NAMES:
        from lagcomp import model

        value = getattr(model, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'lagcomp' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MODEL_NAMES) | set(_MULTIBODY_NAMES) | set(_URDF_NAMES) | set(_ACCURACY_NAMES)
                  | set(_SUBMODULES))
