"""What the user writes: coordinates, energies, forces (see `system`)."""

from lagcomp.model.system import System as System, coordinates as coordinates, t as t
from lagcomp.model.constraints import Holonomic as Holonomic, Nonholonomic as Nonholonomic
