"""A system program's cut joints and its equations of motion, compiled: the constraint rows Φ,
G, Φ̈ at u̇ = 0 (`dynamics.systems.loops` documents the four primitives), the constrained solve and
the least-kinetic-energy corrections of the projection (`dynamics.systems.system` documents the
maths with B = G L⁻ᵀ = U Σ Vᵀ: δ = L⁻ᵀ B⁺ residual). Here B⁺ comes from a pivoted QR of Bᵀ over
its independent rows (`factor`), a few reflections per evaluation where the SVD took sweeps;
for a consistent residual (redundant rows are combinations of the kept ones) it is the same
least-norm solution. The SVD is made only at accepted states, for the singular-pose test
(`decompose`).

Status codes returned: OK, LINALG (M not positive definite), SINGULAR (G's rank fell below the
start's at an evaluated state).
"""

from __future__ import annotations

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_layout import (
    P_COUPLING_VALUES,
    P_COUPLINGS,
    P_JOINTS,
    P_PARENT_JOINT,
    P_PRIM_VALUES,
    P_PRIMS,
    P_TOLERANCES,
    T_RANK_RTOL,
    T_SIZE,
    W_ACC,
    W_B,
    W_CHOL,
    W_COLUMN,
    W_COM,
    W_G,
    W_GDOT,
    W_H,
    W_KEEP,
    W_MASS,
    W_MOTION,
    W_ORDER,
    W_PHI,
    W_Q,
    W_QR,
    W_REFERENCE,
    W_REFLECTORS,
    W_ROT,
    W_ROW_A,
    W_ROW_B,
    W_SINGULAR,
    W_SVD_U,
    W_SVD_V,
    W_SVD_WORK,
    W_TAU,
    W_V3,
    W_VEL,
    W_Z,
)
from massprops.dynamics.compiled.systems_linalg import (
    apply_q,
    cholesky,
    jacobi_svd,
    lower_solve,
    pivoted_qr,
    upper_solve,
)
from massprops.dynamics.compiled.systems_loads import applied
from massprops.dynamics.compiled.systems_mass import aba, bias, crba
from massprops.dynamics.compiled.systems_tree import cross_into, kinematics, motion
from massprops.dynamics.compiled.unowned import at

OK, LINALG, SINGULAR = 0, 6, 3


@inlined
def _point_motion(rot, com, vel, acc, ref, body, local):
    """World position (from the reference point ``ref``, as ``com``), velocity and
    acceleration (kinematics' A) of a body point: nine floats (x, v, a), in scalars rather
    than scratch arrays (see `systems_tree.poses`)."""
    if body < 0:
        return local[0] - ref[0], local[1] - ref[1], local[2] - ref[2], 0.0, 0.0, 0.0, 0.0, \
            0.0, 0.0
    r = rot[body]
    x0 = com[body, 0] + r[0, 0] * local[0] + r[0, 1] * local[1] + r[0, 2] * local[2]
    x1 = com[body, 1] + r[1, 0] * local[0] + r[1, 1] * local[1] + r[1, 2] * local[2]
    x2 = com[body, 2] + r[2, 0] * local[0] + r[2, 1] * local[1] + r[2, 2] * local[2]
    w0, w1, w2 = vel[body, 0], vel[body, 1], vel[body, 2]
    v0 = vel[body, 3] + (w1 * x2 - w2 * x1)
    v1 = vel[body, 4] + (w2 * x0 - w0 * x2)
    v2 = vel[body, 5] + (w0 * x1 - w1 * x0)
    e0, e1, e2 = acc[body, 0], acc[body, 1], acc[body, 2]
    a0 = acc[body, 3] + (e1 * x2 - e2 * x1) + (w1 * v2 - w2 * v1)
    a1 = acc[body, 4] + (e2 * x0 - e0 * x2) + (w2 * v0 - w0 * v2)
    a2 = acc[body, 5] + (e0 * x1 - e1 * x0) + (w0 * v1 - w1 * v0)
    return x0, x1, x2, v0, v1, v2, a0, a1, a2


def turned(rot, body, local):
    """R_body local (the world: local) as three floats."""
    if body < 0:
        return local[0], local[1], local[2]
    r = rot[body]
    return (r[0, 0] * local[0] + r[0, 1] * local[1] + r[0, 2] * local[2],
            r[1, 0] * local[0] + r[1, 1] * local[1] + r[1, 2] * local[2],
            r[2, 0] * local[0] + r[2, 1] * local[1] + r[2, 2] * local[2])


