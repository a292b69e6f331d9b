"""``--union``: replace overlapping and nested pieces by the solid they occupy together.

The boolean is manifold3d's (imported here only; DESIGN.md says why that engine). Its topology
is decided by one consistent symbolic perturbation, so the result is always a closed 2-manifold;
its new vertices (where surfaces cross) are rounded float64 interpolations. We do not take their
accuracy on trust: every result triangle keeps the id of the input triangle it lies in
(manifold3d's ``face_id``), and the distance of each of its vertices from that triangle's plane
is measured. Moving a triangle off its plane by at most δ changes any ∫g dV by at most
area · δ · max|g| (the slab between the triangle and its projection), so those distances become
the union's error bar (`massprops.repair.bars`). The result is integrated by the exact integral.

What is united: the pieces of `massprops.mesh.pieces` (the surface cut at non-manifold
edges). Each solid piece loses the cavities that cut into it but do not swallow it whole, then
all solids are united: a cavity stays empty, a solid inside a cavity (a rattle) stays solid.
A piece that is not a closed 2-manifold by itself cannot be an operand: it is added as it is
(counted as before) and named.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from massprops.errors import ComputationError, setting_ref
from massprops.mesh import Mesh
from massprops.mesh.overlap import Composed, compose
from massprops.mesh.pieces import Pieces, Welded, split_pieces
from massprops.repair.bars import Regions
from massprops.tolerances import BOOLEAN_VOLUME_RTOL

U = 2.0**-53


@dataclass(frozen=True)
class UnionRecord:
    """What ``--union`` did (the ``repairs.union`` JSON object).

    pieces : pieces found; unioned : closed pieces given to the boolean (cavities among them:
    cavities); skipped : one line per piece added as it is, with the reason.
    volume_before : m³, the sum of the pieces' signed volumes (what is reported without --union).
    volume_after : m³, the integral of the result. max_displacement : m, the farthest a result
    vertex lies from the plane of the input face it came from (0: no vertex moved).
    triangles : triangles of the result.
    """

    pieces: int
    unioned: int
    cavities: int
    skipped: tuple[str, ...]
    volume_before: float
    volume_after: float | None
    max_displacement: float
    triangles: int

    def as_dict(self) -> dict:
        after = self.volume_after
        return {"pieces": self.pieces, "unioned": self.unioned, "cavities": self.cavities,
                "skipped": list(self.skipped), "volume_before": self.volume_before,
                "volume_after": after,
                "counted_twice": None if after is None else self.volume_before - after,
                "max_displacement": self.max_displacement, "triangles": self.triangles}


@dataclass(frozen=True, eq=False)
class UnionResult:
    """The mesh to integrate, the record (``volume_after`` still None), the error regions and
    warnings."""

    mesh: Mesh
    record: UnionRecord
    regions: Regions
    warnings: tuple[str, ...]


def union_mesh(mesh: Mesh) -> UnionResult:
    """Unite the pieces of ``mesh`` (closed pieces outward, cavities inward: as
    `massprops.mesh.health.prepare_mesh` returns them). A single piece is returned unchanged."""
    w = Welded.of(mesh)
    pieces = split_pieces(w)
    if pieces.count <= 1:
        record = UnionRecord(pieces.count, 0, 0, (), float(pieces.volumes.sum()), None, 0.0,
                             int(mesh.faces.shape[0]))
        return UnionResult(mesh, record, Regions.none(), ())
    composed = compose(w, pieces)
    _check_volume(composed, pieces, mesh.name)
    out = composed.result.to_mesh64()
    verts = np.ascontiguousarray(out.vert_properties[:, :3], dtype=np.float64)
    tris = np.asarray(out.tri_verts, dtype=np.int64).reshape(-1, 3)
    source = np.asarray(out.face_id, dtype=np.int64)
    delta, area = _displacement(verts, tris, source, mesh)
    moved = np.flatnonzero(delta > 0)
    corners = verts[tris[moved]]
    pad = delta[moved, None]
    regions = Regions(area[moved] * delta[moved] * (1 + 8 * U),
                      corners.min(axis=1) - pad, corners.max(axis=1) + pad)
    kept = np.concatenate([pieces.rows(k) for k in composed.skipped]) if composed.skipped \
        else np.zeros(0, np.int64)
    result = _joined(mesh, verts, tris, kept)
    record = UnionRecord(pieces.count, len(composed.solids) + len(composed.cavities),
                         len(composed.cavities), composed.lines, float(pieces.volumes.sum()), None,
                         float(delta.max(initial=0.0)), int(result.faces.shape[0]))
    return UnionResult(result, record, regions, composed.warnings)


def finished(record: UnionRecord, volume_after: float) -> UnionRecord:
    """The record with the integral of the result; a single piece was not touched, so its
    volume before is that same integral (not the rougher per-piece sum)."""
    before = record.volume_before if record.pieces > 1 else float(volume_after)
    return replace(record, volume_before=before, volume_after=float(volume_after))


def _percent(part: float, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"


def _check_volume(composed: Composed, pieces: Pieces, name: str) -> None:
    """A union holds no more than its solids together: the boolean's volume (its own float sum)
    beyond that by more than rounding means its result cannot be trusted (input pieces that
    cut through themselves, which no boolean defines)."""
    solids = float(sum(pieces.volumes[k] for k in composed.solids))
    united = composed.result.volume()
    if united > solids * (1 + BOOLEAN_VOLUME_RTOL) or united < 0:
        raise ComputationError(f"{name}: the union of the pieces came out at {united:.6g} m³, "
                               f"not within 0..{solids:.6g} m³ (the solids together): some "
                               f"piece probably intersects itself; repair it, or inspect without "
                               f"{setting_ref('union')} (overlaps then count twice)")


# --- the result ----------------------------------------------------------------------------------
def _displacement(verts: np.ndarray, tris: np.ndarray, source: np.ndarray, mesh: Mesh
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(δ (t,), area (t,)): a bound of the distance of each result triangle's vertices from the
    plane of its source face (0 where every vertex is a vertex of that face, bit for bit), and
    an upper bound of each result triangle's area, m and m²; in cache-sized blocks."""
    delta, area = np.empty(tris.shape[0]), np.empty(tris.shape[0])
    for lo in range(0, tris.shape[0], _BLOCK):
        hi = min(lo + _BLOCK, tris.shape[0])
        delta[lo:hi], area[lo:hi] = _block_displacement(verts[tris[lo:hi]],
                                                        mesh.vertices[mesh.faces[source[lo:hi]]])
    return delta, area


