"""The bodies of a run for `lagcomp.animation`: centres and axes from the model's ``geometry`` kernel.

A Solution made by `simulate` carries a `BodyGeometry`: its model's ``geometry`` kernel, the
layout the module describes it with (``GEOMETRY``, `lagcomp.codegen.geometry`) and the run's
parameter vector.  `BodyGeometry.frames` calls the kernel once per frame, at the frame's time
and the coordinates interpolated there; velocities are not needed, positions depend on q, t and
the parameters only.  This module imports numpy alone: `simulate` builds a `BodyGeometry` for
every run, drawn or not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The name of the base frame's origin in a tree's skeleton (`lagcomp.animation.ORIGIN`).
ORIGIN = "origin"

#: The columns of a rotation matrix, the body's axes, as the animation labels them.
AXIS_LABELS = ("x", "y", "z")

#: The kinds of entries of ``GEOMETRY`` that write a position then a rotation matrix: a System's rigid body
#: (`lagcomp.codegen.geometry`), a tree's link frame (`lagcomp.codegen.tree_geometry`).
ROTATED = ("rigid", "link")


@dataclass(frozen=True)
class BodyFrames:
    """The bodies at each frame.

    centres : dict of str to ndarray, shape (frames, 3)
        Each drawn body's position (a particle's, a rigid body's centre of mass, a tree link's frame
        origin), by name.
    rotations : dict of str to ndarray, shape (frames, 3, 3)
        Each rigid body's (or tree link's) rotation matrix C whose columns are its axes, by name
        (bodies whose orientation the model knows).
    unplaced : tuple of str
        Bodies the model cannot place (a sympy Point with no frame origin): not drawn.
    skeleton : tuple of (str, str)
        A kinematic tree's rods: (parent link, link) for each link, ``"origin"`` for the base
        (`BodyGeometry.parents`); empty for a System's bodies.
    """

    centres: dict
    rotations: dict
    unplaced: tuple
    skeleton: tuple = ()

    def planar(self) -> bool:
        """Every centre stays at z = 0 and every body turns about z only, exactly, at every frame."""
        centres = all(not np.any(c[:, 2]) for c in self.centres.values())
        turns = all(not np.any(C[:, 2, :2]) and not np.any(C[:, :2, 2]) for C in self.rotations.values())
        return centres and turns

    def axis_tips(self, length: float, d: int) -> dict[tuple[str, str], np.ndarray]:
        """The end of each body axis drawn from its centre, G + length · C[:, j], shape (frames, d), by
        (body, axis label); in 2-D (`d` = 2) the x and y axes only, in the plane."""
        return {(name, label): (self.centres[name] + length * C[:, :, j])[:, :d]
                for name, C in self.rotations.items() for j, label in enumerate(AXIS_LABELS[:d])}


class BodyGeometry:
    """A model's ``geometry`` kernel with its layout and a run's parameters (module docstring).

    layout : tuple of (name, kind, offset)
        The module's ``GEOMETRY``; empty for a model without bodies.
    size : int
        ``GEOMETRY_SIZE``, the length of the kernel's output.
    p : ndarray
        The parameter vector the run used.
    kernel : numba dispatcher or None
        ``geometry(t, y, p, out)``; None once the Solution was pickled (the kernel is not kept).
    parents : tuple of (str, str or None)
        A kinematic tree's ``GEOMETRY_PARENTS`` (each link and its parent link, None for the base),
        drawn as rods; empty for a System's bodies.

    `of` reads the three from the model's kernels when one of them is first read, not before: ``geometry``
    is an on-demand kernel (`lagcomp.codegen.kinds`), built the first time an animation or a plot asks.
    """

    def __init__(self, layout: tuple, size: int, p: np.ndarray, kernel=None, kernels=None, parents: tuple = ()):
        self._layout, self._size, self.p, self._kernel = layout, size, p, kernel
        self._parents = parents
        self._kernels = kernels     # (the model's kernels, until they are read: `_read`)

    def _read(self) -> None:
        if self._kernels is not None:
            module, self._kernels = self._kernels, None
            self._layout = tuple(getattr(module, "GEOMETRY", ()))
            self._size = int(getattr(module, "GEOMETRY_SIZE", 0))
            self._kernel = getattr(module, "geometry", None)
            self._parents = tuple(getattr(module, "GEOMETRY_PARENTS", ()))

    @property
    def layout(self) -> tuple:
        self._read()
        return self._layout

    @property
    def size(self) -> int:
        self._read()
        return self._size

    @property
    def kernel(self):
        self._read()
        return self._kernel

    @property
    def parents(self) -> tuple:
        """((link, parent link or None), ...) of a kinematic tree's links (``GEOMETRY_PARENTS``,
        `lagcomp.codegen.tree_geometry`); empty for a System's bodies."""
        self._read()
        return self._parents

    @classmethod
    def of(cls, model, p: np.ndarray) -> BodyGeometry:
        """The geometry of `model` (a Model or KaneModel: its generated modules) for the parameters `p`."""
        return cls((), 0, np.array(p, dtype=float), None, model.kernels)

    def __reduce__(self):
        """Pickled without the kernel: a numba function of a generated module another process may not have."""
        return BodyGeometry, (self.layout, self.size, self.p, None, None, self.parents)

    def __deepcopy__(self, memo) -> BodyGeometry:
        """A copy that keeps the kernel (in this process it stays valid), read or not yet."""
        return BodyGeometry(self._layout, self._size, self.p.copy(), self._kernel, self._kernels, self._parents)

    def __repr__(self) -> str:
        return f"BodyGeometry(layout={self.layout!r}, size={self.size!r}, p={self.p!r})"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _, _ in self.layout)

    def frames(self, times: np.ndarray, q: np.ndarray) -> BodyFrames:
        """The bodies at `times` (frames,), the coordinates there `q` (frames, n)."""
        out = np.zeros((len(times), self.size))
        y = np.zeros(2 * q.shape[1])  # (q, q̇): the kernel reads no velocity
        for k, time in enumerate(times):
            y[:q.shape[1]] = q[k]
            self.kernel(float(time), y, self.p, out[k])
        centres, rotations, unplaced = {}, {}, []
        for name, kind, offset in self.layout:
            if kind == "unplaced":
                unplaced.append(name)
                continue
            centres[name] = out[:, offset:offset + 3]
            if kind in ROTATED:
                rotations[name] = out[:, offset + 3:offset + 12].reshape(-1, 3, 3)
        skeleton = tuple((parent or ORIGIN, name) for name, parent in self.parents)
        return BodyFrames(centres, rotations, tuple(unplaced), skeleton)
