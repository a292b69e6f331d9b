"""Mesh health: every field against hand-counted topology and closed-form volumes."""

from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np
import pytest
from conftest import said_by_cli
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.errors import DegenerateMeshError, MeshFormatError, MeshTopologyError
from massprops.mesh.geometry import winding_numbers
from massprops.mesh.health import MeshHealth, check_mesh, prepare_mesh
from massprops.mesh.topology import connected_components
from massprops.mesh.value import Mesh, fan_triangulate
from massprops.mesh.weld import weld

# Unit-cube corners are numbered 4x + 2y + z; these quads wind counter-clockwise seen from outside.
CUBE_QUADS = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]


def corners(lo=(0, 0, 0), hi=(1, 1, 1)) -> np.ndarray:
    return np.array([[(lo[0], hi[0])[i >> 2], (lo[1], hi[1])[(i >> 1) & 1], (lo[2], hi[2])[i & 1]]
                     for i in range(8)], dtype=np.float64)


def from_polygons(vertices, polygons, name="mesh") -> Mesh:
    faces, sizes = fan_triangulate(np.concatenate([list(p) for p in polygons]),
                                   np.array([len(p) for p in polygons]))
    return Mesh(np.asarray(vertices, dtype=np.float64), faces, sizes, name=name)


def box(lo=(0, 0, 0), hi=(1, 1, 1), *, quads=False, inward=False, name="box") -> Mesh:
    polys = [p[::-1] if inward else p for p in CUBE_QUADS]
    if not quads:
        polys = [t for p in polys for t in ([p[0], p[1], p[2]], [p[0], p[2], p[3]])]
    return from_polygons(corners(lo, hi), polys, name)


def join(*meshes: Mesh, name="joined") -> Mesh:
    """Concatenate meshes as one file would hold them (vertices not shared between parts)."""
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    return Mesh(np.concatenate([m.vertices for m in meshes]),
                np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]), name=name)


def cyclic_equal(p, q) -> bool:
    p, q = list(map(int, p)), list(map(int, q))
    return len(p) == len(q) and any(p == q[k:] + q[:k] for k in range(len(q)))


TETRA = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64),
             np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), name="tetra")

CLEAN = dict(unique_vertices=None, duplicate_vertices=0, unreferenced_vertices=0,
             degenerate_faces=0, closed=True, boundary_edges=0, manifold=True,
             nonmanifold_edges=0, oriented=True, cavities=0, flipped=False, rewound_faces=0,
             warnings=())


def expect(**fields) -> dict:
    out = dict(CLEAN)
    out.update(fields)
    if out["unique_vertices"] is None:
        out["unique_vertices"] = out["vertices"]
    return out


def assert_health(h: MeshHealth, expected: dict) -> None:
    got = {k: getattr(h, k) for k in expected}
    vols = expected.get("component_volumes")
    if vols is not None:
        assert got.pop("component_volumes") == pytest.approx(vols, rel=1e-12, abs=1e-12)
        expected = {k: v for k, v in expected.items() if k != "component_volumes"}
    assert got == expected


# --- closed, outward: returned unchanged --------------------------------------------------------
VALID = {
    "tetrahedron": (TETRA, expect(vertices=4, faces=4, triangles=4, components=1,
                                  component_volumes=(1 / 6,))),
    "cube-triangles": (box(), expect(vertices=8, faces=12, triangles=12, components=1,
                                     component_volumes=(1.0,))),
    "cube-quads": (box(quads=True), expect(vertices=8, faces=6, triangles=12, components=1,
                                           component_volumes=(1.0,))),
    "two-disjoint-cubes": (join(box(), box((3, 0, 0), (5, 2, 2))),
                           expect(vertices=16, faces=24, triangles=24, components=2,
                                  component_volumes=(1.0, 8.0))),
    "cube-with-cavity": (join(box((0, 0, 0), (3, 3, 3)), box((1, 1, 1), (2, 2, 2), inward=True)),
                         expect(vertices=16, faces=24, triangles=24, components=2, cavities=1,
                                component_volumes=(27.0, -1.0))),
    "island-in-cavity": (join(box((0, 0, 0), (5, 5, 5)), box((1, 1, 1), (4, 4, 4), inward=True),
                              box((2, 2, 2), (3, 3, 3))),
                         expect(vertices=24, faces=36, triangles=36, components=3, cavities=1,
                                component_volumes=(125.0, -27.0, 1.0))),
}


