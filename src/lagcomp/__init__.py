"""lagcomp: compile Lagrangian mechanical systems into cached numba kernels, and simulate them.

    import lagcomp as lc
    th, = lc.coordinates("theta")
    system = lc.System([th], T=..., V=..., name="pendulum")
    model = lc.compile(system)            # derive, emit, cache, load
    sol = model.simulate((0, 10), q0=[1.0], params=dict(...))
"""

__version__ = "0.1.0"

from lagcomp.errors import (
    CacheWarning as CacheWarning,
    InitialConditionError as InitialConditionError,
    IntegrationError as IntegrationError,
    LagcompError as LagcompError,
    ModelError as ModelError,
    OptionError as OptionError,
    ParameterError as ParameterError,
    SingularMassMatrixError as SingularMassMatrixError,
    UndeclaredSymbolError as UndeclaredSymbolError,
)
from lagcomp.integrate.solution import Solution as Solution
from lagcomp.model import (
    Holonomic as Holonomic,
    Nonholonomic as Nonholonomic,
    System as System,
    coordinates as coordinates,
    t as t,
)
from lagcomp.runtime import Model as Model, compile as compile  # noqa: A004
