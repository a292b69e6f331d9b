"""How much volume the overlapping pieces of a mesh share, measured from their union (manifold3d,
imported only when pieces overlap), and the union itself, which `massprops.repair.union` keeps as
the ``--union`` repair's result. Measuring is part of the health check; using the union as the
solid is a repair."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from massprops.mesh.pieces import Pieces, Welded, split_pieces
from massprops.mesh.value import Mesh
from massprops.tolerances import BOOLEAN_VOLUME_RTOL

if TYPE_CHECKING:  # imported at run time only when pieces overlap
    import manifold3d


def overlap_warning(mesh: Mesh, volumes: np.ndarray, overlaps: list[tuple[int, int]]) -> str:
    """The health check's line for a mesh whose pieces overlap (pieces as `prepare_mesh` numbers
    them, ``volumes`` their signed volumes m³): how much volume is counted more than once,
    measured from the union, or bounded by the smaller piece of each overlapping pair when the
    union cannot be formed."""
    total = float(volumes.sum())
    try:
        w = Welded.of(mesh)
        composed = compose(w, split_pieces(w))
        united = composed.result.volume() + sum(composed.skipped_volumes)
    except ImportError:
        united = None
    if united is not None and -BOOLEAN_VOLUME_RTOL * abs(total) <= total - united <= abs(total):
        extra = max(total - united, 0.0)  # else the boolean misbehaved: give the bound below
        return (f"the pieces share {extra:.3g} m³ ({_percent(extra, total)} of the {total:.6g} m³ "
                f"reported), measured from their union: that volume is counted more than once; "
                f"--union counts it once")
    bound = sum(min(abs(volumes[o]), abs(volumes[i])) for o, i in overlaps)
    return (f"the pieces share at most {bound:.3g} m³ ({_percent(bound, total)} of the "
            f"{total:.6g} m³ reported; the smaller piece of each overlapping pair), counted more "
            f"than once; --union counts it once")


# --- the boolean ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Composed:
    result: manifold3d.Manifold
    solids: list[int]
    cavities: list[int]
    skipped: list[int]
    skipped_volumes: list[float]
    lines: tuple[str, ...]
    warnings: tuple[str, ...]


def compose(w: Welded, pieces: Pieces) -> Composed:
    """Each solid minus the cavities that cut into it without swallowing it, all united."""
    import manifold3d as mf

    operands, skipped, lines = {}, [], []
    order = np.argsort(pieces.label, kind="stable")
    bounds = np.searchsorted(pieces.label[order], np.arange(pieces.count + 1))
    for k in range(pieces.count):
        rows = order[bounds[k]:bounds[k + 1]]
        reason = None
        if not pieces.closed[k]:
            reason = f"it is not a closed 2-manifold by itself ({pieces.why_open(k)})"
        elif pieces.volumes[k] == 0:
            reason = "it encloses no volume"
        else:
            made = _manifold(mf, w, rows, reverse=pieces.volumes[k] < 0)
            status = made.status()
            if status != mf.Error.NoError:
                reason = f"manifold3d refused it ({status.name})"
            else:
                operands[k] = made
        if reason is not None:
            skipped.append(k)
            lines.append(f"piece {k + 1} ({rows.size} triangles, volume "
                         f"{pieces.volumes[k]:.6g} m³): {reason}; added as it is")
    solids = [k for k in operands if pieces.volumes[k] > 0]
    cavities = [k for k in operands if pieces.volumes[k] < 0]
    boxes = {k: np.array(m.bounding_box()).reshape(2, 3) for k, m in operands.items()}
    used = set()
    groups = []
    for s in solids:
        cut = [c for c in cavities if _boxes_meet(boxes[s], boxes[c])
               and not (operands[s] - operands[c]).is_empty()]
        used.update(cut)
        if cut:
            holes = mf.Manifold.batch_boolean([operands[c] for c in cut], mf.OpType.Add)
            groups.append(operands[s] - holes)
        else:
            groups.append(operands[s])
    result = mf.Manifold.batch_boolean(groups, mf.OpType.Add) if groups else mf.Manifold()
    warnings = [f"piece {k + 1} of {pieces.count} is not closed by itself and cannot be "
                f"united: {line.split(': ', 1)[1]}" for k, line in zip(skipped, lines)]
    warnings += [f"piece {c + 1} (a cavity: faces inward) cuts into no solid piece; the union "
                 f"leaves it out ({-pieces.volumes[c]:.6g} m³ no longer subtracted)"
                 for c in cavities if c not in used]
    return Composed(result, solids, cavities, skipped,
                     [float(pieces.volumes[k]) for k in skipped], tuple(lines), tuple(warnings))


def _manifold(mf, w: Welded, rows: np.ndarray, reverse: bool):
    """A manifold3d.Manifold of the triangles ``rows`` (float64 positions, their own vertices),
    each result triangle tagged with the row it came from."""
    uniq, local = np.unique(w.tri[rows], return_inverse=True)
    tris = local.reshape(-1, 3)
    if reverse:
        tris = tris[:, ::-1]
    return mf.Manifold(mf.Mesh64(vert_properties=np.ascontiguousarray(w.positions[uniq]),
                                 tri_verts=np.ascontiguousarray(tris, dtype=np.uint64),
                                 face_id=np.ascontiguousarray(rows, dtype=np.uint64)))


def _boxes_meet(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.all(a[0] <= b[1]) and np.all(b[0] <= a[1]))


def _percent(part: float, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"
