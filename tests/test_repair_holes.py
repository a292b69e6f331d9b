"""--fill-holes against exact rational truth: a cube missing a face, prisms with non-star-shaped
open tops, a planar face with a C-shaped hole; the refusal of an opening; a scanned-like sphere
with holes against its intact self (exact rational volume); the triangulators by enumeration."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from conftest import said_by_cli
from exact_moments import box as exact_box
from exact_moments import mesh as exact_mesh
from exact_moments import prism
from repair_meshes import box, hemisphere_bowl, icosphere, without
from test_repair_union import assert_matches, bars

from massprops.errors import MeshTopologyError
from massprops.inspection.file import inspect_mesh
from massprops.mesh import Mesh
from massprops.mesh.boundary import max_hole_for
from massprops.repair import RepairOptions
from massprops.repair.holes import fill_holes
from massprops.repair.triangulate import ear_clip, is_simple, min_area, plane_frame

FILL = RepairOptions(fill_holes=True)


def fill(max_hole=None) -> RepairOptions:
    return RepairOptions(fill_holes=True, max_hole=max_hole)


def test_cube_missing_a_face_is_capped_to_the_cube_exactly():
    cube = box((0, 0, 0), (1, 2, 3))
    for rows in ([0, 1], [4, 5], [10, 11]):
        holed = without(cube, rows)
        result = inspect_mesh(holed, repairs=fill(0.5))
        assert_matches(result.properties, exact_box((0, 0, 0), (1, 2, 3)))
        record = result.repairs["fill_holes"].as_dict()
        assert record["holes"] == 1 and record["boundary_edges"] == 4
        assert record["cap_volume_spread"] == 0.0  # a planar rim between square neighbours
        assert result.health.closed


def c_shape() -> np.ndarray:
    """A "C" (counter-clockwise): no point of it sees the whole outline, so a fan from any
    corner folds over itself."""
    return np.array([[0, 0], [3, 0], [3, 1], [1, 1], [1, 2], [3, 2], [3, 3], [0, 3]], float) * 0.37


def prism_mesh(xy: np.ndarray, height: float, *, top: bool = True) -> Mesh:
    """A prism over a simple counter-clockwise polygon: bottom fanned by the caller's choice
    (an ear-clipped list below), the walls, and (if ``top``) the top."""
    k = len(xy)
    v = np.concatenate([np.column_stack([xy, np.zeros(k)]),
                        np.column_stack([xy, np.full(k, height)])])
    ears = _hand_triangulation(k)
    i = np.arange(k)
    j = (i + 1) % k
    faces = [ears[:, ::-1], np.stack([i, j, j + k], 1), np.stack([i, j + k, i + k], 1)]
    if top:
        faces.append(ears + k)
    return Mesh(v, np.concatenate(faces).astype(np.int64), name="prism")


def _hand_triangulation(k: int) -> np.ndarray:
    """Triangles of the C shape written out by hand (counter-clockwise)."""
    assert k == 8
    return np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 7], [4, 5, 6], [4, 6, 7]])


def test_non_star_shaped_open_top_is_capped_exactly():
    xy = c_shape()
    truth = prism(xy, 0, 0.5)
    result = inspect_mesh(prism_mesh(xy, 0.5, top=False), repairs=fill(0.5))
    assert_matches(result.properties, truth)
    assert result.repairs["fill_holes"].ear_clipped == 1


def test_c_shaped_hole_in_a_flat_face_is_capped_exactly():
    """The top face of a box has a C-shaped hole (the face around it triangulated by manifold3d's
    polygon triangulator, an independent library): capping gives the box back exactly, and the
    rim's neighbours are flat, so the bar is zero."""
    import manifold3d as mf

    outer = np.array([[-1, -1], [2, -1], [2, 2], [-1, 2]], float)
    hole = c_shape()[::-1]  # clockwise: a hole
    ring = mf.triangulate([outer, hole])
    flat = np.concatenate([outer, hole])
    k = flat.shape[0]
    v = np.concatenate([np.column_stack([flat, np.full(k, 1.0)]),
                        [[-1, -1, 0], [2, -1, 0], [2, 2, 0], [-1, 2, 0]]])
    b0 = k
    sides = []
    for a, b in ((0, 1), (1, 2), (2, 3), (3, 0)):
        sides += [[a, b0 + a, b0 + b], [a, b0 + b, b]]
    faces = np.concatenate([np.asarray(ring, dtype=np.int64),
                            np.array([[b0, b0 + 2, b0 + 1], [b0, b0 + 3, b0 + 2]]),
                            np.array(sides)])
    mesh = Mesh(v, faces.astype(np.int64), name="holed")
    truth = exact_box((-1, -1, 0), (2, 2, 1))
    assert exact_mesh(v, faces).volume < truth.volume  # the hole's cap is missing
    result = inspect_mesh(mesh, repairs=FILL)
    assert_matches(result.properties, truth)
    assert result.repairs["fill_holes"].cap_volume_spread == 0.0


