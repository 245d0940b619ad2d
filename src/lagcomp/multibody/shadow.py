"""The shadow switch of a spherical joint's MRPs, as an event with a reset (`lagcomp.multibody.mrp`).

Each spherical (or free) joint gets the event ``<link>_shadow``: g = σ·σ − 1 crossing zero upwards (the rotation
passing half a turn), reset σ → −σ / s, σ̇ → −σ̇ / s + 2 σ (σ·σ̇) / s² (s = σ·σ).  The orientation and the angular
velocity, hence the energy and the momenta of the bodies, are the same after it; the coordinates stay within
|σ| ≤ 1, far from the parametrization's singularity at |σ| → ∞ (a full turn).  The drivers' events locate the
crossing and apply the reset like any other event's, so a run records the switches in `Solution.events`.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.model.events import Event
from lagcomp.multibody import mrp
from lagcomp.multibody.joints import t


def shadow_events(nodes) -> tuple[Event, ...]:
    """One `lagcomp.Event` per spherical joint among the tree's `nodes` (`lagcomp.multibody.tree.Node`), in node
    order."""
    events = []
    for i, node in enumerate(nodes):
        if node.joint.kind != "spherical" or node.joint.axis != (1, 0, 0):
            continue
        sigma = [nodes[i + k].joint.coordinate for k in range(3)]
        rates = [c.diff(t) for c in sigma]
        after, rates_after = mrp.shadow(sigma, rates)
        reset = dict(zip(sigma, after)) | dict(zip(rates, rates_after))
        events.append(Event(f"{nodes[i + 2].link}_shadow", sp.Add(*(c ** 2 for c in sigma)) - 1, direction=1,
                            reset=reset))
    return tuple(events)