@pytest.mark.parametrize("mesh, fields", VALID.values(), ids=VALID.keys())
def test_valid_solid_is_returned_unchanged(mesh, fields):
    fixed, health = prepare_mesh(mesh)
    assert fixed is mesh
    assert_health(health, fields)
    assert_health(check_mesh(mesh), fields)


# --- inside out ---------------------------------------------------------------------------------
def hexagonal_prism(inward=False) -> Mesh:
    """Regular hexagon of side 1 (area 3√3/2) extruded 2: volume 3√3, mixed polygon sizes."""
    ring = [(math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)) for k in range(6)]
    verts = [(x, y, 0.0) for x, y in ring] + [(x, y, 2.0) for x, y in ring]
    polys = [list(range(5, -1, -1)), list(range(6, 12))]
    polys += [[k, (k + 1) % 6, (k + 1) % 6 + 6, k + 6] for k in range(6)]
    return from_polygons(verts, [p[::-1] for p in polys] if inward else polys, "prism")


INSIDE_OUT = {
    "tetrahedron": (Mesh(TETRA.vertices, TETRA.faces[:, ::-1].copy()), 1 / 6),
    "cube-triangles": (box(inward=True), 1.0),
    "cube-quads": (box(quads=True, inward=True), 1.0),
    "hexagonal-prism": (hexagonal_prism(inward=True), 3 * math.sqrt(3)),
    "two-disjoint-cubes": (join(box(inward=True), box((2, 0, 0), (3, 1, 1), inward=True)), 2.0),
}


@pytest.mark.parametrize("mesh, volume", INSIDE_OUT.values(), ids=INSIDE_OUT.keys())
def test_inside_out_mesh_is_flipped(mesh, volume):
    fixed, health = prepare_mesh(mesh)
    assert health.flipped and health.warnings == ("faces pointed inward; flipped",)
    assert sum(health.component_volumes) == pytest.approx(volume, rel=1e-12)
    assert sum(check_mesh(mesh).component_volumes) == pytest.approx(-volume, rel=1e-12)
    assert "faces point inward" in check_mesh(mesh).warnings[0]
    # Every file polygon comes back reversed, and the layout is still its fan triangulation.
    for before, after in zip(mesh.polygons(), fixed.polygons()):
        assert cyclic_equal(after, before[::-1])
    faces, _ = fan_triangulate(*fixed.polygons_flat())
    assert np.array_equal(faces, fixed.faces)
    assert check_mesh(fixed).closed and sum(check_mesh(fixed).component_volumes) > 0


def test_inverted_part_among_two_is_flipped_alone():
    mesh = join(box(), box((2, 0, 0), (3, 1, 1), inward=True))
    fixed, health = prepare_mesh(mesh)
    assert health.component_volumes == pytest.approx((1.0, 1.0))
    assert not health.flipped and health.cavities == 0
    assert health.warnings == ("component 2 of 2 (signed volume -1 m³) faced inward but lies "
                               "inside no solid part; flipped it",)
    assert np.array_equal(fixed.faces[:12], mesh.faces[:12])
    assert np.array_equal(fixed.faces[12:], mesh.faces[12:, ::-1])


def test_many_inverted_parts_are_flipped_and_reported_five_at_a_time():
    parts = [box()] + [box((2 * k, 0, 0), (2 * k + 1, 1, 1), inward=True) for k in range(1, 8)]
    _, health = prepare_mesh(join(*parts))
    assert health.component_volumes == pytest.approx((1.0,) * 8)
    assert len(health.warnings) == 6 and health.warnings[-1] == "... and 2 more like it"
    assert health.warnings[0].startswith("component 2 of 8 ")


