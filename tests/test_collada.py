"""COLLADA meshes read exactly: a wedge in centimetres, y up, placed by nested node transforms,
against its closed form and against the same part written as an OBJ in metres, z up."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import json_lines

from massprops.errors import MeshFormatError
from massprops.inspection.file import inspect_file

A, B, H = 2.1, 4.3, 6.7        # cm, none a float32 number: legs along x, y (z up), height z
WEDGE = np.array([[0, 0, 0], [A, 0, 0], [0, B, 0], [0, 0, H], [A, 0, H], [0, B, H]], float)
POLYGONS = [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]]
UP = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])   # y up -> z up: (x, y, z) -> (x, -z, y)


def rot(axis, deg):
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    t = math.radians(deg)
    return np.eye(3) + math.sin(t) * kx + (1 - math.cos(t)) * kx @ kx


T1 = np.array([10.0, 20.0, 30.0])          # outer node <translate>, cm, y-up frame
R2 = rot([0, 1, 0], 90)                     # inner node <rotate> 0 1 0 90
M3 = np.array([[0, -1, 0, 1.5], [1, 0, 0, -2.5], [0, 0, 1, 0.5], [0, 0, 0, 1]], float)


def dae_text(unit="0.01", up="Y_UP"):
    """The wedge as y-up positions ((X, Y, Z) z-up -> (X, Z, -Y)), polylist with vcount,
    under node translate -> node rotate -> node matrix."""
    pos = WEDGE @ UP  # rows: UP^T p, i.e. z-up -> y-up
    floats = " ".join(repr(float(x)) for x in pos.ravel())
    vcount = " ".join(str(len(p)) for p in POLYGONS)
    # interleave a dummy normal index (offset 1) to check the stride
    p = " ".join(f"{i} 0" for poly in POLYGONS for i in poly)
    matrix = " ".join(repr(float(x)) for x in M3.ravel())
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="{unit}"/><up_axis>{up}</up_axis></asset>
  <library_geometries><geometry id="wedge"><mesh>
    <source id="pos"><float_array id="pos-a" count="18">{floats}</float_array>
      <technique_common><accessor source="#pos-a" count="6" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <source id="nrm"><float_array id="nrm-a" count="3">0 0 1</float_array>
      <technique_common><accessor source="#nrm-a" count="1" stride="3"/></technique_common>
    </source>
    <vertices id="verts"><input semantic="POSITION" source="#pos"/></vertices>
    <polylist count="5"><input semantic="VERTEX" source="#verts" offset="0"/>
      <input semantic="NORMAL" source="#nrm" offset="1"/>
      <vcount>{vcount}</vcount><p>{p}</p></polylist>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene">
    <node id="outer"><translate>{" ".join(map(str, T1))}</translate>
      <node id="inner"><rotate>0 1 0 90</rotate>
        <node id="leaf"><matrix>{matrix}</matrix><instance_geometry url="#wedge"/></node>
      </node>
    </node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def truth(scale=0.01):
    """Closed form of the wedge (own frame, cm -> m), then the placement: p -> UP (T1 + R2 (R3 p
    + t3)) in metres, with p in the y-up frame (UP^T p_zup)."""
    a, b, h = A * scale, B * scale, H * scale
    vol = a * b * h / 2
    com = np.array([a / 3, b / 3, h / 2])
    ixx_a, iyy_a, ixy_a = a * b**3 / 36, a**3 * b / 36, -a * a * b * b / 72  # area moments
    area = a * b / 2
    j = np.array([[h * ixx_a + area * h**3 / 12, -h * ixy_a, 0],
                  [-h * ixy_a, h * iyy_a + area * h**3 / 12, 0],
                  [0, 0, h * (ixx_a + iyy_a)]])
    rot_total = UP @ R2 @ M3[:3, :3] @ UP.T
    shift = UP @ (T1 + R2 @ M3[:3, 3]) * scale
    return vol, rot_total @ com + shift, rot_total @ j @ rot_total.T


def test_dae_in_centimetres_y_up_against_closed_form(tmp_path):
    f = tmp_path / "wedge.dae"
    f.write_text(dae_text())
    r = inspect_file(f).properties
    vol, com, j = truth()
    assert r.volume == pytest.approx(vol, rel=1e-14)
    assert np.allclose(r.center_of_mass, com, rtol=0, atol=1e-16)
    assert np.allclose(r.inertia, j, rtol=0, atol=1e-14 * np.abs(j).max())


def test_dae_equals_the_obj_in_metres_z_up(tmp_path, run):
    """The same placed wedge written as an OBJ in metres: the same numbers (float64 reading,
    no float32 rounding of the arrays: that would show at 1e-8)."""
    vol, com, j = truth()
    rot_total = UP @ R2 @ M3[:3, :3] @ UP.T
    shift = UP @ (T1 + R2 @ M3[:3, 3]) * 0.01
    pts = (WEDGE * 0.01) @ rot_total.T + shift
    obj = tmp_path / "wedge.obj"
    obj.write_text("".join(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in pts)
                   + "".join("f " + " ".join(str(i + 1) for i in p) + "\n" for p in POLYGONS))
    dae = tmp_path / "wedge.dae"
    dae.write_text(dae_text())
    a, b = (json_lines(run("inspect", "--json", p).stdout)[0] for p in (dae, obj))
    assert a["volume"] == pytest.approx(b["volume"], rel=1e-14)
    assert np.allclose(a["center_of_mass"], b["center_of_mass"], rtol=0, atol=1e-16)
    assert np.allclose(a["inertia"], b["inertia"], rtol=0, atol=1e-14 * np.abs(j).max())


def test_dae_z_up_in_metres_is_untouched(tmp_path):
    f = tmp_path / "wedge.dae"
    f.write_text(dae_text(unit="1", up="Z_UP"))
    r = inspect_file(f).properties
    assert r.volume == pytest.approx(A * B * H / 2, rel=1e-14)


def test_dae_refuses_broken_files(tmp_path):
    f = tmp_path / "bad.dae"
    f.write_text(dae_text().replace('url="#wedge"', 'url="#nothing"'))
    with pytest.raises(MeshFormatError, match="names no element"):
        inspect_file(f)
    f.write_text(dae_text().replace("<vcount>3 3", "<vcount>3 4"))
    with pytest.raises(MeshFormatError, match="vcount"):
        inspect_file(f)
