"""Causes of a tensor given in the wrong frame, each solved for rather than guessed:

- ``about_point``: the tensor about a point p instead of the COM c. J_stated − J_com =
  m (|d|² I − d dᵀ) with d = p − c, so with D = (J_stated − J_com) / m, ½ tr(D) = |d|² and
  d dᵀ = ½ tr(D) I − D: d is the square root of that matrix's largest eigenpair (the least-squares
  rank-one fit when D carries noise), p = c ± d (both fit; the one nearer the link origin is
  named, the stated COM when it is that point);
- ``rotated``: stated = R computed Rᵀ. R = E_s G E_cᵀ from the two eigenframes, G block-diagonal
  over groups of equal moments (each block the orthogonal Procrustes fit of E_sᵀ E_c, so within a
  degenerate group the smallest turn is chosen), det R = +1;
- ``axes_permuted``: stated = P computed Pᵀ for one of the 48 signed permutations P (the COM
  permuted too, or not).
Each returns candidate models (causes, inertia, centres of mass to try) for `diagnose`.
"""

from __future__ import annotations

import itertools
import math
from typing import cast

import numpy as np

from massprops.inertia import parallel_axis

__all__ = ["about_point", "rotation", "SIGNED_PERMUTATIONS"]


def _signed_permutations() -> list[tuple[list[int], np.ndarray]]:
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            p = np.zeros((3, 3))
            for i, (j, s) in enumerate(zip(perm, signs)):
                p[i, j] = s
            out.append(([s * (j + 1) for j, s in zip(perm, signs)], p))
    out.sort(key=lambda e: (np.linalg.det(e[1]) < 0, sum(x < 0 for x in e[0])))
    return out[1:]  # the identity first, left out


SIGNED_PERMUTATIONS = _signed_permutations()
"""(signed 1-based axis indices, P) for the 47 signed permutations other than the identity,
proper ones first: stated axis i is ``sign · computed axis |p_i|``."""


def about_point(target: np.ndarray, inertia: np.ndarray, mass: float, com: np.ndarray,
                stated_com: np.ndarray):
    """[(cause, inertia about p, [COMs to try])] for the point p whose tensor best fits
    ``target`` (kg·m², link axes), or [] when no point does (D not of the form |d|²I − ddᵀ)."""
    d_mat = (target - inertia) / mass
    m = 0.5 * np.trace(d_mat) * np.eye(3) - d_mat
    values, vectors = np.linalg.eigh(0.5 * (m + m.T))
    if values[2] <= 0:
        return []
    d = math.sqrt(values[2]) * vectors[:, 2]
    points = [com + d, com - d]
    near_stated = [np.linalg.norm(p - stated_com) for p in points]
    # cast: max of a numpy float and a float has no common type in the stubs
    if min(near_stated) <= 1e-9 * cast(float, max(np.linalg.norm(d), 1e-300)):
        p = points[int(np.argmin(near_stated))]
        where = "the inertial frame's origin"
    else:
        p = min(points, key=lambda q: float(np.linalg.norm(q)))
        where = ("the link origin" if np.linalg.norm(p) <= 1e-6 * np.linalg.norm(d)
                 else "the point " + _vec(p))
    cause = ("about_point", {"point": p.tolist()},
             f"inertia about {where} ({np.linalg.norm(d):.3g} m from the COM)")
    return [(cause, parallel_axis(inertia, mass, p - com), [com, p])]


def rotation(target: np.ndarray, inertia: np.ndarray, com: np.ndarray, rtol: float):
    """[(cause, R J Rᵀ, [COMs])]: the signed permutations and the turn R whose image of
    ``inertia`` may fit ``target``; [] when the principal moments differ by more than ``rtol``."""
    lt, et = np.linalg.eigh(0.5 * (target + target.T))
    lc, ec = np.linalg.eigh(0.5 * (inertia + inertia.T))
    scale = float(np.max(np.abs(lc))) or 1.0
    if np.max(np.abs(lt - lc)) > rtol * scale:
        return []
    out = []
    for signed, p in SIGNED_PERMUTATIONS:
        out.append((("axes_permuted", {"permutation": signed},
                     f"axes permuted {signed} (stated axis i = computed axis p_i)"),
                    p @ inertia @ p.T, [com, p @ com]))
    m = et.T @ ec
    g = np.zeros((3, 3))
    groups = _groups(lc, rtol * scale)
    for grp in groups:
        u, _, vt = np.linalg.svd(m[np.ix_(grp, grp)])
        g[np.ix_(grp, grp)] = u @ vt
    r = et @ g @ ec.T
    if np.linalg.det(r) < 0:
        # flip the axis whose alignment is weakest (a sign of a principal axis is free)
        k = int(np.argmin(np.abs(np.diag(et.T @ r @ ec))))
        g[:, k] *= -1
        r = et @ g @ ec.T
    angle = math.acos(max(-1.0, min(1.0, (np.trace(r) - 1) / 2)))
    if angle > 1e-9:
        axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        n = np.linalg.norm(axis)
        about = f" about {_vec(axis / n)}" if n > 1e-12 else ""
        out.append((("rotated", {"rotation": r.tolist()},
                     f"the tensor turned by {math.degrees(angle):.3g}°{about}"),
                    r @ inertia @ r.T, [com, r @ com]))
    return out


def _groups(moments: np.ndarray, gap: float) -> list[list[int]]:
    groups = [[0]]
    for i in (1, 2):
        if moments[i] - moments[groups[-1][-1]] <= gap:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def _vec(v: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.3g}" for x in v) + "]"
