"""``inspect --write-physics OUT`` (issue 32, point 5): the copy of a glTF asset carries the
``KHR_physics_rigid_bodies`` motion of each mesh node.

The assets are built here with pygltflib (an independent writer) and read back with it (an
independent reader); the truth is the closed form of the notes' cuboid, 3 × 2 × 2 turned 30°
about z and moved off the origin in its own coordinates: volume 12, the centre of mass at the
offset, J = Rz(30°) (m/12 diag(2²+2², 3²+2², 3²+2²)) Rz(30°)ᵀ. The node's own rotation and
translation must not enter (the motion is in node space). Coordinates are float32 in glTF, so
the numbers agree to float32 rounding (rtol 1e-6), not to round-off.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import SAMPLES, rot_z

pygltflib = pytest.importorskip("pygltflib")

OFFSET = np.array([0.5, -1.0, 2.0])
SIZE = np.array([3.0, 2.0, 2.0])
RTOL = 1e-6  # float32 coordinates
EXT = "KHR_physics_rigid_bodies"
OTHER_BYTES = bytes(range(256)) * 3  # a buffer view no mesh uses: must survive byte for byte


def box(size=SIZE, turn_deg=30.0, offset=OFFSET, drop_face=False):
    """(8, 3) float32 corners and (12, 3) uint32 triangles (counter-clockwise from outside) of a
    box of ``size`` centred at the origin, turned about z, then moved by ``offset``."""
    corners = np.array(list(itertools.product((-0.5, 0.5), repeat=3))) * size  # x slowest
    corners = corners @ rot_z(turn_deg).T + offset
    # corner index = 4 ix + 2 iy + iz; each quad counter-clockwise seen from outside
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    if drop_face:
        quads = quads[1:]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return corners.astype(np.float32), np.array(tris, dtype=np.uint32)


def truth(mass, size=SIZE, turn_deg=30.0):
    a, b, c = size
    principal = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return rot_z(turn_deg) @ principal @ rot_z(turn_deg).T


def build(meshes, nodes, *, uri=None):
    """A pygltflib GLTF2 with ``meshes`` (list of (corners, triangles)), ``nodes`` (dicts of
    pygltflib.Node fields) in one scene, one buffer (``uri``: external, else the GLB blob) that
    also holds OTHER_BYTES in a view of its own; (gltf, blob)."""
    g = pygltflib
    blob, views, accessors, gl_meshes = b"", [], [], []
    for corners, tris in meshes:
        for data, target, acc in (
            (tris.tobytes(), g.ELEMENT_ARRAY_BUFFER,
             dict(componentType=g.UNSIGNED_INT, count=tris.size, type=g.SCALAR)),
            (corners.tobytes(), g.ARRAY_BUFFER,
             dict(componentType=g.FLOAT, count=len(corners), type=g.VEC3,
                  max=corners.max(axis=0).tolist(), min=corners.min(axis=0).tolist())),
        ):
            views.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data),
                                      target=target))
            accessors.append(g.Accessor(bufferView=len(views) - 1, **acc))
            blob += data
        gl_meshes.append(g.Mesh(primitives=[g.Primitive(
            attributes=g.Attributes(POSITION=len(accessors) - 1), indices=len(accessors) - 2)]))
    views.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(OTHER_BYTES)))
    blob += OTHER_BYTES
    gltf = g.GLTF2(
        scene=0, scenes=[g.Scene(nodes=[i for i, n in enumerate(nodes) if n.get("root", True)])],
        nodes=[g.Node(**{k: v for k, v in n.items() if k != "root"}) for n in nodes],
        meshes=gl_meshes, accessors=accessors, bufferViews=views,
        buffers=[g.Buffer(byteLength=len(blob), uri=uri)],
        extras={"kept": "yes"})
    return gltf, blob


def save_glb(path, meshes, nodes):
    gltf, blob = build(meshes, nodes)
    gltf.set_binary_blob(blob)
    gltf.save_binary(str(path))
    return path


def motion_of(gltf, node):
    return gltf.nodes[node].extensions[EXT]["motion"]


def check_cuboid(motion, mass):
    from scipy.spatial.transform import Rotation  # scalar-last [x, y, z, w], as glTF

    assert motion["mass"] == pytest.approx(mass, rel=RTOL)
    assert np.allclose(motion["centerOfMass"], OFFSET, rtol=0, atol=RTOL * 3)
    diag = motion["inertiaDiagonal"]
    assert np.allclose(diag, mass / 12 * np.array([8.0, 13.0, 13.0]), rtol=RTOL, atol=0)
    r = Rotation.from_quat(motion["inertiaOrientation"]).as_matrix()
    assert np.allclose(r @ np.diag(diag) @ r.T, truth(mass), rtol=0, atol=RTOL * mass)


TURNED = {"rotation": [0.0, 0.0, np.sin(np.pi / 8), np.cos(np.pi / 8)],  # 45° about z
          "translation": [10.0, 0.0, -4.0], "name": "body"}


def test_cuboid_motion_in_node_space(run, tmp_path):
    src = save_glb(tmp_path / "part.glb", [box()],
                   [{**TURNED, "mesh": 0, "children": [1]}, {"name": "marker", "root": False}])
    before = src.read_bytes()
    out = tmp_path / "physics.glb"
    res = run("inspect", src, "--write-physics", out, "--density", "2.5")
    assert res.exit_code == 0, res.stderr
    assert src.read_bytes() == before  # never over the input
    gltf = pygltflib.GLTF2.load(str(out))
    check_cuboid(motion_of(gltf, 0), 2.5 * 12)
    assert EXT in gltf.extensionsUsed
    assert EXT not in (gltf.extensionsRequired or [])  # an engine may ignore it
    # everything else as it was: node transform, the other node, the buffer, extras
    assert gltf.nodes[0].rotation == TURNED["rotation"]
    assert gltf.nodes[0].translation == TURNED["translation"]
    assert gltf.nodes[1].name == "marker" and not gltf.nodes[1].extensions
    assert gltf.binary_blob() == pygltflib.GLTF2.load(str(src)).binary_blob()
    assert gltf.binary_blob().endswith(OTHER_BYTES)
    assert gltf.extras == {"kept": "yes"}


def test_two_nodes_share_a_mesh_and_mass_is_the_total(run, tmp_path):
    cube = box(size=np.ones(3), turn_deg=0.0, offset=np.zeros(3))
    src = save_glb(tmp_path / "two.glb", [box(), cube],
                   [{"mesh": 0}, {**TURNED, "mesh": 0}, {"mesh": 1, "scale": [1.0, 1.0, 1.0]}])
    out = tmp_path / "two_physics.glb"
    res = run("inspect", src, "--write-physics", out, "--mass", "25", "--json")
    assert res.exit_code == 0, res.stderr
    gltf = pygltflib.GLTF2.load(str(out))
    # volumes 12, 12, 1: one density for the asset, 25 kg in all
    check_cuboid(motion_of(gltf, 0), 12.0)
    assert motion_of(gltf, 1) == motion_of(gltf, 0)  # one mesh, one motion, wherever it is
    assert motion_of(gltf, 2)["mass"] == pytest.approx(1.0, rel=RTOL)
    assert np.allclose(motion_of(gltf, 2)["inertiaDiagonal"], 1 / 6, rtol=RTOL)
    lines = [line for line in res.stdout.splitlines() if line]
    assert len(lines) == 3  # one JSON object per mesh node


def test_existing_motion_keeps_its_other_keys(run, tmp_path):
    node = {"mesh": 0, "extensions": {EXT: {"motion": {"mass": 99.0, "isKinematic": True},
                                            "collider": {"shape": 0}}}}
    src = save_glb(tmp_path / "old.glb", [box()], [node])
    out = tmp_path / "new.glb"
    assert run("inspect", src, "--write-physics", out).exit_code == 0
    physics = pygltflib.GLTF2.load(str(out)).nodes[0].extensions[EXT]
    assert physics["collider"] == {"shape": 0}
    assert physics["motion"]["isKinematic"] is True
    check_cuboid(physics["motion"], 12.0)


@pytest.mark.parametrize("where", ["beside", "elsewhere"])
def test_gltf_with_an_external_buffer(run, tmp_path, where):
    gltf, blob = build([box()], [{"mesh": 0}], uri="part%20data.bin")
    (tmp_path / "part data.bin").write_bytes(blob)
    src = tmp_path / "part.gltf"
    gltf.save_json(str(src))
    folder = tmp_path if where == "beside" else tmp_path / "out" / "deep"
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / "physics.gltf"
    res = run("inspect", src, "--write-physics", out, "--mass", "3")
    assert res.exit_code == 0, res.stderr
    copy = pygltflib.GLTF2.load(str(out))
    uri = copy.buffers[0].uri
    assert uri == ("part%20data.bin" if where == "beside" else "../../part%20data.bin")
    from urllib.parse import unquote

    assert (folder / unquote(uri)).resolve() == (tmp_path / "part data.bin").resolve()
    check_cuboid(motion_of(copy, 0), 3.0)
    assert EXT in copy.extensionsUsed


def one_error_line(res) -> str:
    """The error's line: the one stderr line, or, for an option click refuses (exit 2), the
    last line under click's usage text."""
    lines = res.stderr.splitlines()
    assert "Traceback" not in res.stderr and res.stdout == ""
    if res.exit_code == 2 and lines and lines[-1].startswith("Error: "):
        return lines[-1]
    assert len(lines) == 1 and lines[0].startswith("massprops: error: "), res.stderr
    return lines[0]


