"""Checks every reader applies to the arrays it parsed, each failing with one line naming the file.

``where`` arguments are callables turning an item number (vertex, face or index token, 0-based)
into the place a user can look at, e.g. ``"line 12"``; they run only when a check fails.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from massprops.errors import MeshFormatError

Where = Callable[[int], str]


def require_content(n_vertices: int, n_faces: int, name: str) -> None:
    """Raise unless the file defined at least one vertex and one face."""
    if n_vertices == 0 or n_faces == 0:
        raise MeshFormatError(
            f"{name}: found {n_vertices} vertices and {n_faces} faces; expected a surface mesh "
            f"(vertices and faces)"
        )


def require_finite(vertices: np.ndarray, name: str, where: Where) -> None:
    """Raise naming the first vertex with a NaN or infinite coordinate.

    vertices : (n, 3) float64.
    """
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        coords = " ".join(repr(float(c)) for c in vertices[i])
        raise MeshFormatError(
            f"{name}: {where(i)}: vertex {i + 1} has a non-finite coordinate ({coords}); "
            f"expected finite numbers"
        )


def require_polygon_sizes(sizes: np.ndarray, name: str, where: Where) -> None:
    """Raise naming the first face with fewer than 3 vertices.

    sizes : (p,) int, vertex count of each face.
    """
    small = sizes < 3
    if small.any():
        i = int(np.argmax(small))
        raise MeshFormatError(
            f"{name}: {where(i)}: face {i + 1} has {int(sizes[i])} vertex indices; "
            f"expected at least 3"
        )


def one_based_indices(
    raw: np.ndarray,
    n_vertices: int,
    name: str,
    where: Where,
    relative_base: Callable[[], np.ndarray] | None = None,
) -> np.ndarray:
    """0-based int64 indices from a 1-based format's index tokens, range-checked.

    raw : (T,) int64 as written in the file.
    where : item number is the token number in ``raw``.
    relative_base : for formats with relative indices (OBJ: -1 is the latest vertex), a callable
        returning (T,) int64, the number of vertices defined before each token's line; None means
        negative indices are errors.
    """
    zero = raw == 0
    if zero.any():
        k = int(np.argmax(zero))
        raise MeshFormatError(
            f"{name}: {where(k)}: vertex index 0; this format counts vertices from 1 "
            f"(expected 1..{n_vertices})"
        )
    index = raw - 1
    negative = raw < 0
    if relative_base is not None and negative.any():
        index = np.where(negative, relative_base() + raw, index)
    return require_in_range(index, n_vertices, name, where, shown=raw)


def require_in_range(
    index: np.ndarray, n_vertices: int, name: str, where: Where, shown: np.ndarray | None = None
) -> np.ndarray:
    """``index`` (0-based int64) after checking 0 <= index < n_vertices; returns it.

    shown : the values as the file wrote them, for the message (default ``index``).
    """
    bad = (index < 0) | (index >= n_vertices)
    if bad.any():
        k = int(np.argmax(bad))
        value = int((index if shown is None else shown)[k])
        raise MeshFormatError(
            f"{name}: {where(k)}: vertex index {value} is out of range; the file defines "
            f"{n_vertices} vertices"
        )
    return index
