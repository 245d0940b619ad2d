"""KanesMethod models for the Kane interop tests (tests/test_kane_interop.py).

`bicycle()` is the Whipple bicycle of sympy's own test
(sympy/physics/mechanics/tests/test_kane3.py, sympy 1.14), built exactly as
that test builds it — same frames, points, hand-set velocities
(``v2pt_theory`` from a contact point whose velocity is set to zero),
speeds, kinematic equations and constraints, constraint_solver="CRAMER" —
with the benchmark parameter values of Meijaard, Papadopoulos, Ruina &
Schwab (2007) as that test enters them.  `bicycle(wheel_angles=True)` is the
variant of issue 18: the two wheel angles added as coordinates so that
u = q̇, the point velocities still set by hand.
"""

from __future__ import annotations

from sympy import acos, cos, pi, sin, sqrt, symbols
from sympy.physics.mechanics import KanesMethod, Point, ReferenceFrame, RigidBody, dot, dynamicsymbols, inertia


def bicycle(wheel_angles: bool = False):
    """(KanesMethod after kanes_equations, parameter values by name, rear and front wheel radii)."""
    q1, q2, q4, q5 = dynamicsymbols("q1 q2 q4 q5")
    q1d, q2d, q4d, q5d = dynamicsymbols("q1 q2 q4 q5", 1)
    u1, u2, u3, u4, u5, u6 = dynamicsymbols("u1 u2 u3 u4 u5 u6")
    WFrad, WRrad, htangle, forkoffset = symbols("WFrad WRrad htangle forkoffset")
    forklength, framelength, forkcg1 = symbols("forklength framelength forkcg1")
    forkcg3, framecg1, framecg3, Iwr11 = symbols("forkcg3 framecg1 framecg3 Iwr11")
    Iwr22, Iwf11, Iwf22, Iframe11 = symbols("Iwr22 Iwf11 Iwf22 Iframe11")
    Iframe22, Iframe33, Iframe31, Ifork11 = symbols("Iframe22 Iframe33 Iframe31 Ifork11")
    Ifork22, Ifork33, Ifork31, g = symbols("Ifork22 Ifork33 Ifork31 g")
    mframe, mfork, mwf, mwr = symbols("mframe mfork mwf mwr")

    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    R = Y.orientnew("R", "Axis", [q2, Y.x])
    Frame = R.orientnew("Frame", "Axis", [q4 + htangle, R.y])
    WR = ReferenceFrame("WR")
    TempFrame = Frame.orientnew("TempFrame", "Axis", [-htangle, Frame.y])
    Fork = Frame.orientnew("Fork", "Axis", [q5, Frame.x])
    TempFork = Fork.orientnew("TempFork", "Axis", [-htangle, Fork.y])
    WF = ReferenceFrame("WF")

    WR_cont = Point("WR_cont")
    WR_mc = WR_cont.locatenew("WR_mc", WRrad * R.z)
    Steer = WR_mc.locatenew("Steer", framelength * Frame.z)
    Frame_mc = WR_mc.locatenew("Frame_mc", -framecg1 * Frame.x + framecg3 * Frame.z)
    Fork_mc = Steer.locatenew("Fork_mc", -forkcg1 * Fork.x + forkcg3 * Fork.z)
    WF_mc = Steer.locatenew("WF_mc", forklength * Fork.x + forkoffset * Fork.z)
    WF_cont = WF_mc.locatenew("WF_cont", WFrad * (dot(Fork.y, Y.z) * Fork.y - Y.z).normalize())

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

    Frame_I = (inertia(TempFrame, Iframe11, Iframe22, Iframe33, 0, 0, Iframe31), Frame_mc)
    Fork_I = (inertia(TempFork, Ifork11, Ifork22, Ifork33, 0, 0, Ifork31), Fork_mc)
    WR_I = (inertia(Frame, Iwr11, Iwr22, Iwr11), WR_mc)
    WF_I = (inertia(Fork, Iwf11, Iwf22, Iwf11), WF_mc)
    BodyFrame = RigidBody("BodyFrame", Frame_mc, Frame, mframe, Frame_I)
    BodyFork = RigidBody("BodyFork", Fork_mc, Fork, mfork, Fork_I)
    BodyWR = RigidBody("BodyWR", WR_mc, WR, mwr, WR_I)
    BodyWF = RigidBody("BodyWF", WF_mc, WF, mwf, WF_I)

    kd = [q1d - u1, q2d - u2, q4d - u4, q5d - u5]
    q_ind, q_dep = [q1, q2, q5], [q4]
    if wheel_angles:  # issue 18's variant: the wheel angles as coordinates, u = q̇ throughout
        q3, q6 = dynamicsymbols("q3 q6")
        kd += [q3.diff() - u3, q6.diff() - u6]
        q_ind += [q3, q6]
    conlist_speed = [WF_cont.vel(N) & Y.x, WF_cont.vel(N) & Y.y, WF_cont.vel(N) & Y.z]
    conlist_coord = [WF_cont.pos_from(WR_cont) & Y.z]
    FL = [(Frame_mc, -mframe * g * Y.z), (Fork_mc, -mfork * g * Y.z), (WF_mc, -mwf * g * Y.z),
          (WR_mc, -mwr * g * Y.z)]
    BL = [BodyFrame, BodyFork, BodyWR, BodyWF]
    KM = KanesMethod(N, q_ind=q_ind, q_dependent=q_dep, configuration_constraints=conlist_coord,
                     u_ind=[u2, u3, u5], u_dependent=[u1, u4, u6], velocity_constraints=conlist_speed,
                     kd_eqs=kd, constraint_solver="CRAMER")
    KM.kanes_equations(BL, FL)
    return KM, dict(BENCHMARK), (RAD_REAR, RAD_FRONT)


