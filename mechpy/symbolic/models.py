"""Models written with SymPy's mechanics, for :func:`mechpy.mechanics`.

* :func:`rolling_disc`: a thin disc rolling without slipping on a plane (Kane,
  two nonholonomic constraints, the contact point's x, y dependent speeds);
* :func:`whipple_bicycle`: the Carvallo-Whipple bicycle in Moore's
  formulation (Kane; the rear-frame pitch a dependent coordinate with the
  holonomic constraint that the front wheel touches the ground, three
  velocity constraints for the front contact), with the benchmark
  parameters of Meijaard, Papadopoulos, Ruina and Schwab, Proc. R. Soc. A 463
  (2007) 1955-1982, converted to the model's geometry;
* :func:`n_link_cart`: PyDy's n-link pendulum on a cart, driven by a force
  on the cart (a specified input).

Each returns ``(method, params)``: the formed KanesMethod and the constants'
values by name.  SymPy is imported when they are called.
"""
from __future__ import annotations

import math

__all__ = ["rolling_disc", "whipple_bicycle", "whipple_state", "n_link_cart"]


def rolling_disc():
    """A thin disc rolling without slipping on the horizontal plane.

    Coordinates (yaw q1, lean q2, spin q3, contact x q4, contact y q5), speeds
    u1..u3 = q1'..q3' (independent) and u4, u5 = q4', q5' (dependent, from
    the two rolling constraints); constants m (kg), r (m), g (m/s^2).

    Returns
    -------
    (KanesMethod, dict)
        The formed equations and the constants' values (m = 1, r = 0.5, g = 9.81).

    Examples
    --------
    Rolling upright at spin rate w, the contact point moves at r w:

    >>> from mechpy.symbolic.models import rolling_disc
    >>> kane, params = rolling_disc()
    >>> disc = mp.mechanics(kane, params)
    >>> y = [0, 0, 0, 0, 0, 0, 0, 2.0, 1.0, 0.0]   # u3 = 2 rad/s, u4 = r u3
    >>> float(np.abs(disc.constraint_residual(y)).max())
    0.0
    """
    import sympy as sp
    from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)
    q1, q2, q3, q4, q5 = dynamicsymbols("q1:6")
    u1, u2, u3, u4, u5 = dynamicsymbols("u1:6")
    m, r, g = sp.symbols("m r g", positive=True)
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", (q1, N.z))          # yaw
    L = Y.orientnew("L", "Axis", (q2, Y.x))          # lean
    R = L.orientnew("R", "Axis", (q3, L.y))          # spin about the disc's axis
    kd = [q1.diff() - u1, q2.diff() - u2, q3.diff() - u3, q4.diff() - u4, q5.diff() - u5]
    w_R = u1 * N.z + u2 * Y.x + u3 * L.y             # R's angular velocity in N
    R.set_ang_vel(N, w_R)
    O = Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", q4 * N.x + q5 * N.y)        # the contact point on the plane
    C.set_vel(N, u4 * N.x + u5 * N.y)
    D = C.locatenew("D", r * L.z)                    # the centre
    # rolling: the disc's material point at the contact is at rest
    D.set_vel(N, w_R.cross(r * L.z))
    # the centre's velocity from its position must be that one
    geo = u4 * N.x + u5 * N.y + (u1 * N.z + u2 * Y.x).cross(r * L.z)
    rel = geo - w_R.cross(r * L.z)
    cons = [rel.dot(Y.x), rel.dot(Y.y)]
    disc = RigidBody("disc", D, R, m, (inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4), D))
    kane = KanesMethod(N, q_ind=[q1, q2, q3, q4, q5], u_ind=[u1, u2, u3], u_dependent=[u4, u5],
                       kd_eqs=kd, velocity_constraints=cons)
    kane.kanes_equations([disc], [(D, -m * g * N.z)])
    return kane, {"m": 1.0, "r": 0.5, "g": 9.81}


#: The benchmark bicycle of Meijaard et al. (2007), Table 1 (SI units).
BENCHMARK = dict(w=1.02, c=0.08, lam=math.pi / 10, g=9.81, rR=0.3, mR=2.0, IRxx=0.0603,
                 IRyy=0.12, xB=0.3, zB=-0.9, mB=85.0, IBxx=9.2, IByy=11.0, IBzz=2.8,
                 IBxz=2.4, xH=0.9, zH=-0.7, mH=4.0, IHxx=0.05892, IHyy=0.06, IHzz=0.00708,
                 IHxz=-0.00756, rF=0.35, mF=3.0, IFxx=0.1405, IFyy=0.28)


