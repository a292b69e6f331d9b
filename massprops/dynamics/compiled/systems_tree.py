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
def force_cross(v, f, out):
    """out = v ×f f (a spatial motion v, a force f = (n_O, f)), out not v or f."""
    out[0] = v[1] * f[2] - v[2] * f[1] + v[4] * f[5] - v[5] * f[4]
    out[1] = v[2] * f[0] - v[0] * f[2] + v[5] * f[3] - v[3] * f[5]
    out[2] = v[0] * f[1] - v[1] * f[0] + v[3] * f[4] - v[4] * f[3]
    out[3] = v[1] * f[5] - v[2] * f[4]
    out[4] = v[2] * f[3] - v[0] * f[5]
    out[5] = v[0] * f[4] - v[1] * f[3]


@inlined
def _column(s, col, w, p, turning):
    """S column ``col``: a turn about w through p, (w, p × w), or a shift along w, (0, w)."""
    if turning:
        s[0, col], s[1, col], s[2, col] = w[0], w[1], w[2]
        s[3, col] = p[1] * w[2] - p[2] * w[1]
        s[4, col] = p[2] * w[0] - p[0] * w[2]
        s[5, col] = p[0] * w[1] - p[1] * w[0]
    else:
        s[0, col] = s[1, col] = s[2, col] = 0.0
        s[3, col], s[4, col], s[5, col] = w[0], w[1], w[2]


@array_inner
def kinematics(pp, q, u, wp):
    """Per body: R, com, V and A at u̇ = 0 (with the joint's own bias term in ``cb``), the
    spatial inertia about O; per dof a column of S; per joint its point (world); q itself
    where the system has couplings (ws[34], for `systems_loops.terms`)."""
    ji, jaxes, jsp, jsc, jrp0 = at(pp, 1), at(pp, 2), at(pp, 3), at(pp, 4), at(pp, 5)
    bmass, binertia, brot0, bcom0 = at(pp, 7), at(pp, 8), at(pp, 9), at(pp, 10)
    rot, com, vel, acc = at(wp, 0), at(wp, 1), at(wp, 2), at(wp, 3)
    sp, s, pts, cb = at(wp, 4), at(wp, 5), at(wp, 6), at(wp, 7)
    m3, v3, v6 = at(wp, 8), at(wp, 9), at(wp, 10)
    carry, qm, tmp, rp = m3[0], m3[1], m3[2], m3[3]
    d, p, w, cp = v3[0], v3[1], v3[2], v3[3]
    vp, ap, su, b2, c0, c1 = v6[0], v6[1], v6[2], v6[3], v6[4], v6[5]
    qc = at(wp, 34)  # the coordinates, for the couplings' rows (sized 0 without couplings)
    for i in range(qc.size):
        qc[i] = q[i]
    for k in range(ji.shape[0]):
        kind, par, ch, iq, iu, nvj = ji[k, 0], ji[k, 1], ji[k, 2], ji[k, 3], ji[k, 4], ji[k, 6]
        for i in range(3):
            cp[i] = com[par, i] if par >= 0 else 0.0
            for j in range(3):
                rp[i, j] = rot[par, i, j] if par >= 0 else (1.0 if i == j else 0.0)
        for i in range(6):
            vp[i] = vel[par, i] if par >= 0 else 0.0
            ap[i] = acc[par, i] if par >= 0 else 0.0
            b2[i] = 0.0
        if kind == FREE:
            quat_into(qm, q, iq + 3)
            mm3(qm, brot0[ch], rot[ch], False)
            for i in range(3):
                com[ch, i] = bcom0[ch, i] + q[iq + i]
                p[i] = com[ch, i]
            for c in range(6):
                for i in range(6):
                    s[i, iu + c] = 0.0
            for i in range(3):
                s[3 + i, iu + i] = 1.0
                for j in range(3):
                    w[j] = 1.0 if i == j else 0.0
                _column(s, iu + 3 + i, w, p, True)
            cross_into(w, u[iu:iu + 3], u[iu + 3:iu + 6])
            b2[3], b2[4], b2[5] = w[0], w[1], w[2]
        else:
            mm3(rp, jrp0[k], carry, True)
            for i in range(3):
                d[i] = 0.0
            a0, a1 = jaxes[k, 0], jaxes[k, 1]
            if kind == REVOLUTE or kind == CYLINDRICAL:
                rot_into(qm, a0, q[iq])
                if kind == CYLINDRICAL:
                    for i in range(3):
                        d[i] = q[iq + 1] * a0[i]
            elif kind == UNIVERSAL:
                rot_into(tmp, a0, q[iq])
                rot_into(qm, a1, q[iq + 1])
                mm3(tmp, qm, rp, False)  # rp is free again: R(a0, q0) R(a1, q1)
                for i in range(3):
                    for j in range(3):
                        qm[i, j] = rp[i, j]
            elif kind == SPHERICAL:
                quat_into(qm, q, iq)
            else:  # prismatic, fixed
                for i in range(3):
                    for j in range(3):
                        qm[i, j] = 1.0 if i == j else 0.0
                if kind == PRISMATIC:
                    for i in range(3):
                        d[i] = q[iq] * a0[i]
            mm3(carry, qm, rp, False)
            mm3(rp, brot0[ch], rot[ch], False)
            for i in range(3):
                p[i] = cp[i]
                for j in range(3):
                    p[i] += (rot[par, i, j] if par >= 0 else (1.0 if i == j else 0.0)) * jsp[k, j] \
                        + carry[i, j] * d[j]
            for i in range(3):
                com[ch, i] = p[i]
                for j in range(3):
                    com[ch, i] -= rot[ch, i, j] * jsc[k, j]
            if kind == SPHERICAL:
                for c in range(3):
                    for i in range(3):
                        w[i] = carry[i, c]
                    _column(s, iu + c, w, p, True)
            elif kind != FIXED:
                for i in range(3):
                    w[i] = carry[i, 0] * a0[0] + carry[i, 1] * a0[1] + carry[i, 2] * a0[2]
                _column(s, iu, w, p, kind != PRISMATIC)
                if kind == CYLINDRICAL:
                    _column(s, iu + 1, w, p, False)
                elif kind == UNIVERSAL:
                    for i in range(3):
                        d[i] = tmp[i, 0] * a1[0] + tmp[i, 1] * a1[1] + tmp[i, 2] * a1[2]
                    for i in range(3):
                        w[i] = carry[i, 0] * d[0] + carry[i, 1] * d[1] + carry[i, 2] * d[2]
                    _column(s, iu + 1, w, p, True)
            for i in range(6):
                su[i] = 0.0
                for c in range(nvj):
                    su[i] += s[i, iu + c] * u[iu + c]
            motion_cross(vp, su, b2)
            if kind == UNIVERSAL:
                for i in range(6):
                    c0[i] = s[i, iu] * u[iu]
                    su[i] = s[i, iu + 1] * u[iu + 1]
                motion_cross(c0, su, c1)
                for i in range(6):
                    b2[i] += c1[i]
        for i in range(3):
            pts[k, i] = p[i]
        for i in range(6):
            v = vp[i]
            for c in range(nvj):
                v += s[i, iu + c] * u[iu + c]
            vel[ch, i] = v
            cb[ch, i] = b2[i]
            acc[ch, i] = ap[i] + b2[i]
        _spatial_inertia(bmass[ch], binertia[ch], rot[ch], com[ch], sp[ch], tmp)


