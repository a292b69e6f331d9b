"""The inertia doctor's validity tests (issue 32.1): each against a truth worked out by hand, and
a valid tensor shifted and turned a few times stays valid (the tolerance is round-off)."""

from __future__ import annotations

import json

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.inertia import parallel_axis, parallel_axis_to_com, rotate_inertia
from massprops.robot.doctor.bounds import bounds_of, primitive_points
from massprops.robot.doctor.validity import judge
from massprops.rotation import quat_to_matrix

BOX = bounds_of(primitive_points("box", (2.0, 2.0, 2.0)))  # the cube [-1, 1]³


def _box_inertia(m, a, b, c):
    return m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


@settings(max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(0.0, 2.0)] * 2), st.floats(0.01, 100.0),
       st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1),
                          st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
                min_size=1, max_size=4))
def test_a_valid_tensor_shifted_and_turned_a_few_times_stays_valid(dims, mass, moves):
    """A plate of zero thickness sits exactly on the triangle's edge (I3 = I1 + I2), a rod on
    the positive-definite one; turned by random rotations and shifted to points up to a body
    length away and back, neither fails."""
    a, b = 1.0, dims[0] * dims[1]  # b = 0: a flat plate a × dims[0] × 0, or a rod
    j = _box_inertia(mass, a, max(dims[0], 1e-3), b)
    for q0, q1, q2, q3, dx, dy, dz in moves:
        q = np.array([q0, q1, q2, q3]) + [1e-3, 0, 0, 0]
        r = quat_to_matrix(q / np.linalg.norm(q))
        d = np.array([dx, dy, dz])
        j = parallel_axis_to_com(parallel_axis(rotate_inertia(j, r), mass, d), mass, d)
    v = judge(mass, np.zeros(3), j, None)
    assert v.positive_definite and v.triangle, v.problems


def test_each_test_fails_on_its_own_defect():
    ok = _box_inertia(1.0, 1.0, 1.0, 1.0)
    assert judge(1.0, np.zeros(3), ok, BOX).as_dict() == {
        "positive_definite": True, "triangle": True, "com_inside": True, "realizable": True}
    broken = judge(1.0, np.zeros(3), np.diag([1.0, 1.0, 2.5]), None)  # 2.5 > 1 + 1
    assert (broken.positive_definite, broken.triangle, broken.com_inside) == (True, False, None)
    assert judge(1.0, np.zeros(3), np.diag([1.0, 1.0, -0.1]), None).positive_definite is False
    outside = judge(1.0, np.array([1.01, 0.0, 0.0]), ok, BOX)
    assert outside.com_inside is False and "outside the convex hull" in outside.problems[0]
    assert judge(1.0, np.array([0.99, 0.99, -0.99]), ok, BOX).com_inside is True


def test_realizability_is_exact_for_the_ellipsoid_around_the_geometry():
    """The cube's smallest ellipsoid is the ball of radius √3 (symmetry). A thin spherical
    shell of radius r about the centre has Σ = m r²/3 I, J = 2 m r²/3 I: Wensing's trace is
    m (1 − r²/3), so the shell is realizable inside the ball exactly when r <= √3; beyond it no
    non-negative density inside the cube has that inertia (exact side: False)."""
    for r, expected in ((1.70, True), (1.76, False)):
        v = judge(1.0, np.zeros(3), 2 / 3 * r * r * np.eye(3), BOX)
        assert (v.triangle, v.realizable) == (True, expected), (r, v)
    # the solid cube itself, and a point mass pair at two corners (on the geometry)
    assert judge(1.0, np.zeros(3), _box_inertia(1.0, 2, 2, 2), BOX).realizable
    corner = np.array([1.0, 1.0, 1.0])
    pair = 2 * 0.5 * (corner @ corner * np.eye(3) - np.outer(corner, corner))
    assert judge(1.0, np.zeros(3), pair, BOX).realizable


def test_bounds_contain_each_primitive():
    """The hull of a primitive's points contains the solid: points on its surface are inside
    (a sphere's poles and equator, a cylinder's rim, a cone's base rim)."""
    checks = {("sphere", (0.5,)): [[0.5, 0, 0], [0, 0, -0.5], [0.3, 0.3, np.sqrt(0.07)]],
              ("cylinder", (0.2, 1.0)): [[0.2, 0, 0.5], [0, -0.2, -0.5], [0.1414, 0.1414, 0]],
              ("capsule", (0.1, 0.4)): [[0, 0, 0.3], [0.1, 0, 0.2], [0.0707, 0.0707, -0.2]],
              ("cone", (0.3, 0.8)): [[0.3, 0, -0.2], [0, 0, 0.6], [0.2121, 0.2121, -0.2]],
              ("ellipsoid", (0.1, 0.2, 0.3)): [[0.1, 0, 0], [0, 0.2, 0], [0, 0, -0.3]]}
    for (kind, dims), surface in checks.items():
        b = bounds_of(primitive_points(kind, dims))
        for p in surface:
            assert b.outside(np.array(p)) <= 1e-12, (kind, p)
            d = np.array(p) - b.centre
            assert d @ np.linalg.solve(b.shape, d) <= 1 + 1e-12


# A box with an inside-out box (a "cavity") straddling its surface, mostly outside: the health
# check keeps it (warning "partly outside every solid part"), and the part outside counts with
# negative density. Boxes: [-0.5, 0.5] x [-0.1, 0.1]², inverted [-0.2, 0.2] x [-0.4, -0.05] x
# [-0.05, 0.05]. The same mechanism makes a computed tensor break the triangle inequality.
def _boxes_obj() -> str:
    out, faces = [], [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
                      (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    for k, (lo, hi, flip) in enumerate((([-0.5, -0.1, -0.1], [0.5, 0.1, 0.1], False),
                                        ([-0.2, -0.4, -0.05], [0.2, -0.05, 0.05], True))):
        out += [f"v {x} {y} {z}" for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                for z in (lo[2], hi[2])]
        out += [f"f {' '.join(str(8 * k + i + 1) for i in (f[::-1] if flip else f))}"
                for f in faces]
    return "\n".join(out) + "\n"


def test_a_computed_inertial_with_negative_density_is_not_valid(tmp_path, run):
    (tmp_path / "parts.obj").write_text(_boxes_obj())
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="wrist"><inertial><mass value="1"/><inertia ixx="0.01" '
        'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry>'
        '<mesh filename="parts.obj"/></geometry></collision></link></robot>')
    result = run("model", tmp_path / "r.urdf", "--json")
    row = json.loads(result.stdout)
    assert row["computed"]["valid"]["triangle"] is False
    assert row["computed"]["valid"]["positive_definite"] is False
    assert any("partly outside every solid part" in w for w in row["warnings"])
    assert row["valid"] == {"positive_definite": True, "triangle": True, "com_inside": True,
                            "realizable": True}
    table = run("model", tmp_path / "r.urdf").stdout
    assert ("wrist: computed inertial not valid, never written: inertia is not positive "
            "definite") in " ".join(table.split())
