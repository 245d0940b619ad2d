"""The Taylor mode programs of a System whose ``closed_contacts`` kernel holds a temporary of the parameters only
(a common factor CSE took out of the gap's gradient): the program binds ``closed_contacts``' temporaries under other
names (``_h``…, `lagcomp.codegen.taylor._bind_closed`), and a scalar computed from one must read it by that name.

The model: a particle (mass m) under gravity g dropped onto the incline x + y = 0, written as the gap a b (x + y),
restitution e.  It first meets the incline at t1 = √(2 h/g) from (0, h); once at rest on it, it slides down, held
by the normal force λ: m ẍ = a b λ, m ÿ = a b λ − m g and ẍ + ÿ = 0 give λ = m g/(2 a b) (in the units conjugate to
the gap), ẍ = g/2 = −ÿ.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.integrate.status import Status

G = 9.81


@pytest.fixture(scope="module")
def incline(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g, a, b, e = sp.symbols("m g a b e", positive=True)
    system = lc.System([x, y], T=m * (x.diff(lc.t) ** 2 + y.diff(lc.t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("incline", a * b * (x + y), restitution=e)], name="taylor_modes_incline",
                       defaults={"m": 1.5, "g": G, "a": 2.0, "b": 0.75, "e": 0.5})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def test_the_particle_slides_down_the_incline_held_by_the_closed_form_force(incline):
    h = 1.0
    taylor = incline.simulate((0.0, 3.0), [0.0, h], [0.0, 0.0], method="taylor", rtol=1e-12, atol=1e-12,
                              t_eval=np.linspace(0.0, 3.0, 301))
    dop853 = incline.simulate((0.0, 3.0), [0.0, h], [0.0, 0.0], method="dop853", rtol=1e-13, atol=1e-13,
                              t_eval=np.linspace(0.0, 3.0, 301))
    assert taylor.status == Status.DONE, taylor.message
    assert taylor.events["incline"].t[0] == pytest.approx(np.sqrt(2 * h / G), abs=1e-12)
    np.testing.assert_allclose(taylor.events["incline"].t, dop853.events["incline"].t, rtol=0, atol=1e-10)
    assert [(s.contact, s.closed) for s in taylor.contact_switches] == [("incline", True)]
    held = taylor.t > taylor.contact_switches[0].t
    assert held.sum() > 10
    np.testing.assert_allclose(taylor.contact_forces[held, 0], 1.5 * G / (2 * 2.0 * 0.75), rtol=1e-12)
    np.testing.assert_allclose(taylor.y[held], dop853.y[held], rtol=0, atol=1e-9)
