"""The inertia doctor's validity tests (issue 32.1): each against a truth worked out by hand, and
a valid tensor shifted and turned a few times stays valid (the tolerance is round-off)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.inertia import parallel_axis, parallel_axis_to_com, rotate_inertia
from massprops.robot.analyze import analyze_model
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


# example-robot-data's romeo LWristRoll.dae, as found on the real file: every piece faces
# inward; the main body (a solid "inside no other piece") is flipped, but each of the two small
# bosses has a vertex inside it, so the nesting rule takes them for cavities of it, though most
# of each lies outside. Here: the cube [-0.1, 0.1]³ and bosses [-0.05, 0.05]² x [0.08, 0.18] and
# its mirror in z, all three written inward; a fifth of each boss lies in the cube.
_CUBE = ([-0.1, -0.1, -0.1], [0.1, 0.1, 0.1])
_BOSSES = (([-0.05, -0.05, 0.08], [0.05, 0.05, 0.18]), ([-0.05, -0.05, -0.18], [0.05, 0.05, -0.08]))
_FACES = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1), (2, 3, 7), (2, 7, 6),
          (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # outward for the corner order below


def _obj(boxes, inward: bool) -> str:
    out = []
    for k, (lo, hi) in enumerate(boxes):
        out += [f"v {x} {y} {z}" for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                for z in (lo[2], hi[2])]
        out += [f"f {' '.join(str(8 * k + i + 1) for i in (f[::-1] if inward else f))}"
                for f in _FACES]
    return "\n".join(out) + "\n"


def _signed_boxes(signed) -> tuple[float, np.ndarray, np.ndarray]:
    """Closed form: volume, centroid and inertia about it (unit density) of boxes counted with
    the signs given (+1 solid, -1 subtracted), by the parallel-axis rule."""
    parts = []
    for s, (lo, hi) in signed:
        d = np.subtract(hi, lo)
        v = float(np.prod(d))
        parts.append((s * v, (np.add(lo, hi)) / 2, s * _box_inertia(v, *d)))
    vol = sum(v for v, _c, _j in parts)
    com = sum(v * c for v, c, _j in parts) / vol
    j = sum(jj + parallel_axis(np.zeros((3, 3)), v, c - com) for v, c, jj in parts)
    return vol, com, j


def _wrist(tmp_path, inward: bool):
    (tmp_path / "wrist.obj").write_text(_obj([_CUBE, *_BOSSES], inward))
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="wrist"><inertial><mass value="2"/><inertia ixx="0.01" '
        'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry>'
        '<mesh filename="wrist.obj"/></geometry></collision></link></robot>')
    return tmp_path / "r.urdf"


def test_romeo_wrist_inward_bosses_taken_for_cavities_break_the_triangle(tmp_path, run):
    row = json.loads(run("model", _wrist(tmp_path, inward=True), "--json").stdout)
    # what the signed integral is: the cube less both whole bosses (closed form, mass 2 kept)
    vol, com, j = _signed_boxes([(1, _CUBE), (-1, _BOSSES[0]), (-1, _BOSSES[1])])
    moments = np.linalg.eigvalsh(j)
    assert moments[0] > 0 and moments[2] > moments[0] + moments[1]  # romeo's pattern
    assert np.allclose(row["computed"]["inertia"], 2 / vol * j, rtol=0, atol=1e-12)
    assert np.allclose(row["computed"]["center_of_mass"], com, atol=1e-12)
    assert row["computed"]["valid"] == {"positive_definite": True, "triangle": False,
                                        "com_inside": True, "realizable": False}
    said = [w for w in row["warnings"] if w.startswith("computed inertial not valid")]
    assert len(said) == 1
    assert ("principal moments" in said[0] and "break the triangle inequality" in said[0]
            and "wrist.obj: components 2, 3 face inward and are partly outside every solid part, "
            "so they count there with negative density" in said[0])
    table = " ".join(run("model", _wrist(tmp_path, inward=True)).stdout.split())
    assert table.count("computed inertial not valid") == 1
    assert "wrist.obj: components 2, 3 face inward" in table


def test_romeo_wrist_with_its_faces_reversed_in_the_file_is_valid(tmp_path, run):
    """The fix the warning names: every piece outward, the bosses are solids (their share with
    the cube counted twice, as the overlap warning says)."""
    row = json.loads(run("model", _wrist(tmp_path, inward=False), "--json").stdout)
    vol, _com, j = _signed_boxes([(1, _CUBE), (1, _BOSSES[0]), (1, _BOSSES[1])])
    assert np.allclose(row["computed"]["inertia"], 2 / vol * j, rtol=0, atol=1e-12)
    assert all(row["computed"]["valid"].values())
    assert not any(w.startswith("computed inertial not valid") for w in row["warnings"])


def test_an_open_mesh_integrated_as_it_is_is_named_as_the_cause(tmp_path, run):
    """--allow-open: a closed cube [-0.1, 0.1]³ and two loose squares 0.1 wide at z = ±0.5 facing
    the origin. Integrated about the box centre (the origin), each square closes off a pyramid of
    negative volume with its apex there; the closed form of cube less both pyramids."""
    out = [f"v {x} {y} {z}" for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)]
    out += [f"f {' '.join(str(i + 1) for i in f)}" for f in _FACES]
    for k, z in enumerate((0.5, -0.5)):
        b = 9 + 4 * k
        out += [f"v -0.05 -0.05 {z}", f"v 0.05 -0.05 {z}", f"v 0.05 0.05 {z}", f"v -0.05 0.05 {z}"]
        quad = [(b, b + 1, b + 2), (b, b + 2, b + 3)]
        out += [f"f {' '.join(map(str, t[::-1] if z > 0 else t))}" for t in quad]
    (tmp_path / "part.obj").write_text("\n".join(out) + "\n")
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="flap"><inertial><mass value="1"/><inertia ixx="0.01" '
        'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry>'
        '<mesh filename="part.obj"/></geometry></collision></link></robot>')
    row = json.loads(run("model", tmp_path / "r.urdf", "--json", "--allow-open").stdout)
    a, h, side = 0.1, 0.5, 0.2
    vol = side**3 - 2 * a * a * h / 3
    sxx = side**3 * side**2 / 12 - 2 * a**4 * h / 60  # ∫x² dV: cube less both pyramids
    szz = side**3 * side**2 / 12 - 2 * a**2 * h**3 / 5
    j = np.diag([sxx + szz, sxx + szz, 2 * sxx]) / vol  # m = 1 kg
    assert np.allclose(row["computed"]["inertia"], j, rtol=0, atol=1e-12)
    assert row["computed"]["valid"]["positive_definite"] is False
    said = [w for w in row["warnings"] if w.startswith("computed inertial not valid")]
    assert len(said) == 1 and said[0].endswith(
        "part.obj: an open surface integrated as it is (--allow-open), its signed volumes not a "
        "solid's")


@pytest.mark.parametrize("bound, said", [(1e-12, 1), (0.03, 0)])
def test_the_invalidity_warning_follows_mujocos_boundinertia(tmp_path, bound, said):
    """MJCF boundinertia raises each computed principal moment to at least its value. The
    inward-bosses wrist at MuJoCo's 1000 kg/m³ (6 kg) computes 0.0162, 0.0162, 0.05 kg·m²
    (triangle broken); raised to 0.03, 0.03, 0.05 it is valid, and the warning goes."""
    (tmp_path / "wrist.obj").write_text(_obj([_CUBE, *_BOSSES], inward=True))
    (tmp_path / "r.xml").write_text(
        f'<mujoco><compiler boundinertia="{bound}"/><asset><mesh name="w" file="wrist.obj"/>'
        '</asset><worldbody><body name="wrist"><geom type="mesh" mesh="w"/></body></worldbody>'
        '</mujoco>')
    r, = analyze_model(tmp_path / "r.xml").links
    assert r.computed_validity().ok is (said == 0)
    assert sum(w.startswith("computed inertial not valid") for w in r.warnings) == said