def test_hollow_cube_entirely_inside_out_is_flipped_as_a_whole():
    """Outer shell inward, cavity shell outward: the whole mesh is inside out, not two parts."""
    mesh = join(box((0, 0, 0), (3, 3, 3), inward=True), box((1, 1, 1), (2, 2, 2)))
    _, health = prepare_mesh(mesh)
    assert health.flipped and health.warnings == ("faces pointed inward; flipped",)
    assert health.component_volumes == pytest.approx((27.0, -1.0))
    assert health.cavities == 1


@pytest.mark.parametrize("inner", [((1, 1, 1), (3, 3, 3)), ((0.5, 0.5, 0.5), (1.5, 1.5, 1.5))],
                         ids=["overlapping", "nested"])
def test_overlapping_positive_parts_are_warned_counted_twice(inner):
    mesh = join(box((0, 0, 0), (2, 2, 2)), box(*inner))
    fixed, health = prepare_mesh(mesh)
    assert fixed is mesh and not health.flipped
    inner_volume = float(np.prod(np.subtract(inner[1], inner[0])))
    assert health.component_volumes == pytest.approx((8.0, inner_volume))
    assert len(health.warnings) == 2
    assert health.warnings[0].startswith("components 1 and 2 overlap or nest")
    assert "counted twice" in health.warnings[0]
    # the shared volume, measured from the union: the inner box lies inside [0, 2]³ up to 2
    shared = float(np.prod(np.minimum(inner[1], 2) - np.maximum(inner[0], 0)))
    assert health.warnings[1].startswith(f"the pieces share {shared:.3g} m³ (")
    assert health.warnings[1].endswith("counted more than once; --union counts it once")


def test_inverted_outer_shell_around_a_good_cavity_is_flipped_alone():
    """Depth decides: the outer shell holds nothing and faces inward, the cavity is right."""
    mesh = join(box((0, 0, 0), (3, 3, 3), inward=True), box((1, 1, 1), (2, 2, 2), inward=True))
    _, health = prepare_mesh(mesh)
    assert health.component_volumes == pytest.approx((27.0, -1.0)) and not health.flipped
    assert health.warnings == ("component 1 of 2 (signed volume -27 m³) faced inward but lies "
                               "inside no solid part; flipped it",)


def test_cavity_sticking_out_of_its_solid_is_warned():
    mesh = join(box((0, 0, 0), (2, 2, 2)), box((1, 1, 1), (3, 3, 3), inward=True))
    _, health = prepare_mesh(mesh)
    assert health.component_volumes == pytest.approx((8.0, -8.0))
    assert any("partly outside every solid part" in w for w in health.warnings)


def test_part_resting_on_another_is_not_an_overlap():
    """The upper box's bottom corners lie on the lower box's top face: winding 1/2 there is
    inconclusive and must not be read as nesting."""
    mesh = join(box(), box((0.25, 0.25, 1), (0.75, 0.75, 2)))
    fixed, health = prepare_mesh(mesh)
    assert fixed is mesh and health.warnings == ()
    assert health.component_volumes == pytest.approx((1.0, 0.25))


# --- open ---------------------------------------------------------------------------------------
def test_open_cube_is_refused_with_the_gap_counted():
    """One quad removed: its 4 sides are boundary edges (length 4); its diagonal went with it."""
    mesh = from_polygons(corners(), CUBE_QUADS[1:], "open.obj")
    with pytest.raises(MeshTopologyError) as err:
        prepare_mesh(mesh)
    assert err.value.settings == ("fill_holes", "max_hole", "shell", "allow_open")
    assert said_by_cli(err.value) == (
        "open.obj: mesh is not closed: 4 boundary edges (total length 4 m "
                              "in 1 boundary loop, the largest of 4 edges spanning 1 m² (20% of "
                              "the surface area)); use --fill-holes with --max-hole 0.21 to cap "
                              "them (the largest is above the default limit 0.1), --shell "
                              "THICKNESS for a thin-walled or open part, or --allow-open to "
                              "compute anyway")
    fixed, health = prepare_mesh(mesh, allow_open=True)
    assert fixed is mesh
    assert_health(health, dict(closed=False, boundary_edges=4, manifold=False, nonmanifold_edges=0,
                               oriented=True, components=1, faces=5, triangles=10, flipped=False))
    # About the box centre the hole is capped by a pyramid of volume 1 · (1/2) / 3 = 1/6.
    assert health.component_volumes == pytest.approx((5 / 6,))
    gap, meaning = health.warnings
    assert "4 boundary edges (total length 4 m)" in gap
    assert "= 1 m², 20% of the surface area" in gap  # |Σ a_f| = missing face, of 5 m²
    assert f"{math.sqrt(3) / 3:.3g} m³" in meaning  # |Σ a_f| · diagonal / 3


