"""The joint-space equations of a system program's tree, compiled: u̇ by the articulated-body
algorithm where there are no loops (O(n)), and M (CRBA, O(n · depth)) with the bias h (RNEA,
O(n)) where the loop constraints need M itself (`systems_loops`).

Both from the kinematics at u̇ = 0 and the applied loads (`systems_tree`), world-frame spatial
vectors about O (no transforms between bodies): M u̇ + h = τ, h = Sᵀ Σ_subtree (I A₀ + V ×f I V
− f_ext). ABA (Featherstone, Rigid Body Dynamics Algorithms, §7.3, here in absolute
coordinates): inward, U = I^A S, D = Sᵀ U, ũ = τ − Sᵀ p^A, the parent gets I^A − U D⁻¹ Uᵀ and
p^A + I^a c + U D⁻¹ ũ (c the joint's bias acceleration); outward, u̇ = D⁻¹ (ũ − Uᵀ a_parent−c).
A floating root (a free joint, S invertible) takes its acceleration from I^A A + p^A = S⁻ᵀ τ
directly (`_floating_root`).
"""

from __future__ import annotations

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_layout import (
    P_JOINTS,
    P_PARENT_JOINT,
    W_ABA_DINV,
    W_ABA_U,
    W_ABA_UMAT,
    W_ACC,
    W_ART_BIAS,
    W_ART_INERTIA,
    W_BIAS,
    W_COMPOSITE,
    W_INERTIA,
    W_LOADS,
    W_M6,
    W_M6_PAIR,
    W_MOTION,
    W_TAU,
    W_VEL,
)
from massprops.dynamics.compiled.systems_linalg import cholesky, lower_solve, upper_solve
from massprops.dynamics.compiled.systems_tree import (
    FREE,
    INERTIA_SIZE,
    spatial_matrix,
    spatial_times,
)
from massprops.dynamics.compiled.unowned import at


@inlined
def _net(vel, inert, fext, i, out):
    """out = V_i ×f (I_i V_i) − f_ext,i."""
    v0, v1, v2, v3, v4, v5 = vel[i, 0], vel[i, 1], vel[i, 2], vel[i, 3], vel[i, 4], vel[i, 5]
    f0, f1, f2, f3, f4, f5 = spatial_times(inert[i], v0, v1, v2, v3, v4, v5)
    out[0] = v1 * f2 - v2 * f1 + v4 * f5 - v5 * f4 - fext[i, 0]
    out[1] = v2 * f0 - v0 * f2 + v5 * f3 - v3 * f5 - fext[i, 1]
    out[2] = v0 * f1 - v1 * f0 + v3 * f4 - v4 * f3 - fext[i, 2]
    out[3] = v1 * f5 - v2 * f4 - fext[i, 3]
    out[4] = v2 * f3 - v0 * f5 - fext[i, 4]
    out[5] = v0 * f4 - v1 * f3 - fext[i, 5]


