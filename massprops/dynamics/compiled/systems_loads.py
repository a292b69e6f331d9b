"""A system program's applied loads, compiled: gravity, body forces and torques (with their time
windows), springs between bodies, the tree joints' springs, dampers and drives, and the cut
joints' as wrench pairs on their two bodies (`systems.cutjoint`), as in
`dynamics.systems.system.System.applied` (spatial forces about O on each body, world, and
generalised loads on the joints)."""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_layout import (
    P_CUT_LOAD_VALUES,
    P_CUT_LOADS,
    P_FORCE_VALUES,
    P_FORCES,
    P_JOINTS,
    P_LOADED,
    P_LOADED_VALUES,
    P_SPRING_VALUES,
    P_SPRINGS,
    P_WEIGHT,
    W_COM,
    W_LOADS,
    W_REFERENCE,
    W_ROT,
    W_TAU,
    W_V3,
    W_VEL,
)
from massprops.dynamics.compiled.systems_tree import cross_into
from massprops.dynamics.compiled.unowned import at


@array_inner
def applied(pp, t, q, u, wp):
    """fext (n, 6) spatial forces about O on each body and τ (nv,) joint loads (System.applied)."""
    ji, bweight = at(pp, P_JOINTS), at(pp, P_WEIGHT)
    fi, ff, si = at(pp, P_FORCES), at(pp, P_FORCE_VALUES), at(pp, P_SPRINGS)
    sf, li, lf = at(pp, P_SPRING_VALUES), at(pp, P_LOADED), at(pp, P_LOADED_VALUES)
    rot, com, vel, fext = at(wp, W_ROT), at(wp, W_COM), at(wp, W_VEL), at(wp, W_LOADS)
    tau = at(wp, W_TAU)
    ref = at(wp, W_REFERENCE)
    v3 = at(wp, W_V3)
    vec, x, xa, xb = v3[0], v3[1], v3[2], v3[3]
    va, vb, dd, force = v3[4], v3[5], v3[6], v3[7]
    for i in range(com.shape[0]):
        cross_into(x, com[i], bweight[i])
        for j in range(3):
            fext[i, j] = x[j]
            fext[i, 3 + j] = bweight[i, j]
    for f in range(fi.shape[0]):
        if not ff[f, 6] <= t < ff[f, 7]:
            continue
        b = fi[f, 1]
        if fi[f, 0] == 2:  # drag, in the world frame (`falling` leaves a dragged system there)
            _drag(ff[f, 0], ff[f, 1], com[b], vel[b], fext[b], x, vec)
            continue
        for i in range(3):
            vec[i] = ff[f, i]
            if fi[f, 2]:  # body frame
                vec[i] = rot[b, i, 0] * ff[f, 0] + rot[b, i, 1] * ff[f, 1] + rot[b, i, 2] * ff[f, 2]
        if fi[f, 0] == 1:  # a torque
            for i in range(3):
                fext[b, i] += vec[i]
            continue
        for i in range(3):
            x[i] = com[b, i]
            if fi[f, 3]:  # applied at a point
                x[i] += rot[b, i, 0] * ff[f, 3] + rot[b, i, 1] * ff[f, 4] + rot[b, i, 2] * ff[f, 5]
        cross_into(xa, x, vec)
        for i in range(3):
            fext[b, i] += xa[i]
            fext[b, 3 + i] += vec[i]
    for n in range(si.shape[0]):
        _point_state(rot, com, vel, ref, si[n, 0], sf[n, 0:3], xa, va)
        _point_state(rot, com, vel, ref, si[n, 1], sf[n, 3:6], xb, vb)
        for i in range(3):
            x[i] = xb[i] - xa[i]
            dd[i] = vb[i] - va[i]
        k, rest, damping = sf[n, 6], sf[n, 7], sf[n, 8]
        if rest == 0.0:
            for i in range(3):
                force[i] = -k * x[i] - damping * dd[i]
        else:
            length = math.sqrt(x[0] ** 2 + x[1] ** 2 + x[2] ** 2)
            for i in range(3):
                vec[i] = x[i] / length if length > 0 else 0.0
            mag = -k * (length - rest) - damping * (vec[0] * dd[0] + vec[1] * dd[1]
                                                   + vec[2] * dd[2])
            for i in range(3):
                force[i] = mag * vec[i]
        for side in range(2):
            body = si[n, 1 - side]
            sign = 1.0 if side == 0 else -1.0
            if body < 0:
                continue
            cross_into(vec, xb if side == 0 else xa, force)
            for i in range(3):
                fext[body, i] += sign * vec[i]
                fext[body, 3 + i] += sign * force[i]
    for i in range(tau.shape[0]):
        tau[i] = 0.0
    for n in range(li.shape[0]):
        k = li[n]
        sign = -1.0 if ji[k, 7] else 1.0
        coord, rate = sign * q[ji[k, 3]], sign * u[ji[k, 4]]
        load = -lf[n, 0] * (coord - lf[n, 1]) - lf[n, 2] * rate
        if lf[n, 4] <= t < lf[n, 5]:
            load += lf[n, 3]
        tau[ji[k, 4]] += sign * load
    _cut_loads(at(pp, P_CUT_LOADS), at(pp, P_CUT_LOAD_VALUES), t, rot, com, vel, ref, fext, v3)


