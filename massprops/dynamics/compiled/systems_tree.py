"""The spanning tree of a system program, compiled: kinematics (poses, spatial velocities, bias
accelerations at u̇ = 0, spatial inertias, the joints' motion subspaces S) and the small
spatial-vector helpers the other systems kernels use.

The maths of `dynamics.systems.tree` (which documents the frames and joint coordinates;
world-frame spatial vectors about the world origin), over the arrays of a system program
(`dynamics.systems.program`) and a workspace (`systems_step.workspace`), in loops: one pass over
the joints (O(n)). The loads are in `systems_loads`, the mass matrix and ABA in `systems_mass`.

Calling convention of the systems kernels below `systems_step`: ``pp`` and ``wp`` point to the
program and workspace tuples (`unowned.by_ref`, made once per right-hand side or projection) and
``at(pp, k)`` reads item k, instead of passing the tuples, which numba flattens into ~600
arguments per call. The small helpers are ``inlined`` (numba's IR inlining): LLVM does not inline
across numba's per-function libraries, and a call per cross product cost more than its
arithmetic (measured: the double pendulum's right-hand side 3.7 → 2.1 µs with both changes).
"""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_layout import (
    P_AXES_PARENT,
    P_COM0,
    P_INERTIA,
    P_JOINTS,
    P_MASS,
    P_ROT_PARENT0,
    P_ROTATION0,
    P_S_CHILD,
    P_S_PARENT,
    P_TURN0,
    W_ACC,
    W_BIAS,
    W_COM,
    W_INERTIA,
    W_JOINT_POINTS,
    W_M3,
    W_M6,
    W_MOTION,
    W_Q,
    W_REFERENCE,
    W_ROT,
    W_V3,
    W_VEL,
)
from massprops.dynamics.compiled.unowned import at

FIXED, REVOLUTE, PRISMATIC, CYLINDRICAL, UNIVERSAL, SPHERICAL, FREE = range(7)
"""Joint kind codes of a system program (`dynamics.systems.program.KIND`)."""


@inlined
def cross_into(out, a, b):
    x = a[1] * b[2] - a[2] * b[1]
    y = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    out[0], out[1] = x, y


@inlined
def rot_into(out, a, angle):
    """out = Rot(a, angle), a unit (Rodrigues: c E + s ã + (1 - c) a aᵀ)."""
    s, c = math.sin(angle), math.cos(angle)
    v = 1.0 - c
    x, y, z = a[0], a[1], a[2]
    out[0, 0], out[0, 1], out[0, 2] = c + x * x * v, x * y * v - z * s, x * z * v + y * s
    out[1, 0], out[1, 1], out[1, 2] = y * x * v + z * s, c + y * y * v, y * z * v - x * s
    out[2, 0], out[2, 1], out[2, 2] = z * x * v - y * s, z * y * v + x * s, c + z * z * v


@inlined
def turn_between(pr, world, a, angle, kc, out):
    """out = P Rot(a, angle) K (a unit; P = ``pr``, or E where ``world``; K = ``kc``), row by
    row in scalars: no scratch matrix is stored and loaded back (see `poses`)."""
    s, c = math.sin(angle), math.cos(angle)
    v = 1.0 - c
    x, y, z = a[0], a[1], a[2]
    q00, q01, q02 = c + x * x * v, x * y * v - z * s, x * z * v + y * s
    q10, q11, q12 = y * x * v + z * s, c + y * y * v, y * z * v - x * s
    q20, q21, q22 = z * x * v - y * s, z * y * v + x * s, c + z * z * v
    for i in range(3):
        if world:
            m0, m1, m2 = (q00, q01, q02) if i == 0 else ((q10, q11, q12) if i == 1
                                                           else (q20, q21, q22))
        else:
            p0, p1, p2 = pr[i, 0], pr[i, 1], pr[i, 2]
            m0 = p0 * q00 + p1 * q10 + p2 * q20
            m1 = p0 * q01 + p1 * q11 + p2 * q21
            m2 = p0 * q02 + p1 * q12 + p2 * q22
        out[i, 0] = m0 * kc[0, 0] + m1 * kc[1, 0] + m2 * kc[2, 0]
        out[i, 1] = m0 * kc[0, 1] + m1 * kc[1, 1] + m2 * kc[2, 1]
        out[i, 2] = m0 * kc[0, 2] + m1 * kc[1, 2] + m2 * kc[2, 2]