def test_refusals(run, tmp_path):
    src = save_glb(tmp_path / "part.glb", [box()], [{"mesh": 0}])
    before = src.read_bytes()
    cases = [
        ((src, "--write-physics", src), 1, "input"),  # over the input
        ((src, "--write-physics", tmp_path / "no" / "x.glb"), 1, "does not exist"),
        ((src, "--write-physics", tmp_path / "x.gltf"), 2, ".gltf"),  # another extension
        ((SAMPLES / "cuboid.obj", "--write-physics", tmp_path / "x.glb"), 2, "glTF"),
        ((src, src, "--write-physics", tmp_path / "x.glb"), 2, "one"),
        ((src, "--write-physics", tmp_path / "x.glb", "--unit", "mm"), 2, "--unit"),
    ]
    for args, code, said in cases:
        res = run("inspect", *args)
        assert res.exit_code == code, (args, res.stderr)
        assert said in one_error_line(res), res.stderr
    assert src.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.glb"]  # nothing written


def test_existing_output_needs_force(run, tmp_path):
    src = save_glb(tmp_path / "part.glb", [box()], [{"mesh": 0}])
    out = tmp_path / "out.glb"
    out.write_bytes(b"old")
    res = run("inspect", src, "--write-physics", out)
    assert res.exit_code == 1 and "--force" in one_error_line(res)
    assert out.read_bytes() == b"old"
    assert run("inspect", src, "--write-physics", out, "--force").exit_code == 0
    check_cuboid(motion_of(pygltflib.GLTF2.load(str(out)), 0), 12.0)


