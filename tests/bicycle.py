"""The Whipple bicycle of Meijaard, Papadopoulos, Ruina & Schwab (2007) as sympy's test_kane3 builds it.

`kane3_bicycle()` is sympy's own KanesMethod model (sympy/physics/mechanics/
tests/test_kane3.py, ported from Autolev), unchanged: coordinates yaw q1,
lean (roll) q2, pitch q4 (dependent, through the holonomic front-contact
condition) and steer q5; speeds u1 (yaw rate), u2 (lean rate), u3 (rear
wheel rate), u4 (pitch rate), u5 (steer rate), u6 (front wheel rate), of
which u1, u4, u6 are dependent through the front contact's velocity
constraints.  The wheel angles are ignorable and have no coordinates.

`first_order_form(km)` turns it into lagcomp's `FirstOrderForm` (plain
symbols; M, F = KanesMethod's full mass matrix and forcing, Φ = the
configuration constraint, Ψ = the velocity constraints), and
`BENCHMARK` holds the numerical parameters of the benchmark bicycle in the
model's symbols, as test_kane3 converts them from the paper's Table 1.

Building the KanesMethod takes most of a minute; tests build it once per
session.
"""

from __future__ import annotations

import sympy as sp
import sympy.physics.mechanics as me
from sympy import acos, cos, pi, sin, sqrt

from lagcomp.mechanics.first_order import FirstOrderForm

PARAMETER_NAMES = ("WFrad WRrad htangle forkoffset forklength framelength forkcg1 forkcg3 framecg1 framecg3 "
                   "Iwr11 Iwr22 Iwf11 Iwf22 Iframe11 Iframe22 Iframe33 Iframe31 Ifork11 Ifork22 Ifork33 Ifork31 g "
                   "mframe mfork mwf mwr").split()

#: Wheel radii of the benchmark bicycle (m): forward speed v means u3 = v / RAD_REAR, u6 = v / RAD_FRONT.
RAD_REAR, RAD_FRONT = 0.3, 0.35


def kane3_bicycle() -> me.KanesMethod:
    """sympy's test_kane3 bicycle, its `kanes_equations` formed (a few lines of test_kane3, verbatim in substance)."""
    q1, q2, q4, q5 = me.dynamicsymbols("q1 q2 q4 q5")
    q1d, q2d, q4d, q5d = me.dynamicsymbols("q1 q2 q4 q5", 1)
    u1, u2, u3, u4, u5, u6 = me.dynamicsymbols("u1 u2 u3 u4 u5 u6")
    (WFrad, WRrad, htangle, forkoffset, forklength, framelength, forkcg1, forkcg3, framecg1, framecg3,
     Iwr11, Iwr22, Iwf11, Iwf22, Iframe11, Iframe22, Iframe33, Iframe31, Ifork11, Ifork22, Ifork33, Ifork31,
     g, mframe, mfork, mwf, mwr) = sp.symbols(PARAMETER_NAMES)

    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    R = Y.orientnew("R", "Axis", [q2, Y.x])
    Frame = R.orientnew("Frame", "Axis", [q4 + htangle, R.y])
    WR = me.ReferenceFrame("WR")
    TempFrame = Frame.orientnew("TempFrame", "Axis", [-htangle, Frame.y])
    Fork = Frame.orientnew("Fork", "Axis", [q5, Frame.x])
    TempFork = Fork.orientnew("TempFork", "Axis", [-htangle, Fork.y])
    WF = me.ReferenceFrame("WF")

    WR_cont = me.Point("WR_cont")
    WR_mc = WR_cont.locatenew("WR_mc", WRrad * R.z)
    Steer = WR_mc.locatenew("Steer", framelength * Frame.z)
    Frame_mc = WR_mc.locatenew("Frame_mc", -framecg1 * Frame.x + framecg3 * Frame.z)
    Fork_mc = Steer.locatenew("Fork_mc", -forkcg1 * Fork.x + forkcg3 * Fork.z)
    WF_mc = Steer.locatenew("WF_mc", forklength * Fork.x + forkoffset * Fork.z)
    WF_cont = WF_mc.locatenew("WF_cont", WFrad * (me.dot(Fork.y, Y.z) * Fork.y - Y.z).normalize())

    Y.set_ang_vel(N, u1 * Y.z)
    R.set_ang_vel(Y, u2 * R.x)
    WR.set_ang_vel(Frame, u3 * Frame.y)
    Frame.set_ang_vel(R, u4 * Frame.y)
    Fork.set_ang_vel(Frame, u5 * Fork.x)
    WF.set_ang_vel(Fork, u6 * Fork.y)

    WR_cont.set_vel(N, 0)
    WR_mc.v2pt_theory(WR_cont, N, WR)
    Steer.v2pt_theory(WR_mc, N, Frame)
    Frame_mc.v2pt_theory(WR_mc, N, Frame)
    Fork_mc.v2pt_theory(Steer, N, Fork)
    WF_mc.v2pt_theory(Steer, N, Fork)
    WF_cont.v2pt_theory(WF_mc, N, WF)

    Frame_I = (me.inertia(TempFrame, Iframe11, Iframe22, Iframe33, 0, 0, Iframe31), Frame_mc)
    Fork_I = (me.inertia(TempFork, Ifork11, Ifork22, Ifork33, 0, 0, Ifork31), Fork_mc)
    WR_I = (me.inertia(Frame, Iwr11, Iwr22, Iwr11), WR_mc)
    WF_I = (me.inertia(Fork, Iwf11, Iwf22, Iwf11), WF_mc)
    bodies = [me.RigidBody("BodyFrame", Frame_mc, Frame, mframe, Frame_I),
              me.RigidBody("BodyFork", Fork_mc, Fork, mfork, Fork_I),
              me.RigidBody("BodyWR", WR_mc, WR, mwr, WR_I),
              me.RigidBody("BodyWF", WF_mc, WF, mwf, WF_I)]
    loads = [(Frame_mc, -mframe * g * Y.z), (Fork_mc, -mfork * g * Y.z),
             (WF_mc, -mwf * g * Y.z), (WR_mc, -mwr * g * Y.z)]

    km = me.KanesMethod(
        N, q_ind=[q1, q2, q5], q_dependent=[q4], configuration_constraints=[WF_cont.pos_from(WR_cont) & Y.z],
        u_ind=[u2, u3, u5], u_dependent=[u1, u4, u6],
        velocity_constraints=[WF_cont.vel(N) & Y.x, WF_cont.vel(N) & Y.y, WF_cont.vel(N) & Y.z],
        kd_eqs=[q1d - u1, q2d - u2, q4d - u4, q5d - u5], constraint_solver="CRAMER")
    km.kanes_equations(bodies, loads)
    return km