@inlined
def quat_into(out, q, o):
    """out = the rotation of the quaternion q[o:o + 4] = [w, x, y, z] (normalised here)."""
    n = math.sqrt(q[o] ** 2 + q[o + 1] ** 2 + q[o + 2] ** 2 + q[o + 3] ** 2)
    w, x, y, z = q[o] / n, q[o + 1] / n, q[o + 2] / n, q[o + 3] / n
    out[0, 0], out[0, 1] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z)
    out[0, 2], out[1, 0] = 2 * (x * z + w * y), 2 * (x * y + w * z)
    out[1, 1], out[1, 2] = 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    out[2, 0], out[2, 1] = 2 * (x * z - w * y), 2 * (y * z + w * x)
    out[2, 2] = 1 - 2 * (x * x + y * y)


@inlined
def mm3(a, b, out, bt):
    """out = a b (bt: a bᵀ)."""
    for i in range(3):
        for j in range(3):
            s = 0.0
            for k in range(3):
                s += a[i, k] * (b[j, k] if bt else b[k, j])
            out[i, j] = s


@inlined
def motion_cross(v, m, out):
    """out = v ×m m (spatial motions (ω, v_O)), out not v or m."""
    out[0] = v[1] * m[2] - v[2] * m[1]
    out[1] = v[2] * m[0] - v[0] * m[2]
    out[2] = v[0] * m[1] - v[1] * m[0]
    out[3] = v[4] * m[2] - v[5] * m[1] + v[1] * m[5] - v[2] * m[4]
    out[4] = v[5] * m[0] - v[3] * m[2] + v[2] * m[3] - v[0] * m[5]
    out[5] = v[3] * m[1] - v[4] * m[0] + v[0] * m[4] - v[1] * m[3]


@inlined
def _column(s, col, w, px, py, pz, turning):
    """S column ``col``: a turn about w through p, (w, p × w), or a shift along w, (0, w)."""
    if turning:
        s[0, col], s[1, col], s[2, col] = w[0], w[1], w[2]
        s[3, col] = py * w[2] - pz * w[1]
        s[4, col] = pz * w[0] - px * w[2]
        s[5, col] = px * w[1] - py * w[0]
    else:
        s[0, col] = s[1, col] = s[2, col] = 0.0
        s[3, col], s[4, col], s[5, col] = w[0], w[1], w[2]


@array_inner
def kinematics(pp, q, u, wp):
    """Per body: R, com, V and A at u̇ = 0 (with the joint's own bias term in ``cb``), the
    inertia about O (`inertia_about_origin`'s ten numbers); per dof a column of S; per joint
    its point (world); q itself where the system has couplings (`W_Q`, for
    `systems_loops.terms`): `poses`, then `motion` (called, not inlined: `poses` alone takes
    ~17 s to compile, and a copy inlined here would cost that again)."""
    poses(pp, q, wp)
    motion(pp, u, wp)