@pytest.mark.parametrize("node, said", [
    ({"mesh": 0, "scale": [2.0, 1.0, 1.0]}, "scaled"),
    ({"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 3, 0, 0, 0, 0, 1]}, "scaled"),
], ids=["scale", "matrix"])
def test_scaled_nodes_are_refused(run, tmp_path, node, said):
    src = save_glb(tmp_path / "part.glb", [box()], [node])
    res = run("inspect", src, "--write-physics", tmp_path / "out.glb")
    assert res.exit_code == 1
    line = one_error_line(res)
    assert said in line and "part.glb" in line and "node 0" in line
    assert not (tmp_path / "out.glb").exists()


def test_scaled_ancestor_is_refused(run, tmp_path):
    src = save_glb(tmp_path / "part.glb", [box()],
                   [{"scale": [0.01, 0.01, 0.01], "children": [1]}, {"mesh": 0, "root": False}])
    res = run("inspect", src, "--write-physics", tmp_path / "out.glb")
    assert res.exit_code == 1 and "node 1" in one_error_line(res)


def test_open_mesh_is_refused_and_nothing_written(run, tmp_path):
    src = save_glb(tmp_path / "open.glb", [box(drop_face=True)], [{"mesh": 0}])
    res = run("inspect", src, "--write-physics", tmp_path / "out.glb")
    assert res.exit_code == 1
    assert "open.glb" in one_error_line(res)
    assert not (tmp_path / "out.glb").exists()


def test_not_a_gltf_file(run, tmp_path):
    src = tmp_path / "fake.glb"
    src.write_bytes(b"not a glb at all")
    res = run("inspect", src, "--write-physics", tmp_path / "out.glb")
    assert res.exit_code == 1 and "fake.glb" in one_error_line(res)


def test_inward_mesh_is_flipped_and_said_once(run, tmp_path):
    corners, tris = box()
    src = save_glb(tmp_path / "inward.glb", [(corners, tris[:, ::-1].copy())],
                   [{"mesh": 0}, {**TURNED, "mesh": 0}])
    out = tmp_path / "out.glb"
    res = run("inspect", src, "--write-physics", out)
    assert res.exit_code == 0, res.stderr
    warnings = res.stderr.splitlines()
    assert len(warnings) == 1 and warnings[0].startswith("massprops: warning: ")
    assert "mesh 0" in warnings[0]
    gltf = pygltflib.GLTF2.load(str(out))
    check_cuboid(motion_of(gltf, 0), 12.0)
    assert motion_of(gltf, 1) == motion_of(gltf, 0)


def test_primitives_of_a_mesh_are_one_solid(run, tmp_path):
    corners, tris = box()
    gltf, blob = build([(corners, tris[:6].copy()), (corners, tris[6:].copy())], [{"mesh": 0}])
    first, second = gltf.meshes
    gltf.meshes = [pygltflib.Mesh(primitives=first.primitives + second.primitives)]
    gltf.set_binary_blob(blob)
    src = tmp_path / "halves.glb"
    gltf.save_binary(str(src))
    out = tmp_path / "out.glb"
    res = run("inspect", src, "--write-physics", out, "--mass", "2")
    assert res.exit_code == 0, res.stderr
    check_cuboid(motion_of(pygltflib.GLTF2.load(str(out)), 0), 2.0)