def test_open_mesh_facing_inward_is_flipped_under_allow_open():
    mesh = from_polygons(corners(), [p[::-1] for p in CUBE_QUADS[1:]])
    _, health = prepare_mesh(mesh, allow_open=True)
    assert health.flipped and health.component_volumes == pytest.approx((5 / 6,))
    assert "faces pointed inward; flipped" in health.warnings


# --- inconsistent winding -----------------------------------------------------------------------
@pytest.mark.parametrize("wrong, unbalanced", [({0}, 4), ({0, 1, 2}, 8), ({1, 3, 5}, 6),
                                               ({0, 1, 2, 3}, 8)],
                         ids=["one", "three-x0-x1-y0", "three-around-a-corner", "four"])
def test_rewound_faces_are_repaired(wrong, unbalanced):
    """``unbalanced`` counted by hand: edges between a wrong quad and a right one."""
    polys = [p[::-1] if k in wrong else p for k, p in enumerate(CUBE_QUADS)]
    mesh = from_polygons(corners(), polys, "rewound")
    fixed, health = prepare_mesh(mesh)
    assert_health(health, dict(closed=False, boundary_edges=unbalanced, manifold=True,
                               oriented=False, rewound_faces=len(wrong), flipped=False,
                               component_volumes=(1.0,),
                               warnings=(f"re-wound {len(wrong)} faces to a consistent "
                                         f"orientation",)))
    for got, want in zip(fixed.polygons(), CUBE_QUADS):
        assert cyclic_equal(got, want)


def test_rewound_polygons_keep_a_valid_fan_layout():
    prism = hexagonal_prism()
    flat, sizes = prism.polygons_flat()
    polys = np.split(flat, np.cumsum(sizes)[:-1])
    mesh = from_polygons(prism.vertices, [p[::-1] if k in (0, 3) else p
                                          for k, p in enumerate(polys)])
    fixed, health = prepare_mesh(mesh)
    assert health.rewound_faces == 2 and health.component_volumes == pytest.approx((3 * 3**0.5,))
    for got, want in zip(fixed.polygons(), polys):
        assert cyclic_equal(got, want)
    assert np.array_equal(fan_triangulate(*fixed.polygons_flat())[0], fixed.faces)


def test_randomly_rewound_torus_comes_back_outward():
    mesh = torus(24, 12)
    rng = np.random.default_rng(7)
    wrong = rng.random(mesh.faces.shape[0]) < 0.3
    faces = mesh.faces.copy()
    faces[wrong] = faces[wrong][:, ::-1]
    fixed, health = prepare_mesh(Mesh(mesh.vertices, faces))
    assert health.rewound_faces == np.count_nonzero(wrong)
    for got, want in zip(fixed.faces, mesh.faces):
        assert cyclic_equal(got, want)


def mobius(n=12) -> Mesh:
    """A strip of n quads whose last quad joins the first with a half twist."""
    t = np.arange(n) * 2 * np.pi / n
    centre = np.stack([np.cos(t), np.sin(t), 0 * t], 1)
    width = 0.3 * np.stack([np.cos(t / 2) * np.cos(t), np.cos(t / 2) * np.sin(t), np.sin(t / 2)], 1)
    verts = np.concatenate([centre - width, centre + width])  # i: lower edge, n + i: upper edge
    quads = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)] + [[n - 1, n, 0, 2 * n - 1]]
    return from_polygons(verts, quads, "mobius")