@array_inner
def poses(pp, q, wp):
    """What `kinematics` computes from q alone: R, com, inertia, S, joint points (and q). The
    parent's pose is read in place and the child's rotation and inertia built in scalars, not
    through scratch arrays: numba cannot tell that a store into one float array leaves another
    alone, so each copied value was loaded again at every use (with `motion`'s scalars, the
    four-bar's kinematics 767 → 365 ns)."""
    ji, jsp, jsc = at(pp, P_JOINTS), at(pp, P_S_PARENT), at(pp, P_S_CHILD)
    jrp0 = at(pp, P_ROT_PARENT0)
    bmass, binertia, brot0 = at(pp, P_MASS), at(pp, P_INERTIA), at(pp, P_ROTATION0)
    bcom0 = at(pp, P_COM0)
    jaxp, jrc0 = at(pp, P_AXES_PARENT), at(pp, P_TURN0)
    rot, com, inert, s = at(wp, W_ROT), at(wp, W_COM), at(wp, W_INERTIA), at(wp, W_MOTION)
    pts = at(wp, W_JOINT_POINTS)
    ref = at(wp, W_REFERENCE)  # the point positions are measured from (`tree.reference_point`)
    ref[0] = ref[1] = ref[2] = 0.0
    for k in range(ji.shape[0]):
        if ji[k, 0] == FREE:
            ref[0], ref[1], ref[2] = q[ji[k, 3]], q[ji[k, 3] + 1], q[ji[k, 3] + 2]
            break
    m3, v3 = at(wp, W_M3), at(wp, W_V3)
    carry, qm, tmp, rp = m3[0], m3[1], m3[2], m3[3]
    d, w = v3[0], v3[2]
    qc = at(wp, W_Q)  # the coordinates, for the couplings' rows (sized 0 without couplings)
    for i in range(qc.size):
        qc[i] = q[i]
    for k in range(ji.shape[0]):
        kind, par, ch, iq, iu = ji[k, 0], ji[k, 1], ji[k, 2], ji[k, 3], ji[k, 4]
        if kind == FREE:  # the world's child
            quat_into(qm, q, iq + 3)
            mm3(qm, brot0[ch], rot[ch], False)
            px = bcom0[ch, 0] + (q[iq] - ref[0])
            py = bcom0[ch, 1] + (q[iq + 1] - ref[1])
            pz = bcom0[ch, 2] + (q[iq + 2] - ref[2])
            com[ch, 0], com[ch, 1], com[ch, 2] = px, py, pz
            for c in range(6):
                for i in range(6):
                    s[i, iu + c] = 0.0
            for i in range(3):  # ω = Q u: rates that turn with the body (`tree`)
                s[3 + i, iu + i] = 1.0
                for j in range(3):
                    w[j] = qm[j, i]
                _column(s, iu + 3 + i, w, px, py, pz, True)
        else:
            pr = rot[par if par >= 0 else 0]  # the parent's R (unread for the world's children)
            if par >= 0:  # the joint point
                px = com[par, 0] + pr[0, 0] * jsp[k, 0] + pr[0, 1] * jsp[k, 1] \
                    + pr[0, 2] * jsp[k, 2]
                py = com[par, 1] + pr[1, 0] * jsp[k, 0] + pr[1, 1] * jsp[k, 1] \
                    + pr[1, 2] * jsp[k, 2]
                pz = com[par, 2] + pr[2, 0] * jsp[k, 0] + pr[2, 1] * jsp[k, 1] \
                    + pr[2, 2] * jsp[k, 2]
            else:  # a world point, seen from the reference point
                px, py, pz = jsp[k, 0] - ref[0], jsp[k, 1] - ref[1], jsp[k, 2] - ref[2]
            if kind == SPHERICAL:  # through the joint frame; S's columns turn with the child
                jr = jrp0[k]
                if par >= 0:
                    mm3(pr, jr, carry, True)
                else:
                    for i in range(3):
                        for j in range(3):
                            carry[i, j] = jr[j, i]
                quat_into(qm, q, iq)
                mm3(carry, qm, rp, False)
                mm3(rp, brot0[ch], rot[ch], False)
                for c in range(3):
                    for i in range(3):
                        w[i] = rp[i, c]
                    _column(s, iu + c, w, px, py, pz, True)
            else:  # in the parent's frame (program entries 25 and 26)
                a0, a1, kc = jaxp[k, 0], jaxp[k, 1], jrc0[k]
                if kind == UNIVERSAL:
                    rot_into(tmp, a0, q[iq])
                    rot_into(rp, a1, q[iq + 1])
                    mm3(tmp, rp, qm, False)  # R(a0, q0) R(a1, q1)
                    if par >= 0:
                        mm3(pr, qm, rp, False)
                        mm3(rp, kc, rot[ch], False)
                    else:
                        mm3(qm, kc, rot[ch], False)
                else:  # revolute, cylindrical: a turn about a0; prismatic, fixed: none
                    turning = kind == REVOLUTE or kind == CYLINDRICAL
                    turn_between(pr, par < 0, a0, q[iq] if turning else 0.0, kc, rot[ch])
                for i in range(3):  # the first axis in the world
                    w[i] = (pr[i, 0] * a0[0] + pr[i, 1] * a0[1] + pr[i, 2] * a0[2]) \
                        if par >= 0 else a0[i]
                if kind == PRISMATIC or kind == CYLINDRICAL:  # the shift q a along that axis
                    x = q[iq + 1] if kind == CYLINDRICAL else q[iq]
                    px, py, pz = px + x * w[0], py + x * w[1], pz + x * w[2]
                if kind != FIXED:
                    _column(s, iu, w, px, py, pz, kind != PRISMATIC)
                if kind == CYLINDRICAL:
                    _column(s, iu + 1, w, px, py, pz, False)
                elif kind == UNIVERSAL:  # the second axis, turned by the first turn
                    for i in range(3):
                        d[i] = tmp[i, 0] * a1[0] + tmp[i, 1] * a1[1] + tmp[i, 2] * a1[2]
                    for i in range(3):
                        w[i] = (pr[i, 0] * d[0] + pr[i, 1] * d[1] + pr[i, 2] * d[2]) \
                            if par >= 0 else d[i]
                    _column(s, iu + 1, w, px, py, pz, True)
            rc = rot[ch]
            for i in range(3):
                com[ch, i] = (px if i == 0 else (py if i == 1 else pz)) - rc[i, 0] * jsc[k, 0] \
                    - rc[i, 1] * jsc[k, 1] - rc[i, 2] * jsc[k, 2]
        pts[k, 0], pts[k, 1], pts[k, 2] = px, py, pz
        inertia_about_origin(bmass[ch], binertia[ch], rot[ch], com[ch], inert[ch])