_turned = inlined(turned)
"""`turned` copied into the step loop's callers (their hot loops); the outputs call it
(`systems_outputs`: seven call sites, compiled once)."""


@inlined
def _first3(arr, body):
    """arr[body, :3] (ω of a velocity, ω̇ of an acceleration) as three floats, 0 for the world."""
    if body < 0:
        return 0.0, 0.0, 0.0
    return arr[body, 0], arr[body, 1], arr[body, 2]


@inlined
def _dir(rot, vel, acc, body, local, out, i):
    """out = R_body local (the world: local), or, with i >= 0, ω (i = 0) or ω̇ (i = 1)."""
    if i >= 0:
        for r in range(3):
            out[r] = (vel[body, r] if i == 0 else acc[body, r]) if body >= 0 else 0.0
        return
    for r in range(3):
        out[r] = local[r] if body < 0 else (rot[body, r, 0] * local[0] + rot[body, r, 1]
                                            * local[1] + rot[body, r, 2] * local[2])


@array_inner
def terms(pp, wp):
    """Φ (m,), Φ̈ at u̇ = 0 (m,), G (m, nv) into the workspace (with ρ_b and ρ_a (m, 6) of
    the line and distance rows); the couplings' rows last (from the coordinates
    `systems_tree.kinematics` keeps in `W_Q`)."""
    pi, pf, size = at(pp, P_PRIMS), at(pp, P_PRIM_VALUES), at(pp, P_TOLERANCES)[T_SIZE]
    pjoint, ji = at(pp, P_PARENT_JOINT), at(pp, P_JOINTS)
    phi, gdot, rb, ra = at(wp, W_PHI), at(wp, W_GDOT), at(wp, W_ROW_B), at(wp, W_ROW_A)
    g, s = at(wp, W_G), at(wp, W_MOTION)
    rot, com, vel, acc = at(wp, W_ROT), at(wp, W_COM), at(wp, W_VEL), at(wp, W_ACC)
    ref = at(wp, W_REFERENCE)
    v = at(wp, W_V3)
    xa, xb, t, e = v[0], v[3], v[6], v[7]
    d, dd, ddd, w1, w2, w3, w4, w5 = v[8], v[9], v[10], v[11], v[12], v[13], v[14], v[15]
    for n in range(pi.shape[0]):
        kind, a, b, row = pi[n, 0], pi[n, 1], pi[n, 2], pi[n, 3]
        rows = 3 if kind == 0 else 1
        for k in range(rows):
            for c in range(g.shape[1]):
                g[row + k, c] = 0.0
        if kind == 1:  # perp: n · e = 0, e on a, n on b (both world)
            e0, e1, e2 = _turned(rot, a, pf[n, 6:9])
            d0, d1, d2 = _turned(rot, b, pf[n, 9:12])
            n0, n1, n2 = d1 * e2 - d2 * e1, d2 * e0 - d0 * e2, d0 * e1 - d1 * e0  # n × e
            phi[row] = size * (e0 * d0 + e1 * d1 + e2 * d2)
            _turn_row(g, row, ji, pjoint, s, b, n0, n1, n2, size)  # ρ_b = size (n × e, 0)
            _turn_row(g, row, ji, pjoint, s, a, n0, n1, n2, -size)  # = -ρ_a
            wa0, wa1, wa2 = _first3(vel, a)
            wb0, wb1, wb2 = _first3(vel, b)
            t0, t1, t2 = wb1 * d2 - wb2 * d1, wb2 * d0 - wb0 * d2, wb0 * d1 - wb1 * d0
            f0 = t1 * e2 - t2 * e1  # (ωb × n) × e
            f1 = t2 * e0 - t0 * e2
            f2 = t0 * e1 - t1 * e0
            t0, t1, t2 = wa1 * e2 - wa2 * e1, wa2 * e0 - wa0 * e2, wa0 * e1 - wa1 * e0
            f0 += d1 * t2 - d2 * t1  # + n × (ωa × e)
            f1 += d2 * t0 - d0 * t2
            f2 += d0 * t1 - d1 * t0
            aa0, aa1, aa2 = _first3(acc, a)
            ab0, ab1, ab2 = _first3(acc, b)
            gdot[row] = size * ((wb0 - wa0) * f0 + (wb1 - wa1) * f1 + (wb2 - wa2) * f2
                                + (ab0 - aa0) * n0 + (ab1 - aa1) * n1 + (ab2 - aa2) * n2)
        else:
            xa0, xa1, xa2, va0, va1, va2, aa0, aa1, aa2 = _point_motion(rot, com, vel, acc,
                                                                        ref, a, pf[n, 0:3])
            xb0, xb1, xb2, vb0, vb1, vb2, ab0, ab1, ab2 = _point_motion(rot, com, vel, acc,
                                                                        ref, b, pf[n, 3:6])
            if kind == 0:  # point: its rows of G in one walk a side (`_point_rows`)
                phi[row], phi[row + 1], phi[row + 2] = xb0 - xa0, xb1 - xa1, xb2 - xa2
                gdot[row], gdot[row + 1], gdot[row + 2] = ab0 - aa0, ab1 - aa1, ab2 - aa2
                _point_rows(g, row, ji, pjoint, s, b, xb0, xb1, xb2, 1.0)
                _point_rows(g, row, ji, pjoint, s, a, xa0, xa1, xa2, -1.0)
                continue
            xa[0], xa[1], xa[2], xb[0], xb[1], xb[2] = xa0, xa1, xa2, xb0, xb1, xb2
            d[0], d[1], d[2] = xb0 - xa0, xb1 - xa1, xb2 - xa2
            dd[0], dd[1], dd[2] = vb0 - va0, vb1 - va1, vb2 - va2
            ddd[0], ddd[1], ddd[2] = ab0 - aa0, ab1 - aa1, ab2 - aa2
            if kind == 2:  # line
                _dir(rot, vel, acc, a, pf[n, 6:9], e, -1)
                _dir(rot, vel, acc, a, e, w2, 0)
                cross_into(w1, w2, e)  # we
                phi[row] = d[0] * e[0] + d[1] * e[1] + d[2] * e[2]
                _rho(rb, row, xb, e, 1.0)
                _rho(ra, row, xa, e, -1.0)
                cross_into(t, e, d)
                for c in range(3):
                    ra[row, c] += t[c]
                _dir(rot, vel, acc, a, e, w3, 1)
                cross_into(w4, w3, e)
                cross_into(w5, w2, w1)
                x = 0.0
                for c in range(3):
                    x += ddd[c] * e[c] + 2 * dd[c] * w1[c] + d[c] * (w4[c] + w5[c])
                gdot[row] = x
                _rho_row(g, row, ji, pjoint, s, b, rb)
                _rho_row(g, row, ji, pjoint, s, a, ra)
            else:  # dist
                length = pf[n, 12]
                phi[row] = (d[0] ** 2 + d[1] ** 2 + d[2] ** 2 - length * length) / (2 * length)
                for c in range(3):
                    e[c] = d[c] / length
                _rho(rb, row, xb, e, 1.0)
                _rho(ra, row, xa, e, -1.0)
                x = 0.0
                for c in range(3):
                    x += dd[c] * dd[c] + d[c] * ddd[c]
                gdot[row] = x / length
                _rho_row(g, row, ji, pjoint, s, b, rb)
                _rho_row(g, row, ji, pjoint, s, a, ra)
    ct, cv, qc = at(pp, P_COUPLINGS), at(pp, P_COUPLING_VALUES), at(wp, W_Q)
    for k in range(ct.shape[0]):  # the couplings' rows (`dynamics.systems.loops.Coupling`)
        row = ct[k, 0]
        if k == 0 or ct[k - 1, 0] != row:
            phi[row] = gdot[row] = 0.0
            for c in range(g.shape[1]):
                g[row, c] = 0.0
        phi[row] += cv[k, 0] * qc[ct[k, 1]] - cv[k, 1]
        g[row, ct[k, 2]] += cv[k, 0]