@array_inner
def aba(pp, wp, udot):
    """udot (nv,) = M⁻¹ (τ − h) of a tree without loops."""
    ji = at(pp, P_JOINTS)
    acc, inert, s, cb = at(wp, W_ACC), at(wp, W_INERTIA), at(wp, W_MOTION), at(wp, W_BIAS)
    tau = at(wp, W_TAU)
    ia, pa, uu = at(wp, W_ART_INERTIA), at(wp, W_ART_BIAS), at(wp, W_ABA_U)
    dinv, un = at(wp, W_ABA_DINV), at(wp, W_ABA_UMAT)
    v6, m6 = at(wp, W_M6), at(wp, W_M6_PAIR)
    n = inert.shape[0]
    for i in range(n):
        spatial_matrix(inert[i], ia[i])
        _net(at(wp, W_VEL), inert, at(wp, W_LOADS), i, pa[i])
    low, tmp = m6[0], m6[1]
    for k in range(ji.shape[0] - 1, -1, -1):
        par, ch, iu, nvj = ji[k, 1], ji[k, 2], ji[k, 4], ji[k, 6]
        if ji[k, 0] == FREE:  # a root: nothing to pass on (`_floating_root`, outward)
            continue
        for c in range(nvj):  # U = I^A S, ũ = τ − Sᵀ p^A
            x = tau[iu + c]
            for r in range(6):
                x -= s[r, iu + c] * pa[ch, r]
            uu[iu + c] = x
            for r in range(6):
                x = 0.0
                for e in range(6):
                    x += ia[ch, r, e] * s[e, iu + c]
                un[k, r, c] = x
        for a in range(nvj):  # D = Sᵀ U, its inverse (nv ≤ 6: a small Cholesky)
            for b in range(nvj):
                x = 0.0
                for r in range(6):
                    x += s[r, iu + a] * un[k, r, b]
                tmp[a, b] = x
        if nvj and not cholesky(tmp, low, nvj):
            return False
        for b in range(nvj):
            for a in range(nvj):
                v6[1, a] = 1.0 if a == b else 0.0
            lower_solve(low, v6[1], nvj)
            upper_solve(low, v6[1], nvj)
            for a in range(nvj):
                dinv[k, a, b] = v6[1, a]
        if par < 0:
            continue
        for a in range(nvj):  # U D⁻¹ ũ, and U D⁻¹ rows (in tmp: 6 × nvj)
            x = 0.0
            for b in range(nvj):
                x += dinv[k, a, b] * uu[iu + b]
            v6[2, a] = x
        for r in range(6):
            for a in range(nvj):
                x = 0.0
                for b in range(nvj):
                    x += un[k, r, b] * dinv[k, b, a]
                tmp[r, a] = x
        for r in range(6):  # I^a = I^A − U D⁻¹ Uᵀ, into the parent
            for c in range(6):
                x = ia[ch, r, c]
                for a in range(nvj):
                    x -= tmp[r, a] * un[k, c, a]
                ia[par, r, c] += x
                low[r, c] = x
        for r in range(6):  # p^a = p^A + I^a c + U D⁻¹ ũ
            x = pa[ch, r]
            for c in range(6):
                x += low[r, c] * cb[ch, c]
            for a in range(nvj):
                x += un[k, r, a] * v6[2, a]
            pa[par, r] += x
    for k in range(ji.shape[0]):
        par, ch, iu, nvj = ji[k, 1], ji[k, 2], ji[k, 4], ji[k, 6]
        if ji[k, 0] == FREE:
            if not _floating_root(ia[ch], pa[ch], s, tau, iu, low, v6[1], acc[ch], cb[ch],
                                  udot):
                return False
            continue
        for r in range(6):
            acc[ch, r] = (acc[par, r] if par >= 0 else 0.0) + cb[ch, r]  # now the true A
        for a in range(nvj):
            x = uu[iu + a]
            for r in range(6):
                x -= un[k, r, a] * acc[ch, r]
            v6[3, a] = x
        for a in range(nvj):
            x = 0.0
            for b in range(nvj):
                x += dinv[k, a, b] * v6[3, b]
            udot[iu + a] = x
        for r in range(6):
            for a in range(nvj):
                acc[ch, r] += s[r, iu + a] * udot[iu + a]
    return True


@inlined
def _floating_root(ia, pa, s, tau, iu, low, f, acc, cb, udot):
    """acc (6,) = A and udot[iu:iu + 6] of a floating root, a free joint to the world (u = [v_c,
    ω in its own frame], S's columns (0, e_i) and (w_i, c × w_i), the w_i orthonormal). S is
    invertible, so the articulated equation Sᵀ (I^A A + p^A) = τ gives A = (I^A)⁻¹ (f − p^A),
    f = S⁻ᵀ τ: one 6 × 6 Cholesky, where the general step forms U, D = Sᵀ U and D⁻¹ (~5 times
    the work, the whole ABA of a lone body); then u̇ = S⁻¹ (A − c). False if I^A is not
    positive definite."""
    for i in range(3):  # f = S⁻ᵀ τ: f_lin = τ_v, then w_i · f_ang = τ_ω,i − (c × w_i) · f_lin
        f[3 + i] = tau[iu + i]
    f[0] = f[1] = f[2] = 0.0
    for i in range(3):
        col = iu + 3 + i
        g = tau[col] - (s[3, col] * f[3] + s[4, col] * f[4] + s[5, col] * f[5])
        f[0], f[1], f[2] = f[0] + g * s[0, col], f[1] + g * s[1, col], f[2] + g * s[2, col]
    for r in range(6):
        f[r] -= pa[r]
    if not cholesky(ia, low, 6):
        return False
    lower_solve(low, f, 6)
    upper_solve(low, f, 6)
    for r in range(6):
        acc[r] = f[r]
    for i in range(3):  # ω̇'s rates: w_i · α, α = A_ang − c_ang
        col = iu + 3 + i
        udot[col] = s[0, col] * (f[0] - cb[0]) + s[1, col] * (f[1] - cb[1]) \
            + s[2, col] * (f[2] - cb[2])
    for i in range(3):  # v̇_c = (A_lin − c_lin) − Σ (c × w_j) ω̇_j
        x = f[3 + i] - cb[3 + i]
        for j in range(3):
            x -= s[3 + i, iu + 3 + j] * udot[iu + 3 + j]
        udot[iu + i] = x
    return True