def _benchmark_values() -> dict:
    """Table 1 of Meijaard et al. (2007) in the model's parameters, converted as test_kane3 converts them."""
    HTA = (pi / 2 - pi / 10).evalf()
    trail, rad_front, rad_rear, wheelbase = 0.08, RAD_FRONT, RAD_REAR, 1.02
    frame_cg_x, frame_cg_z, fork_cg_x, fork_cg_z = 0.3, 0.9, 0.9, 0.7
    rake = (-(trail * sin(HTA) - (rad_front * cos(HTA)))).evalf()
    frame_length = (wheelbase * sin(HTA) - (rake - (rad_front - rad_rear) * cos(HTA))).evalf()
    frame_cg_norm = ((frame_cg_z - rad_rear - (frame_cg_x / sin(HTA)) * cos(HTA)) * sin(HTA)).evalf()
    frame_cg_par = (frame_cg_x / sin(HTA)
                    + (frame_cg_z - rad_rear - frame_cg_x / sin(HTA) * cos(HTA)) * cos(HTA)).evalf()
    tempa, tempb = fork_cg_z - rad_front, wheelbase - fork_cg_x
    tempc = sqrt(tempa**2 + tempb**2).evalf()
    fork_length = (wheelbase * cos(HTA) - (rad_front - rad_rear) * sin(HTA)).evalf()
    fork_cg_norm = (rake + (tempc * sin(pi / 2 - HTA - acos(tempa / tempc)))).evalf()
    fork_cg_par = (tempc * cos((pi / 2 - HTA) - acos(tempa / tempc)) - fork_length).evalf()
    values = dict(WFrad=rad_front, WRrad=rad_rear, htangle=HTA, forkoffset=rake, forklength=fork_length,
                  framelength=frame_length, forkcg1=fork_cg_par, forkcg3=fork_cg_norm, framecg1=frame_cg_norm,
                  framecg3=frame_cg_par, Iwr11=0.0603, Iwr22=0.12, Iwf11=0.1405, Iwf22=0.28, Ifork11=0.05892,
                  Ifork22=0.06, Ifork33=0.00708, Ifork31=0.00756, Iframe11=9.2, Iframe22=11, Iframe33=2.8,
                  Iframe31=-2.4, mfork=4, mframe=85, mwf=3, mwr=2, g=9.81)
    return {name: float(value) for name, value in values.items()}


#: The benchmark bicycle's parameters by name (test_kane3's val_dict without the state).
BENCHMARK = _benchmark_values()


def first_order_form(km: me.KanesMethod, parameters=None) -> FirstOrderForm:
    """q̇ = N(q, u), M u̇ = F, Φ = 0, Ψ = 0 of any formed `km` in plain symbols (no multipliers: C has no rows).

    `parameters`: the parameter symbols in order (default: the bicycle's, `PARAMETER_NAMES`).
    """
    t = me.dynamicsymbols._t
    q, u = list(km.q), list(km.u)
    q_plain = sp.symbols(" ".join(str(s.func) for s in q))
    u_plain = sp.symbols(" ".join(str(s.func) for s in u))
    plain = {**{s.diff(t): sp.Dummy() for s in q + u}, **dict(zip(q, q_plain)), **dict(zip(u, u_plain))}
    kindiff = km.kindiffdict()

    def convert(matrix) -> sp.Matrix:
        converted = sp.Matrix(matrix).xreplace(plain)
        leftover = [s for s in converted.free_symbols if isinstance(s, sp.Dummy)]
        assert not leftover, f"derivatives left in the Kane form: {leftover}"
        return converted

    velocity = sp.Matrix(km._k_nh) * sp.Matrix(u) + sp.Matrix(km._f_nh)
    parameters = tuple(sp.Symbol(name) for name in PARAMETER_NAMES) if parameters is None else tuple(parameters)
    return FirstOrderForm(
        q=tuple(q_plain), u=tuple(u_plain), parameters=parameters,
        coordinate_names=tuple(str(s) for s in q_plain), speed_names=tuple(str(s) for s in u_plain),
        N=convert([kindiff[s.diff(t)] for s in q]), M=convert(km.mass_matrix), F=convert(km.forcing),
        C=sp.zeros(0, len(u)), gamma=sp.zeros(0, 1),
        Phi=convert(km._f_h), Psi=convert(velocity),
    )
