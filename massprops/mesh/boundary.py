"""The boundary loops of an open mesh, in a few words for the "not closed" refusal: how many, and
how large the largest is against the surface. (Capping them is a repair:
`massprops.repair.holes`.)"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from massprops.mesh.topology import Edges, connected_components


class Holes(NamedTuple):
    """``text``: the loops in words; ``largest``: the largest loop's vector area as a fraction
    of the surface area (a lower bound of its cap's: equal for a flat loop)."""

    text: str
    largest: float


def max_hole_for(fraction: float) -> float | None:
    """The ``max_hole`` (a fraction of the surface, 2 significant digits) that accepts a cap of
    ``fraction``: rounded up, with 0.1 % to spare for the cap's round-off; None beyond 1, the
    largest the option takes."""
    if not (math.isfinite(fraction) and fraction > 0):
        return None
    step = 10.0 ** (math.floor(math.log10(fraction * 1.001)) - 1)
    value = float(f"{math.ceil(fraction * 1.001 / step) * step:.2g}")
    return value if value <= 1 else None


def describe_holes(edges: Edges, positions: np.ndarray, surface: float, *,
                   open_only: bool = False) -> Holes | None:
    """The holes of an open mesh for the "not closed" error: how many boundary loops, and the
    largest's edges and vector area against the surface area (m²), in words and as a fraction.

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
    return Holes(f"{many}, the largest of {counts[big]} edges spanning {size[big]:.3g} m² "
                 f"({_percent(size[big], surface)} of the surface area)",
                 float(size[big] / surface) if surface > 0 else math.inf)


def _percent(part: float, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"
