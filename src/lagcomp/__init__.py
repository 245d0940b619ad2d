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
    Damper as Damper,
    Event as Event,
    Force as Force,
    Gravity as Gravity,
    Holonomic as Holonomic,
    MovingFrame as MovingFrame,
    Nonholonomic as Nonholonomic,
    Particle as Particle,
    RigidBody as RigidBody,
    Spring as Spring,
    System as System,
    Torque as Torque,
    body_rates as body_rates,
    coordinates as coordinates,
    from_kanes_method as from_kanes_method,
    from_lagranges_method as from_lagranges_method,
    rotated as rotated,
    t as t,
)
from lagcomp.runtime import Model as Model, compile as compile  # noqa: A004
