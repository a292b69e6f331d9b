"""--union against exact rational truth: inclusion-exclusion of boxes, a tetrahedron cut by a box
face, cavities and a rattle; invariances for shapes without a closed form."""

from __future__ import annotations

import math
from fractions import Fraction as Q

import numpy as np
import pytest
from exact_moments import Moments, box_intersection, tetrahedron
from exact_moments import box as exact_box
from exact_moments import mesh as exact_mesh
from repair_meshes import box, icosphere, join, moved, rotation

from massprops.errors import MeshTopologyError
from massprops.inspection.file import inspect_mesh
from massprops.mesh import Mesh
from massprops.repair import RepairOptions

UNION = RepairOptions(union=True)


def bars(props):
    """Total error bar: rounding + input + repair, per quantity."""
    u = props.uncertainty
    parts = [b for b in (u.rounding, u.input, u.repair) if b is not None]
    return {k: sum(np.asarray(getattr(b, k), dtype=float) for b in parts)
            for k in ("volume", "mass", "center_of_mass", "inertia", "principal_moments")}


def assert_matches(props, truth: Moments, rho=1.0, extra=0.0):
    """props agrees with the exact moments within its own error bars (+ ``extra`` relative, for
    a truth that is itself only float-accurate), and the bars are not vacuous (< 1e-9)."""
    b = bars(props)
    size = float(truth.volume)
    assert abs(props.volume - size) <= b["volume"] + extra * size + 4e-16 * size
    com, j = truth.com(), rho * truth.inertia()
    scale_c = np.abs(com).max() + size ** (1 / 3)
    np.testing.assert_array_less(np.abs(props.center_of_mass - com),
                                 b["center_of_mass"] + (extra + 4e-16) * scale_c)
    scale_j = np.abs(j).max()
    np.testing.assert_array_less(np.abs(props.inertia - j),
                                 b["inertia"] + (extra + 4e-16) * scale_j)
    assert b["volume"] < 1e-9 * size and b["inertia"].max() < 1e-9 * scale_j


def union_of_boxes(boxes) -> Moments:
    """Inclusion-exclusion over every subset (boxes intersect in boxes)."""
    total = None
    n = len(boxes)
    for mask in range(1, 1 << n):
        chosen = [boxes[i] for i in range(n) if mask >> i & 1]
        meet = box_intersection(*[(np.array(lo, float), np.array(hi, float)) for lo, hi in chosen])
        if meet is None:
            continue
        term = exact_box(*meet).scaled((-1) ** (len(chosen) + 1))
        total = term if total is None else total + term
    return total


@pytest.mark.parametrize("boxes", [
    [((0, 0, 0), (2, 2, 2)), ((1, 1, 1), (3, 3.5, 3))],
    [((0, 0, 0), (1, 1, 1)), ((0.3, 0.1, -0.2), (1.7, 0.6, 0.9)),
     ((0.5, -0.4, 0.25), (0.9, 1.3, 0.7))],
    [((0, 0, 0), (2, 1, 1)), ((0.5, 0, 0), (1.5, 1, 1))],        # shared faces (coplanar)
    [((-1e3, 2, 5), (-999.9, 2.1, 5.3)), ((-999.95, 2.05, 5.1), (-999.8, 2.2, 5.2))],  # far, small
], ids=["two", "three", "coplanar", "far-small"])
def test_union_of_boxes_is_inclusion_exclusion(boxes):
    mesh = join(*(box(lo, hi) for lo, hi in boxes))
    result = inspect_mesh(mesh, density=2.5, repairs=UNION)
    assert_matches(result.properties, union_of_boxes(boxes), rho=2.5)
    record = result.repairs["union"].as_dict()
    assert record["pieces"] == len(boxes) and record["unioned"] == len(boxes)
    naive = sum(float(exact_box(lo, hi).volume) for lo, hi in boxes)
    assert record["volume_before"] == pytest.approx(naive, rel=1e-14)
    assert record["counted_twice"] == pytest.approx(naive - float(union_of_boxes(boxes).volume),
                                                    rel=1e-9, abs=1e-15)
    assert not any("counted twice" in w for w in result.warnings)