def _moore_params(b=BENCHMARK):
    """The benchmark's values in Moore's geometry: the head tube angle from
    the vertical, the fork offset, the frame and fork lengths and mass-centre
    positions along and normal to the head tube (the conversion of the
    benchmark's Table 1 to the frames of the model)."""
    s = math.sin
    co = math.cos
    hta = math.pi / 2 - b["lam"]                   # head tube angle from the ground
    rake = -(b["c"] * s(hta) - b["rF"] * co(hta))
    frame_len = b["w"] * s(hta) - (rake - (b["rF"] - b["rR"]) * co(hta))
    fx, fz = b["xB"], -b["zB"]
    frame_cg_norm = (fz - b["rR"] - (fx / s(hta)) * co(hta)) * s(hta)
    frame_cg_par = fx / s(hta) + (fz - b["rR"] - fx / s(hta) * co(hta)) * co(hta)
    ta = -b["zH"] - b["rF"]
    tb = b["w"] - b["xH"]
    tc = math.hypot(ta, tb)
    fork_len = b["w"] * co(hta) - (b["rF"] - b["rR"]) * s(hta)
    fork_cg_norm = rake + tc * s(math.pi / 2 - hta - math.acos(ta / tc))
    fork_cg_par = tc * co((math.pi / 2 - hta) - math.acos(ta / tc)) - fork_len
    return {"rF": b["rF"], "rR": b["rR"], "htangle": hta, "forkoffset": rake,
            "forklength": fork_len, "framelength": frame_len, "forkcg1": fork_cg_par,
            "forkcg3": fork_cg_norm, "framecg1": frame_cg_norm, "framecg3": frame_cg_par,
            "IRxx": b["IRxx"], "IRyy": b["IRyy"], "IFxx": b["IFxx"], "IFyy": b["IFyy"],
            "IHxx": b["IHxx"], "IHyy": b["IHyy"], "IHzz": b["IHzz"], "IHxz": -b["IHxz"],
            "IBxx": b["IBxx"], "IByy": b["IByy"], "IBzz": b["IBzz"], "IBxz": -b["IBxz"],
            "mH": b["mH"], "mB": b["mB"], "mF": b["mF"], "mR": b["mR"], "g": b["g"]}