def test_opening_is_refused_naming_its_length_and_area():
    """A hemispherical bowl's rim is a regular 32-gon of radius 1: perimeter 64 sin(π/32),
    cap area 16 sin(π/16); the bowl's own area is about 2π, so the cap is about half of it."""
    bowl = hemisphere_bowl(32)
    with pytest.raises(MeshTopologyError) as err:
        inspect_mesh(bowl, repairs=FILL)
    tri = bowl.vertices[bowl.faces]
    surface = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                             axis=1).sum() / 2
    length, cap = 64 * math.sin(math.pi / 32), 16 * math.sin(math.pi / 16)
    assert said_by_cli(err.value) == (
        f"bowl: boundary loop 1 of 1 (32 edges, length {length:.6g} m) would need a cap of "
        f"{cap:.6g} m², {100 * cap / surface:.3g}% of the surface area: too large to be a hole "
        f"(limit 0.1 of the surface; raise it with --max-hole "
        f"{max_hole_for(cap / surface):g}, or use --shell for a thin-walled or open part)")
    inspect_mesh(bowl, repairs=fill(max_hole_for(cap / surface)))  # what it says works
    result = inspect_mesh(bowl, repairs=fill(0.9))  # asked for: a flat cap, exact
    truth = exact_mesh(np.concatenate([bowl.vertices]), np.concatenate(
        [bowl.faces, [[0, (i + 1) % 32, i] for i in range(1, 32)]]))
    assert_matches(result.properties, truth)


def test_allow_open_leaves_the_opening_and_caps_the_holes():
    bowl = hemisphere_bowl()
    top = np.argmax(bowl.vertices[bowl.faces][:, :, 2].min(axis=1))
    holed = without(bowl, [top])
    result = inspect_mesh(holed, repairs=FILL, allow_open=True)
    record = result.repairs["fill_holes"]
    assert record.holes == 1 and len(record.left_open) == 1
    assert any(w.startswith("left open: boundary loop") for w in result.warnings)


def test_scanned_like_sphere_with_holes_against_its_intact_self():
    """A noisy sphere (radii jittered by 1 %) with eight holes of one to six triangles: capped,
    its volume and moments must agree with the intact mesh's exact rational values within the
    error bar (which covers caps up to a dome continuing the neighbours' slope)."""
    rng = np.random.default_rng(7)
    s = icosphere(3)
    v = s.vertices * (1 + 0.01 * rng.standard_normal(s.vertices.shape[0]))[:, None]
    intact = Mesh(v, s.faces, name="scan")
    truth = exact_mesh(v, s.faces)
    removed = set()
    for seed in rng.choice(s.faces.shape[0], 8, replace=False):
        patch = [seed] + list(np.flatnonzero(np.isin(s.faces, s.faces[seed]).sum(axis=1) == 2))
        removed.update(patch[: 1 + rng.integers(0, 6)])
    holed = without(intact, sorted(removed))
    with pytest.raises(MeshTopologyError, match="use fill_holes to cap them"):
        inspect_mesh(holed)
    result = inspect_mesh(holed, repairs=FILL)
    p = result.properties
    b = bars(p)
    assert abs(p.volume - float(truth.volume)) <= b["volume"]
    assert np.all(np.abs(p.center_of_mass - truth.com()) <= b["center_of_mass"])
    assert np.all(np.abs(p.inertia - truth.inertia()) <= b["inertia"])
    record = result.repairs["fill_holes"]
    assert record.holes >= 5 and 0 < record.area_fraction < 0.05
    assert 0 < record.cap_volume_spread < 0.01 * p.volume  # honest, and not vacuous


def test_holes_in_a_polygon_mesh_keep_its_polygons():
    quads = box((0, 0, 0), (1, 1, 1))
    holed = without(quads, [0, 1])
    closed = fill_holes(holed, max_fraction=0.5).mesh
    assert closed.faces.shape[0] == 12


# --- the triangulators ----------------------------------------------------------------------------
def _triangulations(k: int):
    """Every triangulation of a convex k-gon's index polygon (Catalan many), as triangle lists."""
    if k < 3:
        yield []
        return

    def rec(i, j):
        if j - i < 2:
            yield []
            return
        for m in range(i + 1, j):
            for left in rec(i, m):
                for right in rec(m, j):
                    yield left + right + [(i, m, j)]

    yield from rec(0, k - 1)


def _area(points, tris) -> float:
    p = points[np.asarray(tris)]
    return float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum() / 2)


@pytest.mark.parametrize("k", [4, 5, 6, 7])
def test_min_area_is_the_least_of_all_triangulations(k):
    rng = np.random.default_rng(k)
    t = 2 * np.pi * np.arange(k) / k
    points = np.column_stack([np.cos(t), np.sin(t), 0.6 * rng.standard_normal(k)])  # skew rim
    best = min(_area(points, tris) for tris in _triangulations(k))
    got = min_area(points)
    assert got.shape == (k - 2, 3)
    assert _area(points, got) == pytest.approx(best, rel=1e-14)


def test_ear_clipping_covers_a_non_star_polygon_without_overlap():
    xy = c_shape()
    assert is_simple(xy)
    tri = ear_clip(xy)
    p = xy[tri]
    signed = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
              - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])) / 2
    assert np.all(signed > 0)  # no folded triangle
    x, y = xy[:, 0], xy[:, 1]
    shoelace = (np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2
    assert signed.sum() == pytest.approx(shoelace, rel=1e-15)
    edges = {tuple(sorted(e)) for t in tri for e in itertools.combinations(t, 2)}
    assert all(tuple(sorted((i, (i + 1) % len(xy)))) in edges for i in range(len(xy)))


def test_a_rim_that_crosses_itself_in_every_view_is_capped_by_dynamic_programming():
    """A loop going twice around (a doubled circle climbing a helix): its outline is not simple
    in the best-fit plane, so the cap is the least-area triangulation."""
    k = 16
    t = 4 * np.pi * np.arange(k) / k
    points = np.column_stack([np.cos(t) * (1 + 0.1 * np.arange(k) / k), np.sin(t),
                              0.2 * np.sin(t / 2)])
    centre, normal, axes = plane_frame(points)
    assert not is_simple((points - centre) @ axes.T)
    from massprops.repair.holes import _cap

    tri, how = _cap(points)
    assert how == "dp" and tri.shape == (k - 2, 3)
