"""Bundled example systems, ready to compile and run.

Each factory returns a `lagcomp.model.System` with parameter defaults,
initial conditions and a run length.  Look them up by name with `get` or
through the `EXAMPLES` registry:

==================================  ========================================================
``simple_pendulum``                 point mass on a massless rod
``double_pendulum``                 two point masses on two massless rods
``n_link_pendulum``                 planar chain of n point masses (name ``n_link_pendulum_<n>``)
``sling``                           bead on a rod turning at a constant rate in a horizontal plane
``rope``                            rope slipping off a frictionless table edge
``rope_friction``                   the same rope with Coulomb friction on the table
``hoop_bead``                       bead on a hoop turned about its vertical diameter by φ(t)
``huygens``                         Huygens' isochronous cycloidal pendulum
``tray_cylinder``                   cylinder rolling without slipping on a tray moved along a(t)
``unbalanced_cylinder``             rolling cylinder whose centre of mass is off its axis
``driven_pendulum``                 pendulum on a vertically vibrated support (Kapitza)
``henon_heiles``                    star in a galactic potential; events for its Poincaré section
``stiff_spring_pendulum``           pendulum on a stiff damped spring (k/m = 10⁶): a stiff problem
``hoop_bead_reaction``              the hoop bead with φ released: the hoop's normal push as λ
``unbalanced_cylinder_reactions``   the unbalanced cylinder with F_v and F_h from released constraints
``free_axle``                       axle with two independent wheels on an incline (3 multipliers)
``rolling_disc``                    thin disc rolling without slipping on a plane (nonholonomic, 3D)
``chaplygin_sleigh``                rigid body on a knife edge (nonholonomic)
``spherical_pendulum_cartesian``    bob on a rod in Cartesian coordinates: λ gives the rod tension
``spherical_pendulum``              the same pendulum in spherical angles
``four_bar_linkage``                crank, coupler and rocker closing a loop (2 holonomic constraints): λ is a pin force
``turn_indicator``                  gyroscope in a gimbal of a banked, turning aircraft (moving frame, rigid body)
``compton_disc``                    disc on a turning carousel at latitude λ, axis swung over (moving frame)
``driven_pendulum_support``         ``driven_pendulum`` written in the support's frame (driving inertial force)
``symmetric_top``                   heavy symmetric top in Euler angles (rigid body, gravity)
``wheel_jack``                      crank, screw and lozenge holding a load: statics by virtual work
``pythagorean_three_body``          Burrau's three bodies (masses 3, 4, 5) from rest: close approaches
``restricted_three_body``           circular restricted three-body problem, rotating frame (Arenstorf orbit)
==================================  ========================================================

The factories live in `unconstrained`, `constrained`, `bodies` (systems
built from Particle / RigidBody, loads and moving frames) and `gravitation`; each docstring states
the coordinates, conventions, Lagrangian, equations and any closed form.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from lagcomp.errors import ModelError
from lagcomp.examples.bodies import BODIES_EXAMPLES
from lagcomp.examples.constrained import CONSTRAINED_EXAMPLES
from lagcomp.examples.gravitation import GRAVITATION_EXAMPLES
from lagcomp.examples.unconstrained import (
    double_pendulum,
    driven_pendulum,
    henon_heiles,
    hoop_bead,
    huygens,
    n_link_pendulum,
    rope,
    rope_friction,
    simple_pendulum,
    sling,
    stiff_spring_pendulum,
    tray_cylinder,
    unbalanced_cylinder,
)
from lagcomp.model import System

__all__ = ["EXAMPLES", "get"]

#: Every bundled example by name; each factory takes only optional keyword arguments.
EXAMPLES: dict[str, Callable[..., System]] = {
    f.__name__: f
    for f in (
        simple_pendulum, double_pendulum, n_link_pendulum, sling, rope, rope_friction,
        hoop_bead, huygens, tray_cylinder, unbalanced_cylinder, driven_pendulum, henon_heiles,
        stiff_spring_pendulum,
    )
}
EXAMPLES.update(CONSTRAINED_EXAMPLES)
EXAMPLES.update(BODIES_EXAMPLES)
EXAMPLES.update(GRAVITATION_EXAMPLES)


def get(name: str, **kwargs) -> System:
    """The example `name` built with `kwargs`, e.g. ``get("n_link_pendulum", n=5)``.

    The names n_link_pendulum Systems carry (``n_link_pendulum_5``) are accepted too.
    """
    match = re.fullmatch(r"n_link_pendulum_(\d+)", name) if isinstance(name, str) else None
    if match and "n" not in kwargs:  # the name an n_link_pendulum System carries
        return n_link_pendulum(n=int(match.group(1)), **kwargs)
    try:
        factory = EXAMPLES[name]
    except (KeyError, TypeError):
        raise ModelError(f"Unknown example {name!r}; known examples: {', '.join(sorted(EXAMPLES))}.") from None
    return factory(**kwargs)
