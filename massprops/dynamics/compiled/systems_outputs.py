"""What a system run reports at its samples, compiled: body poses and motions, the scene joints'
reactions and points, the loops' residuals, the energy, for every sample of a run in one call of
its own compiled entry (`systems_kernel.evaluate_samples` with a mode of this module).

The numbers of the numpy path (`dynamics.systems.outputs.reference`, `System.energy`), which
stays as the independent reference of the tests; its module doc gives the reactions' rule.
Reactions use the multipliers of least norm, λ = U Σ⁺² Uᵀ r, r = −Φ̈₀ − G M⁻¹ (τ − h) (`System.
solve`), from the SVD of B's independent rows (`systems_loops.decompose`).

Each row of ``out`` is one sample (mode OUTPUTS): per body (program order) ``BODY_COLUMNS``
[com (3) m, R (9, row by row) body → world, V = (ω, v_O) (6) rad/s, m/s], all world, positions
about the system's origin (`assemble.localized`); then per scene joint ``JOINT_COLUMNS``
[force (3) N, torque (3) N·m on its second body about its point, that point (3) m]; then the
largest |Φ| (m) and |G u| (m/s). STATES writes the body columns only (no accelerations),
ENERGIES one column, the energy (J). A sample where M is not positive definite stops the call:
istats[3] its status, istats[4] its index.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_layout import (
    D_BODIES,
    D_M,
    D_NQ,
    D_NV,
    P_COUPLING_VALUES,
    P_COUPLINGS,
    P_CUT_LOAD_VALUES,
    P_CUT_LOADS,
    P_DIMS,
    P_JOINTS,
    P_LOADED,
    P_LOADED_VALUES,
    P_PRIM_VALUES,
    P_PRIMS,
    P_SCENE_JOINTS,
    P_SCENE_POINTS,
    P_SPRING_VALUES,
    P_SPRINGS,
    P_TOLERANCES,
    P_WEIGHT,
    T_SIZE,
    W_ACC,
    W_B,
    W_BIAS,
    W_CHOL,
    W_COM,
    W_G,
    W_GDOT,
    W_H,
    W_INERTIA,
    W_JOINT_POINTS,
    W_KEEP,
    W_LOADS,
    W_MOTION,
    W_PHI,
    W_REFERENCE,
    W_ROT,
    W_ROW_A,
    W_ROW_B,
    W_SINGULAR,
    W_SVD_U,
    W_TAU,
    W_VEL,
)
from massprops.dynamics.compiled.systems_linalg import lower_solve
from massprops.dynamics.compiled.systems_loops import OK, accelerations, decompose, turned
from massprops.dynamics.compiled.systems_mass import _net
from massprops.dynamics.compiled.systems_step import rhs_ref
from massprops.dynamics.compiled.systems_tree import (
    PRISMATIC,
    REVOLUTE,
    kinematics,
    spatial_times,
)
from massprops.dynamics.compiled.unowned import at, by_ref

STATES, ENERGIES, OUTPUTS, RATES = 10, 11, 12, 13
"""The modes of `systems_kernel.evaluate_samples` (the module doc says what each writes;
RATES: ẏ = [q̇, u̇] of each state, the right-hand side the steps take, for the stiffness
probe's Jacobian)."""

BODY_COLUMNS, JOINT_COLUMNS, RESIDUAL_COLUMNS = 18, 9, 2
"""Columns of a sample's row per body, per scene joint, and the residuals' (module doc)."""


O_UDOT, O_NET, O_CUT, O_LAMBDA, O_R, O_VECTOR, O_PAIR = range(7)
"""The slots of `evaluate`'s own arrays (`scratch`): u̇ (nv,), the bodies' net forces (n, 6),
the cut joints' reactions by scene joint (J, 6), λ (m,), r (m,), a vector of max(nv, m), one
cut row's forces on b and on a (2, 6)."""


@inlined
def scratch(prog):
    """`evaluate`'s own arrays, in the order of the ``O_*`` slots. Positions are measured from
    the kinematics' reference point (`systems_layout.W_REFERENCE`)."""
    dims = prog[P_DIMS]
    nv, m, n = dims[D_NV], dims[D_M], dims[D_BODIES]
    return (np.zeros(nv), np.zeros((n, 6)), np.zeros((prog[P_SCENE_JOINTS].shape[0], 6)),
            np.zeros(m), np.zeros(m), np.zeros(max(nv, m)), np.zeros((2, 6)))


@array_inner
def evaluate(prog, ws, own, t_out, y_out, out, istats, mode):
    """Each sample y_out[s] (at t_out[s]) evaluated into out[s] (module doc) by ``mode``. The
    tuples come as the caller owns them (alive for the call) and go on by reference
    (`unowned.by_ref`): taking them as `unowned` views with their owners too, as the step
    loops do, cost the entry ~2 s more to compile (its views and the owners' tuple)."""
    pp, wp, op = by_ref(prog), by_ref(ws), by_ref(own)
    nq = at(pp, P_DIMS)[D_NQ]
    udot = own[O_UDOT]
    for s in range(y_out.shape[0]):
        y, row = y_out[s], out[s]
        if mode == RATES:
            status = rhs_ref(pp, wp, t_out[s], y, row, -1)
            if status != OK:
                istats[3], istats[4] = status, s
                return
            continue
        q, u = y[:nq], y[nq:]
        if mode == OUTPUTS:
            status = accelerations(pp, wp, t_out[s], q, u, udot, -1, False)
            if status != OK:
                istats[3], istats[4] = status, s
                return
        else:
            kinematics(pp, q, u, wp)
        if mode == ENERGIES:
            row[0] = _energy(pp, wp, q, at(wp, W_REFERENCE))
            continue
        _bodies(wp, row, at(wp, W_REFERENCE))
        if mode == OUTPUTS:
            _reactions(pp, wp, op, u, row)


@inlined
def _bodies(wp, row, ref):
    """A sample's body columns: the centre of mass (from the system frame's origin), R, ω and
    the centre's velocity, formed about the reference point the kinematics measure from (no
    cancellation however far the floating base went)."""
    rot, com, vel = at(wp, W_ROT), at(wp, W_COM), at(wp, W_VEL)
    for i in range(com.shape[0]):
        o = BODY_COLUMNS * i
        for c in range(3):
            row[o + c] = com[i, c] + ref[c]
            for d in range(3):
                row[o + 3 + 3 * c + d] = rot[i, c, d]
            row[o + 12 + c] = vel[i, c]
        w0, w1, w2 = vel[i, 0], vel[i, 1], vel[i, 2]
        row[o + 15] = vel[i, 3] + (w1 * com[i, 2] - w2 * com[i, 1])
        row[o + 16] = vel[i, 4] + (w2 * com[i, 0] - w0 * com[i, 2])
        row[o + 17] = vel[i, 5] + (w0 * com[i, 1] - w1 * com[i, 0])


_turned = array_inner(turned)
"""`systems_loops.turned`, called (not inlined) at the outputs' seven call sites."""


@array_inner
def _point(rot, com, ref, body, local):
    """The point of ``body`` at ``local`` (its frame; the world's: world) as three floats,
    world axes, from ``ref`` as the kinematics' positions. Called, not inlined: inlined at its
    seven call sites, with `_reactions`' sums written out per primitive kind, `_reactions`
    and `_energy` took 12 s to compile instead of 6.5 s (the outputs cost nothing per call
    here that matters: ~µs a sample)."""
    if body < 0:
        return local[0] - ref[0], local[1] - ref[1], local[2] - ref[2]
    r = rot[body]
    return (com[body, 0] + r[0, 0] * local[0] + r[0, 1] * local[1] + r[0, 2] * local[2],
            com[body, 1] + r[1, 0] * local[0] + r[1, 1] * local[1] + r[1, 2] * local[2],
            com[body, 2] + r[2, 0] * local[0] + r[2, 1] * local[1] + r[2, 2] * local[2])


@array_inner
def _multipliers(pp, wp, lam, r, z):
    """λ (m,) of least norm (module doc) after `accelerations` with loops (the workspace holds
    τ, h, L, B, Φ̈₀ and the pivoted QR there)."""
    tau, h, low, bm, gdot = at(wp, W_TAU), at(wp, W_H), at(wp, W_CHOL), at(wp, W_B), at(wp, W_GDOT)
    uo, sv, keep = at(wp, W_SVD_U), at(wp, W_SINGULAR), at(wp, W_KEEP)
    m, nv = bm.shape[0], bm.shape[1]
    decompose(pp, wp)
    for i in range(nv):
        z[i] = tau[i] - h[i]
    lower_solve(low, z, nv)  # z₀ = L⁻¹ (τ − h): G M⁻¹ (τ − h) = B z₀
    for i in range(m):
        x = -gdot[i]
        for c in range(nv):
            x -= bm[i, c] * z[c]
        r[i] = x
        lam[i] = 0.0
    for j in range(min(m, nv)):
        if keep[1 + j]:
            x = 0.0
            for i in range(m):
                x += uo[i, j] * r[i]
            x /= sv[j] * sv[j]
            for i in range(m):
                lam[i] += uo[i, j] * x


@array_inner
def _reactions(pp, wp, op, u, row):
    """The scene joints' reactions and points, the residuals (at the rates u), into ``row``
    (module doc; the rule of `dynamics.systems.outputs`); op: `scratch` by reference."""
    ji, pi, pf = at(pp, P_JOINTS), at(pp, P_PRIMS), at(pp, P_PRIM_VALUES)
    sj, sp = at(pp, P_SCENE_JOINTS), at(pp, P_SCENE_POINTS)
    ct, cv = at(pp, P_COUPLINGS), at(pp, P_COUPLING_VALUES)
    rot, com, vel, acc = at(wp, W_ROT), at(wp, W_COM), at(wp, W_VEL), at(wp, W_ACC)
    inert = at(wp, W_INERTIA)
    s, pts, cb, fext = at(wp, W_MOTION), at(wp, W_JOINT_POINTS), at(wp, W_BIAS), at(wp, W_LOADS)
    tau = at(wp, W_TAU)
    phi, g, rb, ra = at(wp, W_PHI), at(wp, W_G), at(wp, W_ROW_B), at(wp, W_ROW_A)
    udot, net, cut, lam, fs = at(op, O_UDOT), at(op, O_NET), at(op, O_CUT), at(op, O_LAMBDA), \
        at(op, O_PAIR)
    ref = at(wp, W_REFERENCE)
    size = at(pp, P_TOLERANCES)[T_SIZE]
    m, nv = g.shape[0], g.shape[1]
    for k in range(ji.shape[0]):  # the true accelerations (the kinematics' are at u̇ = 0)
        par, ch, iu, nvj = ji[k, 1], ji[k, 2], ji[k, 4], ji[k, 6]
        for c in range(6):
            x = (acc[par, c] if par >= 0 else 0.0) + cb[ch, c]
            for a in range(nvj):
                x += s[c, iu + a] * udot[iu + a]
            acc[ch, c] = x
    for i in range(net.shape[0]):  # I A + V ×f I V − f_ext
        _net(vel, inert, fext, i, net[i])
        f = spatial_times(inert[i], acc[i, 0], acc[i, 1], acc[i, 2], acc[i, 3], acc[i, 4],
                          acc[i, 5])
        for c in range(6):
            net[i, c] += f[c]
    for k in range(cut.shape[0]):
        for c in range(6):
            cut[k, c] = 0.0
    if m:
        _multipliers(pp, wp, lam, at(op, O_R), at(op, O_VECTOR))
    for n in range(pi.shape[0]):  # each cut row's force λ ρ on b (fs[0]) and on a (fs[1])
        kind, a, b, r0, k = pi[n, 0], pi[n, 1], pi[n, 2], pi[n, 3], pi[n, 4]
        if kind == 0:  # point: ρ_b = (x_b × e_i, e_i), ρ_a = −(x_a × e_i, e_i)
            f0, f1, f2 = lam[r0], lam[r0 + 1], lam[r0 + 2]
            xb0, xb1, xb2 = _point(rot, com, ref, b, pf[n, 3:6])
            xa0, xa1, xa2 = _point(rot, com, ref, a, pf[n, 0:3])
            fs[0, 0], fs[0, 1], fs[0, 2] = xb1 * f2 - xb2 * f1, xb2 * f0 - xb0 * f2, \
                xb0 * f1 - xb1 * f0
            fs[1, 0], fs[1, 1], fs[1, 2] = xa2 * f1 - xa1 * f2, xa0 * f2 - xa2 * f0, \
                xa1 * f0 - xa0 * f1
            fs[0, 3], fs[0, 4], fs[0, 5], fs[1, 3], fs[1, 4], fs[1, 5] = f0, f1, f2, -f0, -f1, \
                -f2
        elif kind == 1:  # perp: ρ_b = size (n × e, 0) = −ρ_a
            e0, e1, e2 = _turned(rot, a, pf[n, 6:9])
            d0, d1, d2 = _turned(rot, b, pf[n, 9:12])
            x = lam[r0] * size
            fs[0, 0], fs[0, 1], fs[0, 2] = x * (d1 * e2 - d2 * e1), x * (d2 * e0 - d0 * e2), \
                x * (d0 * e1 - d1 * e0)
            for c in range(3):
                fs[0, 3 + c] = fs[1, 3 + c] = 0.0
                fs[1, c] = -fs[0, c]
        else:  # line, dist: `systems_loops.terms` made their ρ rows
            for c in range(6):
                fs[0, c], fs[1, c] = lam[r0] * rb[r0, c], lam[r0] * ra[r0, c]
        for c in range(6):
            cut[k, c] += fs[0, c]
            if b >= 0:
                net[b, c] -= fs[0, c]
            if a >= 0:
                net[a, c] -= fs[1, c]
    for k in range(ct.shape[0]):  # a coupling's reaction drives its joints, as a motor would
        tau[ct[k, 2]] += lam[ct[k, 0]] * cv[k, 0]
    for k in range(ji.shape[0] - 1, -1, -1):  # each tree joint's child: its subtree's sum
        par, ch = ji[k, 1], ji[k, 2]
        if par >= 0:
            for c in range(6):
                net[par, c] += net[ch, c]
    o = BODY_COLUMNS * com.shape[0]
    for k in range(sj.shape[0]):
        n, o_k = sj[k, 0], o + JOINT_COLUMNS * k
        x0, x1, x2 = _point(rot, com, ref, sj[k, 1], sp[k])
        row[o_k + 6], row[o_k + 7], row[o_k + 8] = x0 + ref[0], x1 + ref[1], x2 + ref[2]
        if n < 0:  # a cut joint: its constraint force only, at its point on b
            f = cut[k]
            n0, n1, n2, f0, f1, f2 = f[0], f[1], f[2], f[3], f[4], f[5]
        else:  # less the joint's own load along its axis (drive, spring, damper, coupling)
            f = net[ji[n, 2]]
            n0, n1, n2, f0, f1, f2 = f[0], f[1], f[2], f[3], f[4], f[5]
            kind, iu, load = ji[n, 0], ji[n, 4], 0.0
            x0, x1, x2 = pts[n, 0], pts[n, 1], pts[n, 2]
            if ji[n, 6] and (kind == REVOLUTE or kind == PRISMATIC):
                load = tau[iu]
            if load != 0.0 and kind == REVOLUTE:
                n0, n1, n2 = n0 - load * s[0, iu], n1 - load * s[1, iu], n2 - load * s[2, iu]
            elif load != 0.0:
                w0, w1, w2 = s[3, iu], s[4, iu], s[5, iu]
                n0 -= load * (x1 * w2 - x2 * w1)
                n1 -= load * (x2 * w0 - x0 * w2)
                n2 -= load * (x0 * w1 - x1 * w0)
                f0, f1, f2 = f0 - load * w0, f1 - load * w1, f2 - load * w2
            if ji[n, 7]:  # reversed: the scene's second body is the tree's parent
                n0, n1, n2, f0, f1, f2 = -n0, -n1, -n2, -f0, -f1, -f2
        row[o_k], row[o_k + 1], row[o_k + 2] = f0, f1, f2
        row[o_k + 3] = n0 - (x1 * f2 - x2 * f1)
        row[o_k + 4] = n1 - (x2 * f0 - x0 * f2)
        row[o_k + 5] = n2 - (x0 * f1 - x1 * f0)
    o += JOINT_COLUMNS * sj.shape[0]
    big_phi = big_rate = 0.0
    for i in range(m):
        big_phi = max(big_phi, abs(phi[i]))
        x = 0.0
        for c in range(nv):
            x += g[i, c] * u[c]
        big_rate = max(big_rate, abs(x))
    row[o], row[o + 1] = big_phi, big_rate


@array_inner
def _energy(pp, wp, q, ref):
    """J: kinetic + gravity + the springs' (bodies', tree and cut joints'), as `System.energy`
    (after `kinematics`, whose positions are from ``ref``)."""
    ji, bweight, si = at(pp, P_JOINTS), at(pp, P_WEIGHT), at(pp, P_SPRINGS)
    sf, li, lf = at(pp, P_SPRING_VALUES), at(pp, P_LOADED), \
        at(pp, P_LOADED_VALUES)
    rot, com, vel, inert = at(wp, W_ROT), at(wp, W_COM), at(wp, W_VEL), at(wp, W_INERTIA)
    e = 0.0
    for i in range(com.shape[0]):
        v = vel[i]
        f = spatial_times(inert[i], v[0], v[1], v[2], v[3], v[4], v[5])
        e += 0.5 * (v[0] * f[0] + v[1] * f[1] + v[2] * f[2] + v[3] * f[3] + v[4] * f[4]
                    + v[5] * f[5])
    for i in range(com.shape[0]):
        e -= bweight[i, 0] * (com[i, 0] + ref[0]) + bweight[i, 1] * (com[i, 1] + ref[1]) \
            + bweight[i, 2] * (com[i, 2] + ref[2])
    for n in range(si.shape[0]):
        xa0, xa1, xa2 = _point(rot, com, ref, si[n, 0], sf[n, 0:3])
        xb0, xb1, xb2 = _point(rot, com, ref, si[n, 1], sf[n, 3:6])
        d2 = (xb0 - xa0) ** 2 + (xb1 - xa1) ** 2 + (xb2 - xa2) ** 2
        k, rest = sf[n, 6], sf[n, 7]
        e += 0.5 * k * (math.sqrt(d2) - rest) ** 2 if rest != 0.0 else 0.5 * k * d2
    for n in range(li.shape[0]):
        j = li[n]
        coord = (-1.0 if ji[j, 7] else 1.0) * q[ji[j, 3]]
        e += 0.5 * lf[n, 0] * (coord - lf[n, 1]) ** 2
    ci, cf = at(pp, P_CUT_LOADS), at(pp, P_CUT_LOAD_VALUES)
    for n in range(ci.shape[0]):
        if cf[n, 15] != 0.0:
            e += 0.5 * cf[n, 15] * _cut_stretch(rot, com, ref, ci[n, 0], ci[n, 1], ci[n, 2],
                                                cf[n]) ** 2
    return e


@inlined
def _cut_stretch(rot, com, ref, kind, a, b, cf):
    """A loaded cut joint's coordinate − rest (`cutjoint.stretch`: a revolute's turn within
    [−π, π)), measured from its bodies' poses as `systems_loads` does for its load."""
    e0, e1, e2 = _turned(rot, a, cf[0:3])
    if kind == 0:
        a0, a1, a2 = _turned(rot, a, cf[3:6])
        b0, b1, b2 = _turned(rot, b, cf[6:9])
        da = a0 * e0 + a1 * e1 + a2 * e2
        db = b0 * e0 + b1 * e1 + b2 * e2
        a0, a1, a2 = a0 - da * e0, a1 - da * e1, a2 - da * e2
        b0, b1, b2 = b0 - db * e0, b1 - db * e1, b2 - db * e2
        turn = math.atan2((a1 * b2 - a2 * b1) * e0 + (a2 * b0 - a0 * b2) * e1
                          + (a0 * b1 - a1 * b0) * e2, a0 * b0 + a1 * b1 + a2 * b2)
        d = turn - cf[16]
        return d - 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
    xa0, xa1, xa2 = _point(rot, com, ref, a, cf[9:12])
    xb0, xb1, xb2 = _point(rot, com, ref, b, cf[12:15])
    return -cf[16] + (xb0 - xa0) * e0 + (xb1 - xa1) * e1 + (xb2 - xa2) * e2