def klein_bottle(nu=8, nv=6) -> Mesh:
    """Grid nu×nv glued like a torus along v, with a reflection along u: closed, one-sided.
    Vertex positions are arbitrary distinct points (an immersion is not needed for topology)."""
    idx = lambda i, j: (i % nu) * nv + (j % nv if i < nu else (nv - j) % nv)  # noqa: E731
    quads = [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]
             for i in range(nu) for j in range(nv)]
    verts = np.random.default_rng(3).random((nu * nv, 3))
    return from_polygons(verts, quads, "klein")


@pytest.mark.parametrize("mesh", [mobius(), klein_bottle()], ids=["mobius-strip", "klein-bottle"])
@pytest.mark.parametrize("allow_open", [False, True], ids=["strict", "allow-open"])
def test_one_sided_surface_is_refused(mesh, allow_open):
    health = check_mesh(mesh)
    assert not health.closed and not health.oriented
    assert health.manifold == (mesh.name == "klein")
    with pytest.raises(MeshTopologyError, match="one-sided"):
        prepare_mesh(mesh, allow_open=allow_open)


# --- non-manifold but balanced ------------------------------------------------------------------
def test_cubes_sharing_an_edge_are_fine_with_a_note():
    mesh = join(box(), box((1, 1, 0), (2, 2, 1)))  # common edge x = y = 1
    fixed, health = prepare_mesh(mesh)
    assert fixed is mesh
    assert_health(health, expect(vertices=16, unique_vertices=14, duplicate_vertices=2, faces=24,
                                 triangles=24, manifold=False, nonmanifold_edges=1, components=1,
                                 component_volumes=(2.0,),
                                 warnings=("1 edge shared by more than two faces (solids touching "
                                           "along an edge); the integral is still exact",)))


def test_cubes_touching_at_a_vertex_are_fine_with_a_note():
    """V - E + F = 15 - 36 + 24 = 3: odd, so some vertex is not a disc."""
    _, health = prepare_mesh(join(box(), box((1, 1, 1), (2, 2, 2))))
    assert health.components == 1 and health.component_volumes == pytest.approx((2.0,))
    assert health.unique_vertices == 15 and health.manifold
    assert health.warnings == ("touches itself or another solid at a vertex (Euler characteristic "
                               "3, expected even and at most 2); the integral is still exact",)


# --- welding ------------------------------------------------------------------------------------
def test_split_vertices_at_seams_are_welded():
    """Each quad has its own four vertices (as UV seams make them); origin copies use -0.0."""
    verts, polys = [], []
    for q in CUBE_QUADS:
        polys.append(list(range(len(verts), len(verts) + 4)))
        verts += [corners()[i] for i in q]
    verts = np.array(verts)
    verts[verts == 0] = np.where(np.arange(np.count_nonzero(verts == 0)) % 2, -0.0, 0.0)
    _, health = prepare_mesh(from_polygons(verts, polys))
    assert_health(health, expect(vertices=24, unique_vertices=8, duplicate_vertices=16, faces=6,
                                 triangles=12, components=1, component_volumes=(1.0,)))


def test_stl_soup_is_welded():
    cube = box()
    soup = Mesh(cube.vertices[cube.faces].reshape(-1, 3), np.arange(36).reshape(12, 3))
    _, health = prepare_mesh(soup)
    assert_health(health, expect(vertices=36, unique_vertices=8, duplicate_vertices=28, faces=12,
                                 triangles=12, components=1, component_volumes=(1.0,)))