def whipple_bicycle():
    """The Carvallo-Whipple bicycle (Moore's formulation), benchmark parameters.

    Rigid rear frame B with rider, front frame H (fork and handlebar), knife-edge
    wheels R and F rolling without slipping on flat ground; no rider input.
    Coordinates (q1 yaw, q2 roll, q5 steer | q4 rear-frame pitch, dependent
    through the front wheel's contact with the ground); speeds (u2 roll rate,
    u3 rear wheel rate, u5 steer rate | u1 yaw rate, u4 pitch rate, u6 front
    wheel rate, dependent through the front contact's three velocity
    constraints).  The wheels' rotation angles are ignorable and not
    coordinates.  The constants are the benchmark's (Meijaard et al. 2007,
    Table 1) in the model's geometry.

    Returns
    -------
    (KanesMethod, dict)

    Examples
    --------
    Linearised about upright straight running at 5 m/s, the benchmark's
    eigenvalues (Meijaard et al. 2007, Table 2) are those of the lean and
    steer states:

    >>> from mechpy.symbolic.models import whipple_bicycle, whipple_state
    >>> bike = mp.mechanics(*whipple_bicycle())
    >>> A, _ = bike.linearize(whipple_state(5.0))
    >>> ev = np.linalg.eigvals(A[np.ix_([1, 2, 3, 5], [1, 2, 3, 5])])
    >>> np.round(np.sort_complex(ev), 6).tolist()
    [(-14.07839+0j), (-0.775342-4.464868j), (-0.775342+4.464868j), (-0.322866+0j)]
    >>> table2 = [-14.07838969279822, -0.32286642900409, -0.77534188219585 - 4.46486771378823j,
    ...           -0.77534188219585 + 4.46486771378823j]      # Meijaard et al., v = 5 m/s
    >>> bool(np.abs(np.sort_complex(ev) - np.sort_complex(table2)).max() < 1e-9)
    True
    """
    import sympy as sp
    from sympy.physics.mechanics import (KanesMethod, Point, ReferenceFrame, RigidBody,
                                         dynamicsymbols, inertia)
    q1, q2, q4, q5 = dynamicsymbols("q1 q2 q4 q5")
    u1, u2, u3, u4, u5, u6 = dynamicsymbols("u1:7")
    names = ("rF rR htangle forkoffset forklength framelength forkcg1 forkcg3 framecg1 "
             "framecg3 IRxx IRyy IFxx IFyy IHxx IHyy IHzz IHxz IBxx IByy IBzz IBxz mH mB mF "
             "mR g")
    (rF, rR, hta, offset, forklen, framelen, forkcg1, forkcg3, framecg1, framecg3, IRxx,
     IRyy, IFxx, IFyy, IHxx, IHyy, IHzz, IHxz, IBxx, IByy, IBzz, IBxz, mH, mB, mF, mR,
     g) = sp.symbols(names)
    N = ReferenceFrame("N")
    Yw = N.orientnew("Yw", "Axis", (q1, N.z))            # yaw
    Rl = Yw.orientnew("Rl", "Axis", (q2, Yw.x))          # roll
    Bf = Rl.orientnew("Bf", "Axis", (q4 + hta, Rl.y))    # rear frame, pitched
    Bi = Bf.orientnew("Bi", "Axis", (-hta, Bf.y))        # its inertia frame
    Hf = Bf.orientnew("Hf", "Axis", (q5, Bf.x))          # front frame, steered
    Hi = Hf.orientnew("Hi", "Axis", (-hta, Hf.y))        # its inertia frame
    Rw = ReferenceFrame("Rw")                            # rear wheel (angle ignorable)
    Fw = ReferenceFrame("Fw")                            # front wheel
    Yw.set_ang_vel(N, u1 * Yw.z)
    Rl.set_ang_vel(Yw, u2 * Rl.x)
    Bf.set_ang_vel(Rl, u4 * Bf.y)
    Hf.set_ang_vel(Bf, u5 * Hf.x)
    Rw.set_ang_vel(Bf, u3 * Bf.y)
    Fw.set_ang_vel(Hf, u6 * Hf.y)
    # rear contact -> rear hub -> steer axis / frame centre -> fork centre,
    # front hub -> front contact
    cR = Point("cR")
    hubR = cR.locatenew("hubR", rR * Rl.z)
    steer = hubR.locatenew("steer", framelen * Bf.z)
    Bmc = hubR.locatenew("Bmc", -framecg1 * Bf.x + framecg3 * Bf.z)
    Hmc = steer.locatenew("Hmc", -forkcg1 * Hf.x + forkcg3 * Hf.z)
    hubF = steer.locatenew("hubF", forklen * Hf.x + offset * Hf.z)
    # the front contact: from the hub, down the wheel's plane, normal to the ground
    down = (Hf.y.dot(Yw.z) * Hf.y - Yw.z).normalize()
    cF = hubF.locatenew("cF", rF * down)
    cR.set_vel(N, 0)
    hubR.v2pt_theory(cR, N, Rw)
    steer.v2pt_theory(hubR, N, Bf)
    Bmc.v2pt_theory(hubR, N, Bf)
    Hmc.v2pt_theory(steer, N, Hf)
    hubF.v2pt_theory(steer, N, Hf)
    cF.v2pt_theory(hubF, N, Fw)
    bodies = [RigidBody("B", Bmc, Bf, mB, (inertia(Bi, IBxx, IByy, IBzz, 0, 0, IBxz), Bmc)),
              RigidBody("H", Hmc, Hf, mH, (inertia(Hi, IHxx, IHyy, IHzz, 0, 0, IHxz), Hmc)),
              RigidBody("R", hubR, Rw, mR, (inertia(Bf, IRxx, IRyy, IRxx), hubR)),
              RigidBody("F", hubF, Fw, mF, (inertia(Hf, IFxx, IFyy, IFxx), hubF))]
    kd = [q1.diff() - u1, q2.diff() - u2, q4.diff() - u4, q5.diff() - u5]
    vcF = cF.vel(N)
    speed_cons = [vcF.dot(Yw.x), vcF.dot(Yw.y), vcF.dot(Yw.z)]
    config_cons = [cF.pos_from(cR).dot(Yw.z)]
    loads = [(Bmc, -mB * g * Yw.z), (Hmc, -mH * g * Yw.z), (hubF, -mF * g * Yw.z),
             (hubR, -mR * g * Yw.z)]
    kane = KanesMethod(N, q_ind=[q1, q2, q5], q_dependent=[q4],
                       configuration_constraints=config_cons, u_ind=[u2, u3, u5],
                       u_dependent=[u1, u4, u6], velocity_constraints=speed_cons,
                       kd_eqs=kd, constraint_solver="CRAMER")
    kane.kanes_equations(bodies, loads)
    return kane, _moore_params()


