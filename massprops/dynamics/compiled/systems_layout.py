"""The layout of the systems engine's two tuples, by name: the system program (the system as
arrays, built once by `dynamics.systems.program.build_program`, read by every kernel) and the
workspace (`systems_step.workspace`, the kernels' scratch, made once per compiled call). Every
kernel reads a slot by its name here (``at(pp, P_JOINTS)``, ``prog[P_DIMS]``), never by its
position; numba takes these module ints as compile-time constants. Two vectors of the program
have named entries too: `P_DIMS` (``D_*``) and `P_TOLERANCES` (``T_*``).

Shapes use nq, nv (coordinates, velocities), m (constraint rows), n (bodies), nj (tree joints),
p = max(m, nv), kk = min(m, nv). Bodies and parents use -1 for the world (model.WORLD), as the
kernels test body < 0. Frames and meanings as in `dynamics.systems.tree`, `loops` and `System`
(the numpy objects the program mirrors). C-contiguous int64 or float64 arrays throughout.
"""

from __future__ import annotations

# --- the system program -------------------------------------------------------------------------
P_DIMS = 0
"""(5,) int: the sizes, entries `D_NQ`, `D_NV`, `D_M`, `D_BODIES`, `D_JOINTS`."""
P_JOINTS = 1
"""(nj, 8) int: [kind code (`systems.program.KIND`), parent body, child, iq, iu, nq, nv,
reversed]."""
P_AXES = 2
"""(nj, 2, 3): each joint's axes in its joint frame."""
P_S_PARENT = 3
"""(nj, 3): the joint point from the parent's centre of mass, parent frame."""
P_S_CHILD = 4
"""(nj, 3): the joint point from the child's centre of mass, child frame."""
P_ROT_PARENT0 = 5
"""(nj, 3, 3): the joint frame in the parent's at q = 0."""
P_PARENT_JOINT = 6
"""(n,) int: body -> its tree joint."""
P_MASS = 7
"""(n,) kg."""
P_INERTIA = 8
"""(n, 3, 3) kg m², about the centre of mass, body axes."""
P_ROTATION0 = 9
"""(n, 3, 3): each body's rotation at the start (body -> world)."""
P_COM0 = 10
"""(n, 3) m: each centre of mass at the start."""
P_WEIGHT = 11
"""(n, 3) N: m g of each body."""
P_PRIMS = 12
"""(np, 5) int: the constraint primitives [kind (`systems.program.PRIM`), a, b, first row,
the scene joint it belongs to]."""
P_PRIM_VALUES = 13
"""(np, 13): [pa, pb, ea, nb, length] of each primitive."""
P_FORCES = 14
"""(nf, 4) int: [0 force / 1 torque / 2 drag, body, body frame, at a point]."""
P_FORCE_VALUES = 15
"""(nf, 8): [vector, point in the body frame, start, end]; a drag's [linear, angular, 0, ...,
-inf, inf]."""
P_SPRINGS = 16
"""(ns, 2) int: [a, b]."""
P_SPRING_VALUES = 17
"""(ns, 9): [point on a, point on b, stiffness, rest, damping]."""
P_LOADED = 18
"""(nl,) int: the tree joints with a spring, damper or drive."""
P_LOADED_VALUES = 19
"""(nl, 6): [stiffness, rest, damping, drive, start, end]."""
P_TOLERANCES = 20
"""(4,): entries `T_SIZE`, `T_RANK_RTOL`, `T_PROJECTION_ATOL`, `T_SINGULAR_MARGIN`. The
tolerances travel as data, so that a compiled kernel never holds a stale copy of one."""
P_CUT_LOADS = 21
"""(nc, 3) int: the loaded cut joints [0 revolute / 1 prismatic, a, b]."""
P_CUT_LOAD_VALUES = 22
"""(nc, 21): [axis in a's frame, the normal the turn is measured from in a's frame and in b's,
the joint point in a's and in b's frame, stiffness, rest, damping, drive, start, end]
(`systems.cutjoint`; body frames, world for the world)."""
P_COUPLINGS = 23
"""(nt, 3) int: coupling terms [row, iq, iu]."""
P_COUPLING_VALUES = 24
"""(nt, 2): [scale c, scale constant on a coupling's first term, else 0]
(`loops.Coupling`: Φ_row = Σ scale c q[iq] − scale constant)."""
P_AXES_PARENT = 25
"""(nj, 2, 3): the axes in the parent's frame, R_p0ᵀ a."""
P_TURN0 = 26
"""(nj, 3, 3): R_p0ᵀ R_c0, R_c0 the child's rotation0: a joint turning by Rot(a, q) in its
frame gives the child R_parent Rot(R_p0ᵀ a, q) R_p0ᵀ R_c0, one 3 × 3 product fewer than
through the joint frame."""
P_SCENE_JOINTS = 27
"""(J, 2) int: each scene joint's [tree joint (-1: a cut joint), second body b]."""
P_SCENE_POINTS = 28
"""(J, 3): its point (a distance joint's second point) fixed in b, b's frame (world for the
world): what the outputs report per scene joint (`systems_outputs`)."""
PROGRAM_SLOTS = 29