@array_inner
def _cut_loads(ci, cf, t, rot, com, vel, ref, fext, v3):
    """The loaded cut joints' wrench pairs into fext (`systems.cutjoint`; ci, cf: program
    entries 21 and 22)."""
    e, sa, sb, xa, xb, va, vb, x = v3[8], v3[9], v3[10], v3[11], v3[12], v3[13], v3[14], v3[15]
    for n in range(ci.shape[0]):
        a, b = ci[n, 1], ci[n, 2]
        _turned(rot, a, cf[n, 0:3], e)
        _point_state(rot, com, vel, ref, a, cf[n, 9:12], xa, va)
        _point_state(rot, com, vel, ref, b, cf[n, 12:15], xb, vb)
        rate = 0.0
        for i in range(3):
            rate += ((vel[b, i] if b >= 0 else 0.0) - (vel[a, i] if a >= 0 else 0.0)) * e[i]
        if ci[n, 0] == 0:  # revolute: the turn from a's normal to b's about e
            _turned(rot, a, cf[n, 3:6], sa)
            _turned(rot, b, cf[n, 6:9], sb)
            da = sa[0] * e[0] + sa[1] * e[1] + sa[2] * e[2]
            db = sb[0] * e[0] + sb[1] * e[1] + sb[2] * e[2]
            for i in range(3):
                sa[i] -= da * e[i]
                sb[i] -= db * e[i]
            cross_into(x, sa, sb)
            turn = math.atan2(x[0] * e[0] + x[1] * e[1] + x[2] * e[2],
                              sa[0] * sb[0] + sa[1] * sb[1] + sa[2] * sb[2])
            d = turn - cf[n, 16]
            d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
        else:  # prismatic: the shift (x_b − x_a)·e and its rate
            if a >= 0:
                cross_into(sa, vel[a, 0:3], e)  # ω_a × e
            else:
                for i in range(3):
                    sa[i] = 0.0
            d, rate = -cf[n, 16], 0.0
            for i in range(3):
                d += (xb[i] - xa[i]) * e[i]
                rate += (vb[i] - va[i]) * e[i] + (xb[i] - xa[i]) * sa[i]
        load = -cf[n, 15] * d - cf[n, 17] * rate
        if cf[n, 19] <= t < cf[n, 20]:
            load += cf[n, 18]
        if ci[n, 0] == 0:
            for i in range(3):
                x[i], sb[i] = load * e[i], 0.0
        else:
            cross_into(x, xb, e)
            for i in range(3):
                x[i] *= load
                sb[i] = load * e[i]
        for i in range(3):
            if b >= 0:
                fext[b, i] += x[i]
                fext[b, 3 + i] += sb[i]
            if a >= 0:
                fext[a, i] -= x[i]
                fext[a, 3 + i] -= sb[i]


@inlined
def _drag(linear, angular, c, v, out, x, force):
    """Adds a drag's spatial force about O to ``out`` (6,): −linear v_c at the centre ``c``
    and −angular ω, v = (ω, v_O) the body's spatial velocity."""
    force[0] = -linear * (v[3] + v[1] * c[2] - v[2] * c[1])
    force[1] = -linear * (v[4] + v[2] * c[0] - v[0] * c[2])
    force[2] = -linear * (v[5] + v[0] * c[1] - v[1] * c[0])
    cross_into(x, c, force)
    for i in range(3):
        out[i] += x[i] - angular * v[i]
        out[3 + i] += force[i]


@inlined
def _turned(rot, body, local, out):
    """out = R_body local (the world's vectors are world already)."""
    for i in range(3):
        out[i] = local[i] if body < 0 else (rot[body, i, 0] * local[0] + rot[body, i, 1]
                                            * local[1] + rot[body, i, 2] * local[2])


@inlined
def _point_state(rot, com, vel, ref, body, local, x, v):
    """World position (from the reference point ``ref``, as ``com``) and velocity of a body
    point (the world's points are world already)."""
    if body < 0:
        for i in range(3):
            x[i], v[i] = local[i] - ref[i], 0.0
        return
    for i in range(3):
        x[i] = com[body, i] + rot[body, i, 0] * local[0] + rot[body, i, 1] * local[1] \
            + rot[body, i, 2] * local[2]
    w = vel[body]
    v[0] = vel[body, 3] + w[1] * x[2] - w[2] * x[1]
    v[1] = vel[body, 4] + w[2] * x[0] - w[0] * x[2]
    v[2] = vel[body, 5] + w[0] * x[1] - w[1] * x[0]