@inlined
def _point_rows(g, row, ji, pjoint, s, body, x0, x1, x2, sign):
    """A point primitive's three rows of G, one side: for each dof c that moves ``body``,
    g[row:row + 3, c] += sign (v_c + ω_c × x), the velocity that dof gives the point x (its
    ρ rows (x × e_k, e_k) times S_c, without forming them)."""
    j = pjoint[body] if body >= 0 else -1
    while j >= 0:
        for c in range(ji[j, 4], ji[j, 4] + ji[j, 6]):
            w0, w1, w2 = s[0, c], s[1, c], s[2, c]
            g[row, c] += sign * (s[3, c] + (w1 * x2 - w2 * x1))
            g[row + 1, c] += sign * (s[4, c] + (w2 * x0 - w0 * x2))
            g[row + 2, c] += sign * (s[5, c] + (w0 * x1 - w1 * x0))
        j = pjoint[ji[j, 1]] if ji[j, 1] >= 0 else -1


@inlined
def _rho_row(g, row, ji, pjoint, s, body, rho):
    """G = ρ_b J_b + ρ_a J_a, one side of one row: g[row, c] += ρ[row] · S_c for each dof c
    that moves ``body`` (its ancestors' S columns)."""
    j = pjoint[body] if body >= 0 else -1
    while j >= 0:
        for c in range(ji[j, 4], ji[j, 4] + ji[j, 6]):
            g[row, c] += rho[row, 0] * s[0, c] + rho[row, 1] * s[1, c] + rho[row, 2] * s[2, c] \
                + rho[row, 3] * s[3, c] + rho[row, 4] * s[4, c] + rho[row, 5] * s[5, c]
        j = pjoint[ji[j, 1]] if ji[j, 1] >= 0 else -1