D_NQ, D_NV, D_M, D_BODIES, D_JOINTS = range(5)
"""Entries of `P_DIMS`."""

T_SIZE, T_RANK_RTOL, T_PROJECTION_ATOL, T_SINGULAR_MARGIN = range(4)
"""Entries of `P_TOLERANCES`: the system's size (m), CONSTRAINT_RANK_RTOL, the projection's
position tolerance (m), NEAR_SINGULAR_MARGIN."""

# --- the workspace ------------------------------------------------------------------------------
W_ROT = 0
"""(n, 3, 3): each body's rotation (body -> world)."""
W_COM = 1
"""(n, 3) m: each centre of mass, world, from the point `W_REFERENCE`."""
W_VEL = 2
"""(n, 6): each body's (ω, v_O), world."""
W_ACC = 3
"""(n, 6): each body's spatial acceleration at u̇ = 0, world (`systems_tree.motion`)."""
W_INERTIA = 4
"""(n, INERTIA_SIZE): each body's inertia about O as [m, m c, J_O] (`systems_tree`)."""
W_MOTION = 5
"""(6, nv): the joints' motion subspace, column by velocity (world)."""
W_JOINT_POINTS = 6
"""(nj, 3) m: each tree joint's point, world."""
W_BIAS = 7
"""(n, 6): each body's joint velocity-product term c (`systems_tree.motion`)."""
W_M3 = 8
"""(4, 3, 3): 3 × 3 scratch."""
W_V3 = 9
"""(16, 3): 3-vector scratch."""
W_M6 = 10
"""(6, 6): 6 × 6 scratch."""
W_LOADS = 11
"""(n, 6): the applied spatial force on each body about O, world (`systems_loads.applied`)."""
W_TAU = 12
"""(nv,): τ, the joint loads (`systems_loads.applied`)."""
W_ART_INERTIA = 13
"""(n, 6, 6): the articulated-body inertias."""
W_ART_BIAS = 14
"""(n, 6): the articulated-body bias forces."""
W_ABA_U = 15
"""(nv,): the articulated-body pass's u = τ − Sᵀ pᴬ."""
W_ABA_DINV = 16
"""(nj, 6, 6): each joint's D⁻¹ = (Sᵀ Iᴬ S)⁻¹."""
W_ABA_UMAT = 17
"""(nj, 6, 6): each joint's U = Iᴬ S."""
W_M6_PAIR = 18
"""(2, 6, 6): two 6 × 6 scratch matrices."""
W_PHI = 19
"""(m,): the constraint residuals Φ."""
W_GDOT = 20
"""(m,): Φ̈ at u̇ = 0."""
W_ROW_B = 21
"""(m, 6): ρ_b of the line and distance rows (`systems_loops.terms`)."""
W_ROW_A = 22
"""(m, 6): ρ_a of those rows."""
W_G = 23
"""(m, nv): the constraint Jacobian G = Φ_q."""
W_MASS = 24
"""(nv, nv): the mass matrix M."""
W_CHOL = 25
"""(nv, nv): M's Cholesky factor L."""
W_B = 26
"""(m, nv): B = G L⁻ᵀ."""
W_QR = 27
"""(p, p): the pivoted QR of Bᵀ (`systems_linalg.pivoted_qr`), and the SVD's work."""
W_SVD_WORK = 28
"""(p, p): the SVD's second work matrix."""
W_SINGULAR = 29
"""(p,): B's singular values."""
W_KEEP = 30
"""(1 + p,) int: which singular values are kept, and how many (at p)."""
W_SVD_U = 31
"""(m, kk): B's left singular vectors."""
W_SVD_V = 32
"""(nv, kk): B's right singular vectors."""
W_COLUMN = 33
"""(nv,): a column, a row, a vector of nv."""
W_Q = 34
"""(nq,) where the system has couplings, else (0,): the coordinates for the couplings' rows."""
W_H = 35
"""(nv,): the bias forces h."""
W_ROWS = 36
"""(m,): a vector of m."""
W_DELTA = 37
"""(max(nq, nv),): the projection's correction."""
W_ORDER = 38
"""(1 + p,) int: the QR's column order, and the rank (at p)."""
W_REFLECTORS = 39
"""(p,): the QR's Householder factors."""
W_COMPOSITE = 40
"""(n, INERTIA_SIZE): the composite inertias (CRBA)."""
W_Z = 41
"""(kk, kk): a kk × kk scratch."""
W_REFERENCE = 42
"""(3,) m: the point positions are measured from (`systems.tree.reference_point`)."""
WORKSPACE_SLOTS = 43
