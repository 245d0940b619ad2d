"""What the user writes: coordinates, energies, forces (see `system`)."""

from lagcomp.model.system import System as System, coordinates as coordinates, t as t
from lagcomp.model.constraints import Holonomic as Holonomic, Nonholonomic as Nonholonomic
from lagcomp.model.events import Event as Event
from lagcomp.model.contacts import Contact as Contact
from lagcomp.model.friction import Friction as Friction
from lagcomp.model.inputs import Input as Input
from lagcomp.model.bodies import Particle as Particle, RigidBody as RigidBody, body_rates as body_rates, rotated as rotated
from lagcomp.model.frames import MovingFrame as MovingFrame
from lagcomp.model.loads import (
    Damper as Damper,
    Force as Force,
    Gravity as Gravity,
    Spring as Spring,
    Torque as Torque,
)
from lagcomp.model.interop import from_kanes_method as from_kanes_method, from_lagranges_method as from_lagranges_method