_BLOCK = 1 << 14


def _block_displacement(q: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q (t, 3 corners, 3) result triangles, p (t, 3, 3) their source faces."""
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    n = np.cross(e1, e2)
    nn = np.sqrt(np.einsum("ij,ij->i", n, n))
    scale = np.sqrt(np.einsum("ij,ij->i", e1, e1) * np.einsum("ij,ij->i", e2, e2))
    rel = q - p[:, None, 0]
    dist = np.abs(np.einsum("tk,tck->tc", n, rel))
    reach = np.sqrt(np.einsum("tck,tck->tc", rel, rel))
    with np.errstate(divide="ignore", invalid="ignore"):
        # n·w computed: each n_i is off by <= 4u |e1||e2| (edges, products, difference), the dot
        # adds 3u |n||w|, w itself u|w|: 16u |w||e1||e2| covers them, divided by |n| after.
        bound = (dist + 16 * U * reach * scale[:, None]) / nn[:, None] * (1 + 4 * U)
    bound = np.where(nn[:, None] > 0, bound, reach)  # a zero-area source: its corner's distance
    same = ((q[:, :, None, :] == p[:, None, :, :]).all(axis=3)).any(axis=2)
    delta = np.where(same, 0.0, bound).max(axis=1)
    c = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
    return delta, np.sqrt(np.einsum("ij,ij->i", c, c)) / 2 * (1 + 8 * U)


def _joined(mesh: Mesh, verts: np.ndarray, tris: np.ndarray, kept: np.ndarray) -> Mesh:
    """The union's triangles, then the skipped pieces' triangles as they were."""
    if kept.size:
        used, local = np.unique(mesh.faces[kept], return_inverse=True)
        verts = np.concatenate([verts, mesh.vertices[used]])
        tris = np.concatenate([tris, local.reshape(-1, 3) + (verts.shape[0] - used.size)])
    return replace(mesh, vertices=np.ascontiguousarray(verts),
                   faces=np.ascontiguousarray(tris, dtype=np.int64), polygon_sizes=None)