@inlined
def _turn_row(g, row, ji, pjoint, s, body, n0, n1, n2, scale):
    """A row whose ρ is (scale n, 0), one side: g[row, c] += scale n · ω_c for each dof c that
    moves ``body``."""
    j = pjoint[body] if body >= 0 else -1
    while j >= 0:
        for c in range(ji[j, 4], ji[j, 4] + ji[j, 6]):
            g[row, c] += scale * (n0 * s[0, c] + n1 * s[1, c] + n2 * s[2, c])
        j = pjoint[ji[j, 1]] if ji[j, 1] >= 0 else -1


@inlined
def _rho(out, row, x, e, sign):
    """out[row] = sign (x × e, e)."""
    out[row, 0] = sign * (x[1] * e[2] - x[2] * e[1])
    out[row, 1] = sign * (x[2] * e[0] - x[0] * e[2])
    out[row, 2] = sign * (x[0] * e[1] - x[1] * e[0])
    out[row, 3], out[row, 4], out[row, 5] = sign * e[0], sign * e[1], sign * e[2]


@array_inner
def factor(pp, wp):
    """After `kinematics`: M, its Cholesky factor L, the constraint terms, B = G L⁻ᵀ (`W_B`)
    and the pivoted QR of Bᵀ (`systems_linalg.pivoted_qr`: Bᵀ P = Q R in `W_QR`, the order and
    rank in `W_ORDER`, the reflectors' factors in `W_REFLECTORS`); False if M is not positive
    definite."""
    mass, low, g, bm, x = at(wp, W_MASS), at(wp, W_CHOL), at(wp, W_G), at(wp, W_B), at(wp, W_QR)
    row = at(wp, W_COLUMN)
    nv, m = mass.shape[0], g.shape[0]
    crba(pp, wp, mass)
    if not cholesky(mass, low, nv):
        return False
    terms(pp, wp)
    for i in range(m):
        for c in range(nv):
            row[c] = g[i, c]
        lower_solve(low, row, nv)
        for c in range(nv):
            bm[i, c] = x[c, i] = row[c]
    pivoted_qr(x, nv, m, at(wp, W_ORDER), at(wp, W_REFLECTORS), at(pp, P_TOLERANCES)[T_RANK_RTOL])
    return True


@array_inner
def decompose(pp, wp):
    """The SVD of B's independent part for the singular-pose test (`systems_step.accept`), from
    `factor`'s pivoted QR of the same state (Bᵀ P = Q R, rank r; R's rows below r are under the
    rank tolerance): B = P Rᵀ Qᵀ ≈ P W Q₁ᵀ, W = R[:r]ᵀ (m × r), Q₁ Q's first r columns, and
    W's one-sided Jacobi SVD W Z = U_w Σ gives B's U = P U_w and V = Q₁ Z. A Jacobi SVD of B
    itself (5 sweeps over 3 column pairs on the four-bar) cost ~3× as much at every accepted
    step. ws U (m, kk), σ (kk,), V (nv, kk), kk = min(m, nv), columns r and on zero; `W_KEEP` =
    [count kept, kept flags] (σ_j above CONSTRAINT_RANK_RTOL of the largest)."""
    bm, x, w, sv = at(wp, W_B), at(wp, W_QR), at(wp, W_SVD_WORK), at(wp, W_SINGULAR)
    uo, vo = at(wp, W_SVD_U), at(wp, W_SVD_V)
    order, tau, z, col = at(wp, W_ORDER), at(wp, W_REFLECTORS), at(wp, W_Z), at(wp, W_COLUMN)
    nv, m = bm.shape[1], bm.shape[0]
    kk, r = min(m, nv), order[0]
    for j in range(m):  # W = R[:r]ᵀ: R on and above x's diagonal (reflectors below it)
        for k in range(r):
            w[j, k] = x[k, j] if j >= k else 0.0
    jacobi_svd(w, m, r, z, sv)
    for c in range(kk):
        for j in range(m):  # U = P U_w: W's row j is B's row order[1 + j]
            uo[order[1 + j], c] = w[j, c] / sv[c] if c < r and sv[c] > 0 else 0.0
        for i in range(nv):  # V = Q [Z; 0]
            col[i] = z[i, c] if c < r and i < r else 0.0
        apply_q(x, tau, r, nv, col, False)
        for i in range(nv):
            vo[i, c] = col[i] if c < r else 0.0
        if c >= r:
            sv[c] = 0.0
    top = 0.0
    for j in range(kk):
        top = max(top, sv[j])
    rank_rtol = at(pp, P_TOLERANCES)[T_RANK_RTOL]
    kept = 0
    keep = at(wp, W_KEEP)
    for j in range(kk):
        keep[1 + j] = 1 if sv[j] > rank_rtol * top else 0
        kept += keep[1 + j]
    keep[0] = kept