@inlined
def _spatial_inertia(mass, inertia, r, c, out, tmp):
    """out (6, 6) about O: [[J_w - m c̃c̃, m c̃], [-m c̃, m E]], J_w = R J Rᵀ (as (R J) Rᵀ)."""
    for i in range(3):
        for k in range(3):
            tmp[i, k] = r[i, 0] * inertia[0, k] + r[i, 1] * inertia[1, k] \
                + r[i, 2] * inertia[2, k]
    cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
    for i in range(3):
        for j in range(3):
            # c̃c̃ = c cᵀ - |c|² E
            out[i, j] = tmp[i, 0] * r[j, 0] + tmp[i, 1] * r[j, 1] + tmp[i, 2] * r[j, 2] \
                - mass * (c[i] * c[j] - (cc if i == j else 0.0))
            out[3 + i, 3 + j] = mass if i == j else 0.0
    mx, my, mz = mass * c[0], mass * c[1], mass * c[2]
    out[0, 3], out[0, 4], out[0, 5] = 0.0, -mz, my  # m c̃
    out[1, 3], out[1, 4], out[1, 5] = mz, 0.0, -mx
    out[2, 3], out[2, 4], out[2, 5] = -my, mx, 0.0
    out[3, 0], out[3, 1], out[3, 2] = 0.0, mz, -my  # -m c̃
    out[4, 0], out[4, 1], out[4, 2] = -mz, 0.0, mx
    out[5, 0], out[5, 1], out[5, 2] = my, -mx, 0.0