def test_degenerate_faces_duplicates_and_strays_are_counted_not_fatal():
    cube = box()
    verts = np.concatenate([cube.vertices, [[0, 0, 0], [0.5, 0.5, 0.5], [9, 9, 9]]])  # 8, 9, 10
    extra = [[0, 8, 1],  # repeated position (8 duplicates 0): zero area
             [0, 1, 1],  # repeated index
             [9, 9, 9]]  # a point
    mesh = Mesh(verts, np.concatenate([cube.faces, extra]))
    fixed, health = prepare_mesh(mesh)
    assert fixed is mesh
    # Positions: 8 corners, the centre (used by a degenerate face only), (9,9,9) (used by none).
    assert_health(health, expect(vertices=11, unique_vertices=10, duplicate_vertices=1,
                                 unreferenced_vertices=2, degenerate_faces=3, faces=15,
                                 triangles=15, components=1, component_volumes=(1.0,)))


@pytest.mark.parametrize("prefix_bits", [1, 6, 64], ids=["all-collide", "many-collide", "full"])
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_weld_matches_exact_grouping(prefix_bits, data):
    n = data.draw(st.integers(1, 60))
    values = st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 3.0, 2.0**-30])
    rows = [tuple(data.draw(st.tuples(values, values, values))) for _ in range(n)]
    inv, reps = weld(np.array(rows, dtype=np.float64), prefix_bits=prefix_bits)
    first_use: dict = {}
    for i, r in enumerate(rows):  # python floats: -0.0 == 0.0 and hash alike
        first_use.setdefault(r, i)
    order = sorted(set(first_use.values()))
    assert reps.tolist() == order
    assert inv.tolist() == [order.index(first_use[r]) for r in rows]


def test_weld_repairs_hash_collisions_at_scale():
    """An 8-bit hash prefix makes thousands of collisions; the grouping must not change."""
    mesh = torus(60, 30)
    soup = mesh.vertices[mesh.faces].reshape(-1, 3)
    exact_inv, exact_reps = weld(soup)
    inv, reps = weld(soup, prefix_bits=8)
    assert np.array_equal(inv, exact_inv) and np.array_equal(reps, exact_reps)
    assert np.array_equal(soup[reps[inv]], soup) and reps.size == 1800


# --- kernels against independent truth -----------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40).flatmap(lambda n: st.tuples(
    st.just(n), st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), max_size=60))))
def test_connected_components_match_union_find(graph):
    n, pairs = graph
    parent = list(range(n))

    def root(x):
        while parent[x] != x:
            x = parent[x]
        return x

    for a, b in pairs:
        ra, rb = root(a), root(b)
        parent[max(ra, rb)] = min(ra, rb)
    u = np.array([p[0] for p in pairs], dtype=np.int32)
    v = np.array([p[1] for p in pairs], dtype=np.int32)
    assert connected_components(n, u, v).tolist() == [root(x) for x in range(n)]


def test_winding_number_is_one_sixth_per_cube_face_from_the_centre():
    """Each face of a cube subtends 4π/6 at its centre; the cube gives 1 inside, 0 outside."""
    cube = box((-1, -1, -1), (1, 1, 1))
    tris = cube.vertices[cube.faces]
    points = np.array([[0, 0, 0], [0.5, -0.9, 0.2], [3, 0, 0], [0, 0, -1.5]], dtype=np.float64)
    assert winding_numbers(points, tris) == pytest.approx([1, 1, 0, 0], abs=1e-12)
    assert winding_numbers(points[:1], tris[:2]) == pytest.approx([1 / 6], abs=1e-12)
    assert winding_numbers(points[:1], tris[:, ::-1]) == pytest.approx([-1], abs=1e-12)
    on_surface = np.array([[0, 0, 1], [1, 1, 1], [0.3, -1, 0.2]], dtype=np.float64)
    assert np.isnan(winding_numbers(on_surface, tris)).all()


# --- errors -------------------------------------------------------------------------------------
def test_a_mesh_without_faces_is_refused():
    with pytest.raises(MeshTopologyError, match="empty.obj: mesh has no faces"):
        prepare_mesh(Mesh(np.zeros((4, 3)), np.empty((0, 3), np.int64), name="empty.obj"))


