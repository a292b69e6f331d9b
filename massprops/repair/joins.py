"""Where the faces of a wall meet (``--shell``): the mitre added at each edge, and the regions of
the thin-wall model's error bar at edges and corners. The model and the formulas are stated in
`massprops.repair.shell`; this module evaluates them edge by edge, in blocks.

Two passes, so that no array of per-edge boxes is ever held: `joins` (before the centre of mass
is known) sums the mitre corrections and keeps, per edge and per vertex, only the volume and
radius of its error region; `JoinRegions.sums` (after) turns those into the bars' sums about
the centre of mass, block by block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from massprops.mesh.facesums import gamma
from massprops.mesh.pieces import Welded
from massprops.repair.bars import RegionSums, reach_sums

CHUNK = 1 << 15
"""Edges or vertices per block: a block's temporaries stay in cache."""


@dataclass(frozen=True, eq=False)
class JoinRegions:
    """Error regions: segment (u, v) of welded ids (a vertex: u == v) widened by ``radius``
    (k,) m, holding a volume (k,) m³."""

    u: np.ndarray
    v: np.ndarray
    volume: np.ndarray
    radius: np.ndarray

    @property
    def total(self) -> float:
        return float(self.volume.sum())

    def sums(self, positions: np.ndarray, centre: np.ndarray) -> RegionSums:
        """The `RegionSums` about ``centre`` (3,) m, block by block."""
        out = RegionSums()
        columns = np.ascontiguousarray(positions.T)
        c = centre[:, None]
        for lo in range(0, self.volume.size, CHUNK):
            a = columns[:, self.u[lo:lo + CHUNK]]
            b = columns[:, self.v[lo:lo + CHUNK]]
            # |x - c| <= |midpoint - c| + half the segment's extent + the radius, per axis
            reach = np.abs((a + b) / 2 - c) + np.abs(a - b) / 2 + self.radius[lo:lo + CHUNK]
            out = out + reach_sums(self.volume[lo:lo + CHUNK], reach * (1 + 4 * 2.0**-53))
        return out

    @staticmethod
    def join(*parts: JoinRegions) -> JoinRegions:
        return JoinRegions(*(np.concatenate([getattr(p, f) for p in parts])
                             for f in ("u", "v", "volume", "radius")))


@dataclass(frozen=True, eq=False)
class Joins:
    """Mitre corrections per unit density about the origin: first (3,) m⁴ (Σ ∫x dV), second
    (3, 3) m⁵ (Σ ∫x xᵀ dV), each with a rounding bound; the error regions of edges and corners;
    counts of mitred, folded (not mirrored) and crowded (> 2 faces) edges."""

    first: np.ndarray
    second: np.ndarray
    err_first: np.ndarray
    err_second: np.ndarray
    regions: JoinRegions
    mitred: int
    folded: int
    crowded: int


def unit_normals(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit normals (f, 3), twice the areas (f,)) of triangles p (f, 3 corners, 3); a
    zero-area triangle's normal is 0."""
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n2 = np.sqrt(np.einsum("ij,ij->i", n, n))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n2[:, None] > 0, n / n2[:, None], 0.0), n2


def joins(w: Welded, normals: np.ndarray, doubled: np.ndarray, origin: np.ndarray,
          thickness: float) -> Joins:
    """Mitres and error regions of the mesh ``w`` as a wall of ``thickness`` m (``normals`` (m, 3)
    and ``doubled`` (m,): every face's unit normal and twice its area)."""
    e = w.edges
    two = np.flatnonzero(e.count == 2)
    first, second = np.zeros(3), np.zeros((3, 3))
    err_first, err_second = np.zeros(3), np.zeros((3, 3))
    volume, radius = np.zeros(two.size), np.zeros(two.size)
    turning = e.count > 2
    mitred = folded = 0
    for lo in range(0, two.size, CHUNK):
        b = _edge_block(w, two[lo:lo + CHUNK], normals, doubled, origin, thickness)
        first += b.first
        second += b.second
        err_first += b.err_first
        err_second += b.err_second
        volume[lo:lo + CHUNK], radius[lo:lo + CHUNK] = b.volume, b.radius
        turning[two[lo:lo + CHUNK]] = b.turning
        mitred += b.mitred
        folded += b.folded
    keep = volume > 0
    edges = JoinRegions(e.u[two[keep]], e.v[two[keep]], volume[keep] * (1 + 1e-9), radius[keep])
    crowd = np.flatnonzero(e.count > 2)
    if crowd.size:
        length = np.linalg.norm(w.positions[e.v[crowd]] - w.positions[e.u[crowd]], axis=1)
        height = _longest_height(w, crowd, doubled, length)
        edges = JoinRegions.join(edges, JoinRegions(
            e.u[crowd], e.v[crowd],
            e.count[crowd] * thickness * np.minimum(height, thickness) * length * (1 + 1e-9),
            np.full(crowd.size, 1.5 * thickness)))
    corners = _corners(w, normals, doubled, thickness, turning)
    return Joins(first, second, err_first, err_second, JoinRegions.join(edges, corners), mitred,
                 folded, int(crowd.size))


@dataclass(frozen=True, eq=False)
class _EdgeBlock:
    first: np.ndarray
    second: np.ndarray
    err_first: np.ndarray
    err_second: np.ndarray
    volume: np.ndarray
    radius: np.ndarray
    turning: np.ndarray
    mitred: int
    folded: int