@array_inner
def motion(pp, u, wp):
    """What `kinematics` computes from u, after `poses`: V, A at u̇ = 0 and ``cb``, per joint
    from its parent's V and A (the world's: 0) and its S columns."""
    ji = at(pp, P_JOINTS)
    vel, acc, s, cb = at(wp, W_VEL), at(wp, W_ACC), at(wp, W_MOTION), at(wp, W_BIAS)
    v6 = at(wp, W_M6)
    c0, c1, su = v6[4], v6[5], v6[2]
    for k in range(ji.shape[0]):
        kind, par, ch, iu, nvj = ji[k, 0], ji[k, 1], ji[k, 2], ji[k, 4], ji[k, 6]
        if par >= 0:
            v0, v1, v2, v3_, v4, v5 = vel[par, 0], vel[par, 1], vel[par, 2], vel[par, 3], \
                vel[par, 4], vel[par, 5]
            e0, e1, e2, e3, e4, e5 = acc[par, 0], acc[par, 1], acc[par, 2], acc[par, 3], \
                acc[par, 4], acc[par, 5]
        else:
            v0 = v1 = v2 = v3_ = v4 = v5 = 0.0
            e0 = e1 = e2 = e3 = e4 = e5 = 0.0
        m0 = m1 = m2 = m3_ = m4 = m5 = 0.0  # the joint's motion S u
        for c in range(nvj):
            x = u[iu + c]
            m0 += s[0, iu + c] * x
            m1 += s[1, iu + c] * x
            m2 += s[2, iu + c] * x
            m3_ += s[3, iu + c] * x
            m4 += s[4, iu + c] * x
            m5 += s[5, iu + c] * x
        if kind == FREE:  # the world's child: its bias v_c × ω (u = [v_c, ·], ω = S u's)
            b0 = b1 = b2 = 0.0
            b3 = u[iu + 1] * m2 - u[iu + 2] * m1
            b4 = u[iu + 2] * m0 - u[iu] * m2
            b5 = u[iu] * m1 - u[iu + 1] * m0
        else:  # the bias V_parent ×m S u
            b0 = v1 * m2 - v2 * m1
            b1 = v2 * m0 - v0 * m2
            b2 = v0 * m1 - v1 * m0
            b3 = v4 * m2 - v5 * m1 + v1 * m5 - v2 * m4
            b4 = v5 * m0 - v3_ * m2 + v2 * m3_ - v0 * m5
            b5 = v3_ * m1 - v4 * m0 + v0 * m4 - v1 * m3_
            if kind == UNIVERSAL:  # and the first column's motion ×m the second's
                for i in range(6):
                    c0[i] = s[i, iu] * u[iu]
                    su[i] = s[i, iu + 1] * u[iu + 1]
                motion_cross(c0, su, c1)
                b0, b1, b2 = b0 + c1[0], b1 + c1[1], b2 + c1[2]
                b3, b4, b5 = b3 + c1[3], b4 + c1[4], b5 + c1[5]
        vel[ch, 0], vel[ch, 1], vel[ch, 2] = v0 + m0, v1 + m1, v2 + m2
        vel[ch, 3], vel[ch, 4], vel[ch, 5] = v3_ + m3_, v4 + m4, v5 + m5
        cb[ch, 0], cb[ch, 1], cb[ch, 2], cb[ch, 3], cb[ch, 4], cb[ch, 5] = b0, b1, b2, b3, b4, b5
        acc[ch, 0], acc[ch, 1], acc[ch, 2] = e0 + b0, e1 + b1, e2 + b2
        acc[ch, 3], acc[ch, 4], acc[ch, 5] = e3 + b3, e4 + b4, e5 + b5


INERTIA_SIZE = 10
"""A body's inertia about the world origin O as ten numbers [m, h (3), J_O (6)]: its mass, the
first moment h = m c (world, c the centre of mass) and the inertia tensor about O in world
axes, J_O = J_w − m c̃c̃, as [xx, yy, zz, xy, xz, yz]. The spatial inertia they stand for is
[[J_O, h̃], [−h̃, m E]] (`spatial_times`); the 36 entries of the 6 × 6 matrix take three times
the products."""