def test_tetrahedron_through_a_box_face_is_exact_within_the_boolean_bar():
    """A corner of a tetrahedron pokes into a box through the face x = 1: the intersection is the
    small tetrahedron spanned by that corner and the three points where its edges cross x = 1
    (rational, not floats: manifold3d rounds them, and the bar must cover that)."""
    corner = np.array([0.8, 0.37, 0.41])
    far = np.array([[1.9, 0.2, 0.3], [1.7, 0.71, 0.25], [1.8, 0.33, 0.77]])
    tet = np.vstack([corner, far])
    tet_mesh = Mesh(tet, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), name="tet")
    if exact_mesh(tet, tet_mesh.faces).volume < 0:
        tet_mesh = Mesh(tet, tet_mesh.faces[:, ::-1].copy(), name="tet")
    cq = [Q(float(x)) for x in corner]
    crossings = []
    for p in far:
        pq = [Q(float(x)) for x in p]
        t = (1 - cq[0]) / (pq[0] - cq[0])
        crossings.append([cq[i] + t * (pq[i] - cq[i]) for i in range(3)])
    small = _tetra_fraction([cq, *crossings])
    truth = exact_box((0, 0, 0), (1, 1, 1)) + tetrahedron(tet) - small
    result = inspect_mesh(join(box(), tet_mesh), repairs=UNION)
    assert_matches(result.properties, truth)
    assert result.repairs["union"].max_displacement > 0  # new vertices: the bar is not zero
    assert result.properties.uncertainty.repair.volume > 0


def _tetra_fraction(points) -> Moments:
    """Exact moments of a tetrahedron with fraction corners (the mesh formula, 4 faces)."""
    vol = Q(0)
    first = [Q(0)] * 3
    second = [[Q(0)] * 3 for _ in range(3)]
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    sign = None
    for attempt in (faces, [f[::-1] for f in faces]):
        vol, first, second = Q(0), [Q(0)] * 3, [[Q(0)] * 3 for _ in range(3)]
        for f in attempt:
            a, b, c = (points[i] for i in f)
            d = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                 + a[2] * (b[0] * c[1] - b[1] * c[0]))
            s = [a[i] + b[i] + c[i] for i in range(3)]
            vol += d / 6
            first = [first[i] + d * s[i] / 24 for i in range(3)]
            for i in range(3):
                for j in range(3):
                    second[i][j] += d * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j]
                                         + s[i] * s[j]) / 120
        sign = vol > 0
        if sign:
            break
    return Moments(vol, first, second)


def test_cavity_stays_empty_and_a_rattle_stays_solid():
    """Hollow box [0,4]³ minus [1,3]³; a bar poking into the cavity and out through the wall; a
    small solid floating in the cavity. The cavity is cut from the bar too (it stays empty), the
    rattle, swallowed whole by the cavity, is kept."""
    outer, cavity = ((0, 0, 0), (4, 4, 4)), ((1, 1, 1), (3, 3, 3))
    bar, rattle = ((2.5, 1.5, 1.5), (5, 2.5, 2.5)), ((1.2, 1.2, 1.2), (1.8, 1.8, 1.8))
    mesh = join(box(*outer), box(*cavity, inward=True), box(*bar), box(*rattle))
    b = exact_box
    truth = (b(*outer) + b(*bar) - b((2.5, 1.5, 1.5), (4, 2.5, 2.5)) - b(*cavity)
             + b((2.5, 1.5, 1.5), (3, 2.5, 2.5)) - b((2.5, 1.5, 1.5), (3, 2.5, 2.5)) + b(*rattle))
    result = inspect_mesh(mesh, repairs=UNION)
    assert_matches(result.properties, truth)
    record = result.repairs["union"]
    assert record.cavities == 1 and record.pieces == 4
    assert record.volume_before == pytest.approx(64 - 8 + 2.5 + 0.216)


def test_single_piece_is_left_as_it_is():
    mesh = moved(icosphere(2), rotation((1, 2, 3), 0.4), (5, -3, 2))
    plain = inspect_mesh(mesh)
    result = inspect_mesh(mesh, repairs=UNION)
    assert result.properties.volume == plain.properties.volume
    np.testing.assert_array_equal(result.properties.inertia, plain.properties.inertia)
    assert result.repairs["union"].as_dict()["pieces"] == 1
    assert result.repairs["union"].as_dict()["counted_twice"] == 0.0


def test_separate_pieces_sum_as_before():
    """No overlap: the union is the sum (same solid), within the bars."""
    mesh = join(box((0, 0, 0), (1, 1, 1)), box((2, 0, 0), (3, 2, 1)), box((0, 0, 1), (1, 1, 2)))
    truth = exact_box((0, 0, 0), (1, 1, 1)) + exact_box((2, 0, 0), (3, 2, 1)) + exact_box(
        (0, 0, 1), (1, 1, 2))
    assert_matches(inspect_mesh(mesh, repairs=UNION).properties, truth)