def _edge_block(w: Welded, two: np.ndarray, normals: np.ndarray, doubled: np.ndarray,
                origin: np.ndarray, thickness: float) -> _EdgeBlock:
    """Edges ``two`` (each of exactly two faces): the mitre's moments, the regions."""
    e, pos = w.edges, w.positions
    half_t = thickness / 2
    at = e.start[two]
    pu, pv = pos[e.u[two]], pos[e.v[two]]
    length = np.sqrt(np.einsum("ij,ij->i", pv - pu, pv - pu))
    f, g = e.face[at], e.face[at + 1]
    nf, ng = normals[f], normals[g]
    same_way = e.forward[at] == e.forward[at + 1]
    ng[same_way] *= -1  # wound against its neighbour: compare the two as one surface
    theta = np.arctan2(np.linalg.norm(np.cross(nf, ng), axis=1), np.einsum("ij,ij->i", nf, ng))
    with np.errstate(invalid="ignore", divide="ignore"):
        hf, hg = doubled[f] / length, doubled[g] / length  # heights of the faces over the edge
    tan_half = np.tan(theta / 2)
    reach = half_t * tan_half          # how far a kite runs along each face from the edge
    fits = (reach <= np.minimum(hf, hg)) & (theta > 0)
    # g's corner off the edge: on n_f's side, g turns toward n_f, and the gap is on the other
    opposite = pos[w.tri[g, (e.corner[at + 1] + 2) % 3]]
    side = -np.sign(np.einsum("ij,ij->i", opposite - pu, nf))
    bis = nf + ng
    bis_norm = np.sqrt(np.einsum("ij,ij->i", bis, bis))
    cos_half = np.cos(theta / 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        # ∫_kite y dy: area (T/2)² tan(θ/2), centroid (T/6)(cos(θ/2) + 1/cos(θ/2)) along the
        # bisector, on the gap's side
        scale = side * half_t * half_t * tan_half * thickness / 6 * (cos_half + 1 / cos_half)
        y = np.where(fits[:, None], (scale / bis_norm)[:, None] * bis, 0.0)
    mid = (pu + pv) / 2 - origin
    weight = 2 * length                 # Σ 2L y, Σ 2L (m yᵀ + y mᵀ): exact for quadratics
    first = weight @ y
    half = (mid * weight[:, None]).T @ y
    slack = gamma(40 + two.size)        # <= 40 roundings a term; a dot product one per term
    ay = np.abs(y)
    half_abs = (np.abs(mid) * weight[:, None]).T @ ay
    with np.errstate(invalid="ignore", divide="ignore"):
        radius = np.where(fits, half_t / cos_half, np.hypot(half_t, np.maximum(hf, hg)))
        bend = np.where(fits, half_t * half_t * np.maximum(tan_half - theta / 2, 0.0),
                        2 * half_t * np.minimum(np.nan_to_num(reach, nan=np.inf),
                                                np.maximum(hf, hg)))
    volume = np.where(theta > 0, bend, 0.0) * length
    return _EdgeBlock(first, half + half.T, slack * (weight @ ay),
                      slack * (half_abs + half_abs.T), volume, radius, theta > 0,
                      int(np.count_nonzero(fits)), int(np.count_nonzero(~fits & (theta > 0))))


def _longest_height(w: Welded, crowd: np.ndarray, doubled: np.ndarray, length: np.ndarray
                    ) -> np.ndarray:
    """(c,) the largest height over the edge of the faces at each crowded edge, m."""
    e = w.edges
    uses = np.concatenate([np.arange(e.start[k], e.start[k] + e.count[k]) for k in crowd])
    owner = np.repeat(np.arange(crowd.size), e.count[crowd])
    tallest = np.zeros(crowd.size)
    np.maximum.at(tallest, owner, doubled[e.face[uses]])
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(length > 0, tallest / length, 0.0)


def _corners(w: Welded, normals: np.ndarray, doubled: np.ndarray, thickness: float,
             turning: np.ndarray) -> JoinRegions:
    """One region per vertex whose faces are not all parallel (see `massprops.repair.shell`).
    The wall's layers there are at most as many as the planes meeting at the vertex, and those
    at most one more than its turning edges: that count is the multiplicity m."""
    rows = np.flatnonzero(w.valid)
    tri = w.tri[rows]
    k = w.reps.size
    n = normals[rows]
    weighted = n * doubled[rows, None]
    mean = np.zeros((k, 3))
    for corner in range(3):
        for i in range(3):
            mean[:, i] += np.bincount(tri[:, corner], weights=weighted[:, i], minlength=k)
    size = np.sqrt(np.einsum("ij,ij->i", mean, mean))
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(size[:, None] > 0, mean / size[:, None], 0.0)
    cos_b = np.ones(k)
    for corner in range(3):
        ids = tri[:, corner]
        np.minimum.at(cos_b, ids, np.abs(np.einsum("ij,ij->i", n, mean[ids])))
    cos_b = np.clip(cos_b, 0.0, 1.0)
    e = w.edges
    layers = 1 + np.bincount(e.u[turning], minlength=k) + np.bincount(e.v[turning], minlength=k)
    layers[np.bincount(tri.ravel(), minlength=k) == 0] = 0
    longest = np.zeros(k)
    length = np.linalg.norm(w.positions[e.v] - w.positions[e.u], axis=1)
    np.maximum.at(longest, e.u, length)
    np.maximum.at(longest, e.v, length)
    half_t = thickness / 2
    with np.errstate(divide="ignore"):
        radius = np.minimum(half_t / cos_b, half_t + longest)
    volume = layers * (4 * np.pi / 3) * radius**3 * np.minimum(1.0, 1.0 - cos_b)
    keep = np.flatnonzero(volume > 0)
    return JoinRegions(keep, keep, volume[keep] * (1 + 1e-9), radius[keep])