@inlined
def inertia_about_origin(mass, inertia, r, c, out):
    """out (10,) = the body's inertia about O (`INERTIA_SIZE`), from its mass, its inertia
    about its centre of mass in body axes (symmetric), R (body → world) and c (world):
    J_w = (R J) Rᵀ, in scalars, of J's symmetric part (a given J may be off by the tolerance
    `model.RigidBody` allows)."""
    j00, j11, j22 = inertia[0, 0], inertia[1, 1], inertia[2, 2]
    j01 = 0.5 * (inertia[0, 1] + inertia[1, 0])
    j02 = 0.5 * (inertia[0, 2] + inertia[2, 0])
    j12 = 0.5 * (inertia[1, 2] + inertia[2, 1])
    r00, r01, r02 = r[0, 0], r[0, 1], r[0, 2]
    r10, r11, r12 = r[1, 0], r[1, 1], r[1, 2]
    r20, r21, r22 = r[2, 0], r[2, 1], r[2, 2]
    t00 = r00 * j00 + r01 * j01 + r02 * j02  # T = R J
    t01 = r00 * j01 + r01 * j11 + r02 * j12
    t02 = r00 * j02 + r01 * j12 + r02 * j22
    t10 = r10 * j00 + r11 * j01 + r12 * j02
    t11 = r10 * j01 + r11 * j11 + r12 * j12
    t12 = r10 * j02 + r11 * j12 + r12 * j22
    t20 = r20 * j00 + r21 * j01 + r22 * j02
    t21 = r20 * j01 + r21 * j11 + r22 * j12
    t22 = r20 * j02 + r21 * j12 + r22 * j22
    cx, cy, cz = c[0], c[1], c[2]
    cc = cx * cx + cy * cy + cz * cz
    out[0] = mass
    out[1], out[2], out[3] = mass * cx, mass * cy, mass * cz
    # J_O = T Rᵀ - m c̃c̃, c̃c̃ = c cᵀ - |c|² E: [xx, yy, zz, xy, xz, yz]
    out[4] = t00 * r00 + t01 * r01 + t02 * r02 - mass * (cx * cx - cc)
    out[5] = t10 * r10 + t11 * r11 + t12 * r12 - mass * (cy * cy - cc)
    out[6] = t20 * r20 + t21 * r21 + t22 * r22 - mass * (cz * cz - cc)
    out[7] = t00 * r10 + t01 * r11 + t02 * r12 - mass * (cx * cy)
    out[8] = t00 * r20 + t01 * r21 + t02 * r22 - mass * (cx * cz)
    out[9] = t10 * r20 + t11 * r21 + t12 * r22 - mass * (cy * cz)


@inlined
def spatial_times(ii, v0, v1, v2, v3, v4, v5):
    """The spatial inertia ``ii`` (`INERTIA_SIZE`) times the motion (ω, v_O) = (v0..v5): the
    momentum (J_O ω + h × v, m v − h × ω), as six floats."""
    m, hx, hy, hz = ii[0], ii[1], ii[2], ii[3]
    return (ii[4] * v0 + ii[7] * v1 + ii[8] * v2 + (hy * v5 - hz * v4),
            ii[7] * v0 + ii[5] * v1 + ii[9] * v2 + (hz * v3 - hx * v5),
            ii[8] * v0 + ii[9] * v1 + ii[6] * v2 + (hx * v4 - hy * v3),
            m * v3 - (hy * v2 - hz * v1),
            m * v4 - (hz * v0 - hx * v2),
            m * v5 - (hx * v1 - hy * v0))


@inlined
def spatial_matrix(ii, out):
    """out (6, 6) = the spatial inertia ``ii`` (`INERTIA_SIZE`) written out."""
    m, hx, hy, hz = ii[0], ii[1], ii[2], ii[3]
    out[0, 0], out[1, 1], out[2, 2] = ii[4], ii[5], ii[6]
    out[0, 1] = out[1, 0] = ii[7]
    out[0, 2] = out[2, 0] = ii[8]
    out[1, 2] = out[2, 1] = ii[9]
    for i in range(3):
        for j in range(3):
            out[3 + i, 3 + j] = m if i == j else 0.0
    out[0, 3], out[0, 4], out[0, 5] = 0.0, -hz, hy  # h̃
    out[1, 3], out[1, 4], out[1, 5] = hz, 0.0, -hx
    out[2, 3], out[2, 4], out[2, 5] = -hy, hx, 0.0
    out[3, 0], out[3, 1], out[3, 2] = 0.0, hz, -hy  # -h̃
    out[4, 0], out[4, 1], out[4, 2] = -hz, 0.0, hx
    out[5, 0], out[5, 1], out[5, 2] = hy, -hx, 0.0