@array_inner
def bias(pp, wp, h):
    """h (nv,) = Sᵀ of the transmitted forces I A₀ + V ×f I V − f_ext summed over each
    subtree (RNEA at u̇ = 0); uses the kinematics' A (u̇ = 0)."""
    ji = at(pp, P_JOINTS)
    acc, inert, s, pa = at(wp, W_ACC), at(wp, W_INERTIA), at(wp, W_MOTION), at(wp, W_ART_BIAS)
    for i in range(inert.shape[0]):
        _net(at(wp, W_VEL), inert, at(wp, W_LOADS), i, pa[i])
        f = spatial_times(inert[i], acc[i, 0], acc[i, 1], acc[i, 2], acc[i, 3], acc[i, 4],
                          acc[i, 5])
        for r in range(6):
            pa[i, r] += f[r]
    for k in range(ji.shape[0] - 1, -1, -1):
        par, ch = ji[k, 1], ji[k, 2]
        if par >= 0:
            for r in range(6):
                pa[par, r] += pa[ch, r]
    for k in range(ji.shape[0]):
        ch, iu, nvj = ji[k, 2], ji[k, 4], ji[k, 6]
        for a in range(nvj):
            x = 0.0
            for r in range(6):
                x += s[r, iu + a] * pa[ch, r]
            h[iu + a] = x


@array_inner
def crba(pp, wp, mass):
    """mass (nv, nv) = the joint-space mass matrix (composite rigid bodies, each composite as
    the ten numbers of `systems_tree.INERTIA_SIZE`: sums of masses, first moments and inertias
    about O are the composite's)."""
    ji, pjoint = at(pp, P_JOINTS), at(pp, P_PARENT_JOINT)
    inert, s, comp, v6 = at(wp, W_INERTIA), at(wp, W_MOTION), at(wp, W_COMPOSITE), at(wp, W_M6)
    for i in range(inert.shape[0]):
        for r in range(INERTIA_SIZE):
            comp[i, r] = inert[i, r]
    for k in range(ji.shape[0] - 1, -1, -1):
        par, ch = ji[k, 1], ji[k, 2]
        if par >= 0:
            for r in range(INERTIA_SIZE):
                comp[par, r] += comp[ch, r]
    f = v6[0]
    for k in range(ji.shape[0]):
        ch, iu, nvj = ji[k, 2], ji[k, 4], ji[k, 6]
        for a in range(nvj):
            c = iu + a
            f[0], f[1], f[2], f[3], f[4], f[5] = spatial_times(
                comp[ch], s[0, c], s[1, c], s[2, c], s[3, c], s[4, c], s[5, c])
            anc = k
            while anc >= 0:  # this joint, then its ancestors: M[anc dofs, iu + a]
                for b in range(ji[anc, 6]):
                    x = 0.0
                    for r in range(6):
                        x += s[r, ji[anc, 4] + b] * f[r]
                    mass[ji[anc, 4] + b, c] = x
                    mass[c, ji[anc, 4] + b] = x
                anc = pjoint[ji[anc, 1]] if ji[anc, 1] >= 0 else -1
