"""State-space models for control: ẋ = A x + B w, z = C x + D w about an equilibrium or a steady motion.

`lagcomp.analysis.linearize(model, q, inputs=...)` (unconstrained, x = (δq, δq̇)) and
`lagcomp.analysis.linearize_steady(..., inputs=...)` (constrained too, x the independent coordinates and
speeds) give A and B: x the deviation of the state from the point, w that of the inputs from the values
they are held at.  The outputs z are states chosen by name (C picks them, D = 0), from `linearize` points of
bodies (``"cart.x"``, ``"pole.vy"``: `lagcomp.analysis.body_outputs`) and, from
`linearize_steady`, constraints' reactions (the multipliers' deviations: C = ∂λ/∂x, D = ∂λ/∂w).  `StateSpace.to_scipy`
gives a `scipy.signal.StateSpace`, `StateSpace.to_control` a python-control one (``pip install control``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lagcomp.errors import LinearizationError, OptionError


@dataclass(frozen=True)
class StateSpace:
    """ẋ = A x + B w, z = C x + D w (module docstring).

    Attributes
    ----------
    A : ndarray, shape (m, m)
    B : ndarray, shape (m, U)
    C : ndarray, shape (r, m)
    D : ndarray, shape (r, U)
    states, inputs, outputs : tuple of str
        Labels of x, w and z.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple
    inputs: tuple
    outputs: tuple

    @classmethod
    def of_states(cls, A, B, states, inputs, outputs=None, input_derivatives=(), rows=None) -> StateSpace:
        """A, B with the states named in `outputs` (all when None) as outputs, or other outputs `rows` gives
        ({name: (C row (m,), D row (U,))}: a linearization's reactions); LinearizationError for inputs whose
        derivatives enter the equations (`input_derivatives`)."""
        if input_derivatives:
            raise LinearizationError(
                f"The equations read the derivatives of the input(s) {list(input_derivatives)} (an imposed motion "
                "in T or a constraint): the motion responds to u̇ and ü too, which an input matrix B does not "
                "describe. Write such an input as a force, or take its derivatives as states of your own.")
        states, rows = tuple(states), rows or {}
        names = states if outputs is None else tuple(outputs)
        unknown = [name for name in names if name not in states and name not in rows]
        if unknown:
            raise OptionError(f"Unknown output(s) {unknown}: outputs are states, {list(states)}"
                              + (f", or {list(rows)}." if rows else "."))
        B = np.zeros((len(states), 0)) if B is None else np.asarray(B, dtype=float)
        C, D = np.zeros((len(names), len(states))), np.zeros((len(names), B.shape[1]))
        for i, name in enumerate(names):
            if name in states:
                C[i, states.index(name)] = 1.0
            else:
                C[i], D[i] = rows[name]
        return cls(A=np.asarray(A, dtype=float), B=B, C=C, D=D, states=states, inputs=tuple(inputs), outputs=names)

    def to_scipy(self):
        """`scipy.signal.StateSpace` (A, B, C, D)."""
        from scipy import signal

        return signal.StateSpace(self.A, self.B, self.C, self.D)

    def to_control(self):
        """A python-control ``StateSpace`` with the states', inputs' and outputs' names (needs ``control``); a
        body point's ``"bob.x"`` is named ``"bob_x"`` there (python-control refuses '.' in a signal's name)."""
        try:
            import control
        except ImportError as err:
            raise ImportError("StateSpace.to_control needs python-control (pip install control); "
                              "StateSpace.to_scipy gives a scipy.signal.StateSpace without it.") from err
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states), inputs=list(self.inputs),
                          outputs=[name.replace(".", "_") for name in self.outputs])

    def __repr__(self) -> str:
        return f"StateSpace(states={list(self.states)}, inputs={list(self.inputs)}, outputs={list(self.outputs)})"