def whipple_state(v, roll=0.0, steer=0.0, roll_rate=0.0, steer_rate=0.0):
    """A state of :func:`whipple_bicycle` near upright straight running at
    forward speed v (m/s): (q1, q2, q5, q4, u2, u3, u5, u1, u4, u6) with the
    rear wheel at v / rR and the front at v / rF.  Off the upright state
    (roll or steer not zero) the dependent pitch and speeds must come from the
    constraints: ``scene.project(y)``.

    Examples
    --------
    >>> from mechpy.symbolic.models import whipple_state
    >>> np.round(whipple_state(3.0), 6).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 8.571429]
    """
    b = BENCHMARK
    return [0.0, float(roll), float(steer), 0.0, float(roll_rate), v / b["rR"],
            float(steer_rate), 0.0, 0.0, v / b["rF"]]


def n_link_cart(n):
    """PyDy's n-link pendulum on a cart (Kane): a cart on a horizontal line
    (coordinate q0, driven by the force F(t), a specified input) carrying a
    chain of n massless links with point masses, under gravity.

    Coordinates (q0, q1..qn) (link angles from the vertical), speeds u = q';
    constants m0..mn (kg), l0..l(n-1) (m), g (m/s^2), all 1.0 but g = 9.81.

    Returns
    -------
    (KanesMethod, dict)

    Examples
    --------
    >>> from mechpy.symbolic.models import n_link_cart
    >>> kane, params = n_link_cart(2)
    >>> cart = mp.mechanics(kane, params, specified={"F": 0.0})
    >>> cart.dim, cart.inputs
    (6, ['F'])
    """
    import sympy as sp
    from sympy.physics.mechanics import (KanesMethod, Particle, Point, ReferenceFrame,
                                         dynamicsymbols)
    if not isinstance(n, int) or n < 1:
        raise ValueError(f"n must be a positive integer (links), got {n!r}")
    q = dynamicsymbols(f"q:{n + 1}")
    u = dynamicsymbols(f"u:{n + 1}")
    F = dynamicsymbols("F")
    m = sp.symbols(f"m:{n + 1}")
    ls = sp.symbols(f"l:{n}")
    g = sp.Symbol("g")
    I = ReferenceFrame("I")
    O = Point("O")
    O.set_vel(I, 0)
    P0 = Point("P0")
    P0.set_pos(O, q[0] * I.x)
    P0.set_vel(I, u[0] * I.x)
    particles = [Particle("Pa0", P0, m[0])]
    loads = [(P0, F * I.x - m[0] * g * I.y)]
    kd = [q[0].diff() - u[0]]
    prev = P0
    for i in range(n):
        Bi = I.orientnew(f"B{i}", "Axis", (q[i + 1], I.z))
        Bi.set_ang_vel(I, u[i + 1] * I.z)
        Pi = prev.locatenew(f"P{i + 1}", ls[i] * Bi.x)
        Pi.v2pt_theory(prev, I, Bi)
        particles.append(Particle(f"Pa{i + 1}", Pi, m[i + 1]))
        loads.append((Pi, -m[i + 1] * g * I.y))
        kd.append(q[i + 1].diff() - u[i + 1])
        prev = Pi
    kane = KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(particles, loads)
    params = {**{f"m{i}": 1.0 for i in range(n + 1)}, **{f"l{i}": 1.0 for i in range(n)},
              "g": 9.81}
    return kane, params