def test_a_piece_that_is_not_closed_is_added_as_it_is_and_named():
    """An open box (one face missing) beside an overlapping pair: with --allow-open the open
    piece cannot be an operand; it is counted as before and named, the others are united."""
    open_box = box((5, 0, 0), (6, 1, 1))
    open_box = Mesh(open_box.vertices, open_box.faces[2:], name="open")
    mesh = join(box((0, 0, 0), (2, 2, 2)), box((1, 1, 1), (3, 3, 3)), open_box)
    with pytest.raises(MeshTopologyError):
        inspect_mesh(mesh, repairs=UNION)
    result = inspect_mesh(mesh, repairs=UNION, allow_open=True)
    record = result.repairs["union"]
    assert record.unioned == 2 and len(record.skipped) == 1
    assert "piece 3 (10 triangles" in record.skipped[0]
    assert "not a closed 2-manifold by itself (4 boundary edges)" in record.skipped[0]
    assert any("piece 3 of 3 is not closed by itself and cannot be united" in w
               for w in result.warnings)


def test_solids_touching_along_an_edge_are_united_as_two_pieces():
    """Two cubes sharing one edge (a non-manifold edge in one connected piece): cut there, each
    is closed, and the union is their sum."""
    mesh = join(box((0, 0, 0), (1, 1, 1)), box((1, 1, 0), (2, 2, 1)))
    result = inspect_mesh(mesh, repairs=UNION)
    assert result.repairs["union"].unioned == 2
    assert_matches(result.properties, exact_box((0, 0, 0), (1, 1, 1)) + exact_box((1, 1, 0),
                                                                                  (2, 2, 1)))


def test_union_is_invariant_under_rotation_and_translation():
    """Convex-decomposition-like: five overlapping rotated boxes and two spheres. No closed form:
    moving the whole part rigidly must move its mass properties with it (J -> R J Rᵀ)."""
    parts = [moved(box((0, 0, 0), (2, 0.4, 0.4)), rotation((0, 0, 1), 0.3 * k),
                   (0.2 * k, 0.1 * k, 0)) for k in range(5)]
    parts += [moved(icosphere(2, 0.5), shift=(0.5, 0.2, 0.3)),
              moved(icosphere(2, 0.4), shift=(1.9, 0.7, 0.1))]
    mesh = join(*parts)
    r, t = rotation((0.3, -1, 2), 1.1), np.array([100.0, -50.0, 25.0])
    a = inspect_mesh(mesh, repairs=UNION)
    b = inspect_mesh(moved(mesh, r, t), repairs=UNION)
    pa, pb = a.properties, b.properties
    assert a.repairs["union"].volume_after < a.repairs["union"].volume_before
    tol = 1e-12
    assert pb.volume == pytest.approx(pa.volume, rel=tol)
    np.testing.assert_allclose(pb.center_of_mass, r @ pa.center_of_mass + t, atol=tol * 100)
    np.testing.assert_allclose(pb.inertia, r @ pa.inertia @ r.T,
                               atol=tol * np.abs(pa.inertia).max())
    bar = bars(pa)
    assert bar["volume"] < 1e-12 * pa.volume  # the boolean's rounding, measured, is tiny


def test_default_warning_measures_the_shared_volume_and_names_union():
    boxes = [((0, 0, 0), (2, 2, 2)), ((1, 1, 1), (3, 3.5, 3))]
    result = inspect_mesh(join(*(box(lo, hi) for lo, hi in boxes)))
    shared = 1.0  # [1, 2]³
    line = [w for w in result.warnings if w.startswith("the pieces share")]
    assert line == [f"the pieces share {shared:.3g} m³ ({100 * shared / 18:.3g}% of the 18 m³ "
                    f"reported), measured from their union: that volume is counted more than "
                    f"once; --union counts it once"]
    assert result.repairs is None and result.properties.volume == pytest.approx(18.0)


def shared_line(result) -> list[str]:
    return [w for w in result.warnings if w.startswith("the pieces share")]


@pytest.mark.parametrize("height", [0.6, 0.5], ids=["taller", "flush-degenerate"])
def test_bars_crossing_with_no_vertex_inside_each_other_are_found_and_measured(height):
    """A plus sign: no vertex of either bar lies inside the other (the vertex samples see
    nothing), yet 1 m³ is counted twice. With equal heights the bars' top faces are coplanar
    and every edge crossing is degenerate; the interior probe finds it all the same."""
    result = inspect_mesh(join(box((-2, -0.5, -0.5), (2, 0.5, 0.5)),
                               box((-0.5, -2, -height), (0.5, 2, height))))
    shared = 1.0  # [-0.5, 0.5]³, in closed form
    total = 4.0 + 4.0 * 2 * height
    assert any(w.startswith("components 1 and 2 overlap (their surfaces cross")
               for w in result.warnings)
    assert shared_line(result) == [f"the pieces share {shared:.3g} m³ ({100 * shared / total:.3g}"
                                   f"% of the {total:.6g} m³ reported), measured from their "
                                   f"union: that volume is counted more than once; --union "
                                   f"counts it once"]