def _benchmark_values() -> dict:
    """test_kane3's numerical values (the benchmark bicycle), by parameter name."""
    PaperRadRear, PaperRadFront = 0.3, 0.35
    HTA = float(pi / 2 - pi / 10)
    TrailPaper, PaperWb = 0.08, 1.02
    rake = -(TrailPaper * sin(HTA) - (PaperRadFront * cos(HTA)))
    PaperFrameCgX, PaperFrameCgZ, PaperForkCgX, PaperForkCgZ = 0.3, 0.9, 0.9, 0.7
    FrameLength = PaperWb * sin(HTA) - (rake - (PaperRadFront - PaperRadRear) * cos(HTA))
    FrameCGNorm = (PaperFrameCgZ - PaperRadRear - (PaperFrameCgX / sin(HTA)) * cos(HTA)) * sin(HTA)
    FrameCGPar = PaperFrameCgX / sin(HTA) + (PaperFrameCgZ - PaperRadRear - PaperFrameCgX / sin(HTA) * cos(HTA)) * cos(HTA)
    tempa, tempb = PaperForkCgZ - PaperRadFront, PaperWb - PaperForkCgX
    tempc = sqrt(tempa**2 + tempb**2)
    PaperForkL = PaperWb * cos(HTA) - (PaperRadFront - PaperRadRear) * sin(HTA)
    ForkCGNorm = rake + (tempc * sin(pi / 2 - HTA - acos(tempa / tempc)))
    ForkCGPar = tempc * cos((pi / 2 - HTA) - acos(tempa / tempc)) - PaperForkL
    values = dict(
        WFrad=PaperRadFront, WRrad=PaperRadRear, htangle=HTA, forkoffset=rake, forklength=PaperForkL,
        framelength=FrameLength, forkcg1=ForkCGPar, forkcg3=ForkCGNorm, framecg1=FrameCGNorm, framecg3=FrameCGPar,
        Iwr11=0.0603, Iwr22=0.12, Iwf11=0.1405, Iwf22=0.28, Ifork11=0.05892, Ifork22=0.06, Ifork33=0.00708,
        Ifork31=0.00756, Iframe11=9.2, Iframe22=11, Iframe33=2.8, Iframe31=-2.4, mfork=4, mframe=85, mwf=3, mwr=2,
        g=9.81,
    )
    return {k: float(v) for k, v in values.items()}


#: The benchmark bicycle's parameter values by name.
BENCHMARK = _benchmark_values()
#: Its wheel radii (m): a forward speed v is the rear wheel rate u3 = v / RAD_REAR, the front's u6 = v / RAD_FRONT.
RAD_REAR, RAD_FRONT = 0.3, 0.35
