"""The boundary loops of an open mesh, in a few words for the "not closed" refusal: how many, and
how large the largest is against the surface. (Capping them is a repair:
`massprops.repair.holes`.)"""

from __future__ import annotations

import numpy as np

from massprops.mesh.topology import Edges, connected_components


def describe_holes(edges: Edges, positions: np.ndarray, surface: float, *,
                   open_only: bool = False) -> str | None:
    """A few words on the holes of an open mesh for the "not closed" error: how many boundary
    loops, and the largest's edges and vector area against the surface area (m²).

    edges : the health check's `Edges` of the welded mesh; positions (u, 3):
    the position of each welded id; open_only : take the edges used once (the mesh was re-wound,
    so directions in ``edges`` are the file's) rather than the unbalanced ones. This is the
    default path's error message: vectorised, no loop in Python over the edges; the loops are the
    components of the boundary graph, each one's Newell vector area summed from its edges in any
    order (the surface's direction along the rim: consistent within a loop)."""
    if edges.forward is None:
        return None
    pick = (edges.uses == 1) if open_only else (edges.imbalance != 0)
    k = np.flatnonzero(pick)
    if not k.size:
        return None
    ahead = edges.imbalance[k] > 0
    a = np.where(ahead, edges.u[k], edges.v[k]).astype(np.int64)
    b = np.where(ahead, edges.v[k], edges.u[k]).astype(np.int64)
    n = positions.shape[0]
    root = connected_components(n, edges.u[k], edges.v[k])[a]  # u < v: the kernel's fast case
    counts = np.bincount(root, minlength=n)
    n_loops = int(np.count_nonzero(counts))
    origin = positions[a[0]]  # about a rim point: small products
    p, q = positions[a] - origin, positions[b] - origin
    size = np.zeros(n)
    for i, j in ((1, 2), (2, 0), (0, 1)):
        size += np.bincount(root, weights=p[:, i] * q[:, j] - p[:, j] * q[:, i], minlength=n) ** 2
    size = np.sqrt(size) / 2
    big = int(np.argmax(size))
    many = "1 boundary loop" if n_loops == 1 else f"{n_loops} boundary loops"
    return (f"{many}, the largest of {counts[big]} edges spanning {size[big]:.3g} m² "
            f"({_percent(size[big], surface)} of the surface area)")


def _percent(part: float, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"