def test_check_mesh_of_an_empty_mesh_reports_zeros():
    health = check_mesh(Mesh(np.zeros((0, 3)), np.empty((0, 3), np.int64)))
    assert (health.vertices, health.faces, health.components, health.closed) == (0, 0, 0, True)
    assert health.component_volumes == ()


def test_a_mesh_on_three_positions_is_degenerate():
    two_sided = Mesh(TETRA.vertices[:3].copy(), np.array([[0, 1, 2], [0, 2, 1]]), name="tri")
    assert check_mesh(two_sided).closed
    with pytest.raises(DegenerateMeshError, match="tri: the faces span only 3 distinct"):
        prepare_mesh(two_sided)


def test_out_of_range_indices_are_a_format_error():
    with pytest.raises(MeshFormatError, match=r"bad: face vertex indices must lie in 0\.\.3"):
        check_mesh(Mesh(TETRA.vertices, TETRA.faces + 1, name="bad"))


# --- the fast path on a sizeable mesh -----------------------------------------------------------
def torus(nu, nv, big=1.0, small=0.3) -> Mesh:
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv,
                       indexing="ij")
    ring = big + small * np.cos(v)
    verts = np.stack([ring * np.cos(u), ring * np.sin(u), small * np.sin(v)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, (i + 1) % nu * nv + j
    c, d = (i + 1) % nu * nv + (j + 1) % nv, i * nv + (j + 1) % nv
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                            np.stack([a, c, d], -1).reshape(-1, 3)])
    return Mesh(verts, faces.astype(np.int64), name="torus")


def test_fast_path_on_a_shuffled_torus_soup():
    """20 000 positions, 40 000 triangles as unwelded soup in random order; V - E + F = 0."""
    mesh = torus(200, 100)
    rng = np.random.default_rng(1)
    tri = mesh.vertices[mesh.faces[rng.permutation(mesh.faces.shape[0])]]
    soup = Mesh(tri.reshape(-1, 3), np.arange(3 * 40_000).reshape(-1, 3), name="soup")
    fixed, health = prepare_mesh(soup)
    assert fixed is soup
    assert_health(health, expect(vertices=120_000, unique_vertices=20_000,
                                 duplicate_vertices=100_000, faces=40_000, triangles=40_000,
                                 components=1))
    # Chords of 2π/100 rad deviate from the smooth torus 2π²Rr² by ~1e-3 relative: band 1 %.
    assert health.component_volumes[0] / (2 * math.pi**2 * 0.3**2) == pytest.approx(1, rel=1e-2)


def test_polyhedral_volume_is_exact_on_rational_coordinates():
    """Integer coordinates: the exact volume by Fraction arithmetic over the same faces."""
    mesh = join(box((0, 0, 0), (3, 2, 5)), box((7, 1, 1), (8, 4, 2)))
    exact = Fraction(0)
    for f in mesh.faces.tolist():
        p, q, r = (mesh.vertices[k].astype(int).tolist() for k in f)
        exact += Fraction(p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
                          + p[2] * (q[0] * r[1] - q[1] * r[0]), 6)
    assert sum(prepare_mesh(mesh)[1].component_volumes) == float(exact) == 33.0


# --- the JSON object ----------------------------------------------------------------------------
def test_as_dict_is_plain_json_with_the_contract_keys():
    mesh = join(box(), box((1, 1, 1), (2, 2, 2)))
    out = prepare_mesh(mesh)[1].as_dict()
    assert {"vertices": 16, "faces": 24, "closed": True}.items() <= out.items()
    assert "warnings" not in out
    assert json.loads(json.dumps(out)) == out
    assert all(type(v) in (int, bool, list) for v in out.values())
    assert all(type(x) is float for x in out["component_volumes"])


def test_check_mesh_changes_nothing():
    mesh = box(quads=True, inward=True)
    before = (mesh.vertices.copy(), mesh.faces.copy(), mesh.polygon_sizes.copy())
    check_mesh(mesh)
    prepare_mesh(mesh)
    assert all(np.array_equal(x, y) for x, y in
               zip(before, (mesh.vertices, mesh.faces, mesh.polygon_sizes)))