def test_an_x_of_turned_bars_shares_the_rhombus_prism_of_closed_form():
    angle, width, height = 0.7, 0.6, 0.6
    bar = box((-2, -width / 2, -height / 2), (2, width / 2, height / 2))
    result = inspect_mesh(join(bar, moved(bar, rotation((0, 0, 1), angle))))
    (line,) = shared_line(result)
    shared = width**2 / math.sin(angle) * height  # the rhombus of two strips, times the height
    assert line.startswith(f"the pieces share {shared:.3g} m³")


def test_pieces_that_touch_or_only_share_a_bounding_box_are_not_overlaps():
    touching = join(box((0, 0, 0), (1, 1, 1)), box((1, 0.2, 0.2), (2, 0.8, 0.8)))
    # a thin bar across the corner of a cube, 0.42 m past it: their boxes share a volume
    corner = moved(box((-1, -0.05, -0.05), (1, 0.05, 0.05)), rotation((0, 0, 1), -math.pi / 4),
                   (1.3, 1.3, 0.5))
    apart = join(box((0, 0, 0), (1, 1, 1)), corner)
    for mesh in (touching, apart):
        result = inspect_mesh(mesh)
        assert not [w for w in result.warnings if "overlap" in w or "share" in w], \
            result.warnings


def test_modes_combine_in_order_fill_then_unite_then_wall():
    """Two overlapping cubes, the second missing a face: capped, united (inclusion-exclusion);
    then as a wall: the united surface has area 2 × (24 - 3) = 42 (each cube loses three unit
    squares inside the other), so the mass is exactly ρ T 42 (mitres add no mass)."""
    second = box((1, 1, 1), (3, 3, 3))
    second = Mesh(second.vertices, second.faces[2:], name="open")
    mesh = join(box((0, 0, 0), (2, 2, 2)), second)
    both = RepairOptions(fill_holes=True, max_hole=0.25, union=True)
    result = inspect_mesh(mesh, repairs=both)
    assert_matches(result.properties, union_of_boxes([((0, 0, 0), (2, 2, 2)),
                                                      ((1, 1, 1), (3, 3, 3))]))
    assert list(result.repairs) == ["fill_holes", "union"]
    wall = inspect_mesh(mesh, density=7.0, repairs=RepairOptions(fill_holes=True, max_hole=0.25,
                                                                 union=True, shell=0.01))
    assert list(wall.repairs) == ["fill_holes", "union", "shell"]
    assert wall.properties.mass == pytest.approx(7.0 * 0.01 * 42, rel=1e-14)
    assert wall.repairs["union"].volume_after == pytest.approx(15.0, rel=1e-14)
    np.testing.assert_allclose(wall.properties.center_of_mass, [1.5, 1.5, 1.5], atol=1e-14)


def test_two_spheres_union_is_bracketed_by_the_closed_form_of_balls():
    """Two icospheres (circumradius 1) 1 apart. Each contains the ball of its inradius and lies in
    the unit ball, so their union's volume lies between the unions of two balls of those radii:
    2 (4/3) π r³ minus the lens π (4r + d)(2r - d)² / 12. The icosphere is symmetric under each
    coordinate's reflection, so the union's centre of mass is the midpoint and J_xy = 0."""
    d = 1.0
    one = icosphere(3)
    tri = one.vertices[one.faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    r_in = float(np.min(np.abs(np.einsum("ij,ij->i", normal, tri[:, 0]))
                        / np.linalg.norm(normal, axis=1)))

    def balls(r):
        return 2 * 4 / 3 * np.pi * r**3 - np.pi * (4 * r + d) * (2 * r - d) ** 2 / 12

    result = inspect_mesh(join(one, moved(one, shift=(d, 0, 0))), repairs=UNION)
    p = result.properties
    b = bars(p)
    assert balls(r_in) - b["volume"] <= p.volume <= balls(1.0) + b["volume"]
    np.testing.assert_allclose(p.center_of_mass, [d / 2, 0, 0], atol=b["center_of_mass"].max()
                               + 1e-14)
    assert abs(p.inertia[0, 1]) <= b["inertia"][0, 1] + 1e-14
    assert result.repairs["union"].as_dict()["counted_twice"] > 0