@array_inner
def min_norm(pp, wp, residual, out):
    """out (nv,) = L⁻ᵀ z, z the least-norm solution of B_s z = residual_s over the independent
    rows s of `factor`'s pivoted QR (Bᵀ_s = Q₁ R₁₁: z = Q₁ R₁₁⁻ᵀ residual_s): the smallest
    correction in the kinetic-energy metric with G out = residual on those rows, and on the
    others too where the residual is consistent (the redundant rows are their combinations)."""
    low, x, order, tau = at(wp, W_CHOL), at(wp, W_QR), at(wp, W_ORDER), at(wp, W_REFLECTORS)
    nv = low.shape[0]
    for i in range(nv):
        out[i] = 0.0
    _solve_rt(x, order, residual, out, 1.0)
    apply_q(x, tau, order[0], nv, out, False)
    upper_solve(low, out, nv)


@inlined
def _solve_rt(x, order, c, w, sign):
    """w[:r] = R₁₁⁻ᵀ (sign · c over the pivot order), r = the rank (forward substitution)."""
    for k in range(order[0]):
        s = sign * c[order[1 + k]]
        for i in range(k):
            s -= x[i, k] * w[i]
        w[k] = s / x[k, k]


@array_inner
def accelerations(pp, wp, t, q, u, udot, rank0, posed):
    """udot = the accelerations at (t, q, u); SINGULAR when the rank of G fell below ``rank0``
    (≥ 0). Gauss' principle in z = Lᵀ u̇: z₀ = L⁻¹ (τ − h), the constraint B z = −Φ̈(u̇ = 0)
    on the independent rows, z = Q [R₁₁⁻ᵀ c_s; (Qᵀ z₀) below the rank] (the least change of z₀,
    i.e. of kinetic energy), u̇ = L⁻ᵀ z. The multipliers are not formed here: the reactions
    are an output's work (`dynamics.systems.outputs`, their minimum-norm choice).

    ``posed``: the workspace holds `poses` and `factor` at this q already (the projection's
    last pass, `systems_step.settle`), so only the motion, the loads, h and the constraint terms
    (G anew, the same numbers) are computed: ~0.7 µs of the four-bar's ~1.5."""
    if posed:
        motion(pp, u, wp)
    else:
        kinematics(pp, q, u, wp)
    applied(pp, t, q, u, wp)
    g = at(wp, W_G)
    if g.shape[0] == 0:
        return OK if aba(pp, wp, udot) else LINALG
    h, tau, low, gdot = at(wp, W_H), at(wp, W_TAU), at(wp, W_CHOL), at(wp, W_GDOT)
    x, order, rt = at(wp, W_QR), at(wp, W_ORDER), at(wp, W_REFLECTORS)
    nv = h.shape[0]
    bias(pp, wp, h)
    if posed:
        terms(pp, wp)
    elif not factor(pp, wp):
        return LINALG
    for i in range(nv):
        udot[i] = tau[i] - h[i]
    lower_solve(low, udot, nv)
    rank = order[0]
    apply_q(x, rt, rank, nv, udot, True)
    _solve_rt(x, order, gdot, udot, -1.0)
    apply_q(x, rt, rank, nv, udot, False)
    upper_solve(low, udot, nv)
    if rank0 >= 0 and rank < rank0:
        return SINGULAR
    return OK
