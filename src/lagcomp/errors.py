"""Exceptions and warnings raised by lagcomp.

Every error a user can provoke with bad input is a subclass of `LagcompError`
and also of the builtin it refines (`ValueError` for bad input, `RuntimeError`
for failures at run time), so ``except ValueError`` keeps working.  Messages
name the culprit and say how to fix it.
"""

from __future__ import annotations


class LagcompError(Exception):
    """Base class of every error lagcomp raises on purpose."""


class ModelError(LagcompError, ValueError):
    """The system description is not a valid mechanical system."""


class UndeclaredSymbolError(ModelError):
    """An expression contains a symbol that is neither coordinate, parameter nor t."""


class SingularMassMatrixError(ModelError):
    """The kinetic energy is not positive definite in the velocities."""


class LinearizationError(LagcompError, ValueError):
    """A linearization cannot be formed as asked: singular constraint blocks, a dropped state that matters."""


class CorruptCacheRecordError(ModelError):
    """The cache's record of a model's name could not be read; it was removed (compile the model again)."""


class ParameterError(LagcompError, ValueError):
    """Parameter values are missing, unknown or not finite."""


class InitialConditionError(LagcompError, ValueError):
    """Initial coordinates or velocities have the wrong length or are not finite."""


class OptionError(LagcompError, ValueError):
    """An integration option (time span, step, tolerance, method...) is out of range."""


class UnknownEventError(OptionError, KeyError):
    """`Solution.events[name]` of a name the run has no record of (a KeyError too, as a dict's)."""

    def __str__(self) -> str:  # (KeyError's own would quote the message)
        return str(self.args[0]) if self.args else ""


class IntegrationError(LagcompError, RuntimeError):
    """An integration failed; the partial solution is attached as ``.solution``."""

    def __init__(self, message: str, solution=None):
        super().__init__(message)
        self.solution = solution


class CacheWarning(UserWarning):
    """A cache entry could not be used and was rebuilt."""


class ResetWarning(UserWarning):
    """An event's reset stopped the motion across its surface, and the body then went through the surface without
    the event firing again (`lagcomp.integrate.reset_checks`): a floor that holds is ``lc.Contact``."""


class StiffnessWarning(UserWarning):
    """An explicit method's steps were limited by its stability, not its accuracy: use ``method="radau"``."""
