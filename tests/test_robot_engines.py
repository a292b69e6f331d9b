"""``inspect --format gltf|usd`` (the contract's "Mass properties for engines"): each engine's
own reader, or an independent quaternion convention, turns the printed numbers back into the
tensor, checked against the closed form of the notes' cuboid (3 × 2 × 2, turned 30° about z):
J' = m/12 diag(8, 13, 13) in its own axes, J = Rz(30°) J' Rz(30°)ᵀ."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import SAMPLES, rot_z

MASS = 1.3
TRUTH = rot_z(30.0) @ (MASS / 12 * np.diag([8.0, 13.0, 13.0])) @ rot_z(30.0).T


def test_gltf_motion_reads_back_as_the_tensor(run):
    from scipy.spatial.transform import Rotation  # scalar-last [x, y, z, w], like glTF

    res = run("inspect", "--format", "gltf", "--mass", str(MASS), SAMPLES / "cuboid.obj",
              SAMPLES / "cube.obj")
    assert res.exit_code == 0, res.stderr
    lines = res.stdout.splitlines()
    assert len(lines) == 2  # one JSON object per mesh, nothing else
    motion = json.loads(lines[0])
    assert set(motion) == {"mass", "centerOfMass", "inertiaDiagonal", "inertiaOrientation"}
    assert motion["mass"] == MASS
    assert np.allclose(motion["centerOfMass"], 0, atol=1e-15)
    r = Rotation.from_quat(motion["inertiaOrientation"]).as_matrix()
    j = r @ np.diag(motion["inertiaDiagonal"]) @ r.T
    assert np.allclose(j, TRUTH, rtol=0, atol=1e-14)
    assert motion["inertiaDiagonal"] == sorted(motion["inertiaDiagonal"])


def test_usd_prim_reads_back_through_pxr(run):
    pxr = pytest.importorskip("pxr")
    from pxr import Gf, Sdf, Usd, UsdPhysics

    res = run("inspect", "--format", "usd", "--mass", str(MASS), SAMPLES / "cuboid.obj")
    assert res.exit_code == 0, res.stderr
    assert res.stdout.startswith("# ") and "cuboid.obj" in res.stdout.splitlines()[0]
    layer = Sdf.Layer.CreateAnonymous(".usda")
    assert layer.ImportFromString("#usda 1.0\n" + res.stdout)
    stage = Usd.Stage.Open(layer)
    prim = stage.GetPrimAtPath("/cuboid")
    assert prim.HasAPI(UsdPhysics.MassAPI), pxr.__name__
    api = UsdPhysics.MassAPI(prim)
    assert api.GetMassAttr().Get() == pytest.approx(MASS, rel=1e-7)  # float: USD's type
    diag = np.array(api.GetDiagonalInertiaAttr().Get())
    rotation = Gf.Rotation(Gf.Quatd(api.GetPrincipalAxesAttr().Get()))
    axes = np.column_stack([np.array(rotation.TransformDir(Gf.Vec3d(*e)))
                            for e in np.eye(3)])
    j = axes @ np.diag(diag) @ axes.T
    assert np.allclose(j, TRUTH, rtol=0, atol=1e-6)  # float32 attributes

