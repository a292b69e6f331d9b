"""COLLADA (``.dae``): the triangles of the scene, in metres, z up, read in float64.

Why not pycollada or trimesh: both parse ``<float_array>`` as float32 (a relative rounding of
6e-8 on every coordinate, far above massprops' 1e-15), and trimesh ignores ``<unit>``. This
reader (the standard library's ElementTree) keeps every number as the float64 nearest to its
decimal text.

What it reads (COLLADA 1.4/1.5 core):
- ``<asset><unit meter=s>``: coordinates are multiplied by s (default 1: metres).
  ``<up_axis>``: Y_UP is turned into z up by +90° about x ((x, y, z) -> (x, -z, y)), X_UP by -90°
  about y ((x, y, z) -> (-z, y, x)); Z_UP stays. No ``<up_axis>`` is the standard's default,
  Y_UP. The turn is what ROS's loaders apply (assimp's up-axis conversion) so that a part
  modelled y up stands up in a z-up robot.
- The scene: ``<scene><instance_visual_scene>`` (else the first visual scene), its nodes'
  ``<matrix>`` (row-major 4x4), ``<translate>``, ``<rotate>`` (axis, degrees), ``<scale>`` composed
  in document order, child nodes, ``<instance_node>`` and ``<instance_geometry>``. Without a
  scene, every geometry once, untransformed.
- ``<mesh>`` primitives ``<triangles>``, ``<polylist>`` (``<vcount>``), ``<polygons>`` (one ``<p>``
  per polygon); polygons become fan triangles. Lines and points are skipped.
A mirroring node transform (negative determinant) reverses that instance's faces, so the surface
stays outward.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import cast

import numpy as np

from massprops.errors import MeshFormatError
from massprops.io.source import Source
from massprops.mesh import Mesh

__all__ = ["read_dae"]

_UP = {
    "Z_UP": np.eye(3),
    "Y_UP": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
    "X_UP": np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
}


def read_dae(source: Source) -> Mesh:
    """Read a COLLADA file: every triangle of its scene, metres, z up (see the module)."""
    name = source.name
    try:
        root = ET.fromstring(source.read_bytes())
    except ET.ParseError as exc:
        raise MeshFormatError(f"{name}: not well-formed COLLADA XML ({exc}); re-export the "
                              "file") from exc
    ns = root.tag[:root.tag.index("}") + 1] if root.tag.startswith("{") else ""
    reader = _Reader(root, ns, name)
    return reader.mesh()


class _Reader:
    def __init__(self, root: ET.Element, ns: str, name: str) -> None:
        self.root, self.ns, self.name = root, ns, name
        self.ids = {el.get("id"): el for el in root.iter() if el.get("id")}
        self.geoms: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.parts: list[tuple[np.ndarray, np.ndarray]] = []

    def q(self, tag: str) -> str:
        return self.ns + tag

    def mesh(self) -> Mesh:
        meter, up = 1.0, "Y_UP"  # the COLLADA standard's defaults
        asset = self.root.find(self.q("asset"))
        if asset is not None:
            unit = asset.find(self.q("unit"))
            if unit is not None and unit.get("meter"):
                meter = self._float(cast(str, unit.get("meter")), "<unit meter>")
            axis = asset.find(self.q("up_axis"))
            if axis is not None and axis.text:
                up = axis.text.strip().upper()
                if up not in _UP:
                    raise MeshFormatError(f"{self.name}: <up_axis> {axis.text!r}: expected "
                                          "X_UP, Y_UP or Z_UP")
        top = np.eye(4)
        top[:3, :3] = _UP[up] * meter
        scene = self._scene()
        if scene is None:
            for geom in self.root.iter(self.q("geometry")):
                self._instance(geom, top)
        else:
            for node in scene.findall(self.q("node")):
                self._node(node, top, 0)
        if not self.parts:
            raise MeshFormatError(f"{self.name}: no triangles or polygons in the COLLADA scene; "
                                  "expected a mesh")
        vertices, faces, offset = [], [], 0
        for v, f in self.parts:
            vertices.append(v)
            faces.append(f + offset)
            offset += v.shape[0]
        return Mesh(np.ascontiguousarray(np.concatenate(vertices)),
                    np.ascontiguousarray(np.concatenate(faces)), name=self.name)

    def _scene(self) -> ET.Element | None:
        scene = self.root.find(self.q("scene"))
        if scene is not None:
            inst = scene.find(self.q("instance_visual_scene"))
            if inst is not None:
                return self._ref(inst.get("url", ""))
        lib = self.root.find(self.q("library_visual_scenes"))
        return None if lib is None else lib.find(self.q("visual_scene"))

    def _ref(self, url: str) -> ET.Element:
        el = self.ids.get(url.lstrip("#"))
        if el is None:
            raise MeshFormatError(f"{self.name}: reference {url!r} names no element; the file "
                                  "is incomplete (re-export it)")
        return el

    def _node(self, node: ET.Element, parent: np.ndarray, depth: int) -> None:
        if depth > 256:  # nodes nest far less in any real scene: an instance_node cycle
            raise MeshFormatError(f"{self.name}: the scene's nodes nest more than 256 deep "
                                  "(an <instance_node> cycle?)")
        m = parent.copy()
        for child in node:
            tag = child.tag[len(self.ns):]
            if tag in ("matrix", "translate", "rotate", "scale"):
                m = m @ self._transform(tag, child)
        for child in node:
            tag = child.tag[len(self.ns):]
            if tag == "instance_geometry":
                self._instance(self._ref(child.get("url", "")), m)
            elif tag == "node":
                self._node(child, m, depth + 1)
            elif tag == "instance_node":
                self._node(self._ref(child.get("url", "")), m, depth + 1)

    def _transform(self, tag: str, el: ET.Element) -> np.ndarray:
        x = self._floats(el.text or "", f"<{tag}>")
        out = np.eye(4)
        want = {"matrix": 16, "translate": 3, "rotate": 4, "scale": 3}[tag]
        if x.size != want:
            raise MeshFormatError(f"{self.name}: <{tag}> needs {want} numbers, got {x.size}")
        if tag == "matrix":
            return x.reshape(4, 4)
        if tag == "translate":
            out[:3, 3] = x
        elif tag == "scale":
            out[:3, :3] = np.diag(x)
        else:
            axis, angle = x[:3], math.radians(float(x[3]))
            n = float(np.linalg.norm(axis))
            if n == 0:
                return out
            k = axis / n
            kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            out[:3, :3] = np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx
        return out

    def _instance(self, geom: ET.Element, m: np.ndarray) -> None:
        gid = geom.get("id", "")
        if gid not in self.geoms:
            self.geoms[gid] = self._geometry(geom)
        v, f = self.geoms[gid]
        if f.size == 0:
            return
        a, t = m[:3, :3], m[:3, 3]
        placed = v @ a.T + t
        if np.linalg.det(a) < 0:
            f = f[:, ::-1]
        self.parts.append((placed, np.ascontiguousarray(f)))

    def _geometry(self, geom: ET.Element) -> tuple[np.ndarray, np.ndarray]:
        mesh = geom.find(self.q("mesh"))
        if mesh is None:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
        positions = None
        verts = mesh.find(self.q("vertices"))
        vid = None if verts is None else verts.get("id")
        if verts is not None:
            for inp in verts.findall(self.q("input")):
                if inp.get("semantic") == "POSITION":
                    positions = self._source(inp.get("source", ""))
        faces = []
        for prim in mesh:
            tag = prim.tag[len(self.ns):]
            if tag not in ("triangles", "polylist", "polygons"):
                continue
            inputs = prim.findall(self.q("input"))
            if not inputs:
                continue
            stride = 1 + max(int(i.get("offset", "0")) for i in inputs)
            offset, pos = None, positions
            for i in inputs:
                if i.get("semantic") == "VERTEX" and i.get("source", "").lstrip("#") == vid:
                    offset = int(i.get("offset", "0"))
                elif i.get("semantic") == "POSITION":
                    offset = int(i.get("offset", "0"))
                    pos = self._source(i.get("source", ""))
            if offset is None or pos is None:
                raise MeshFormatError(f"{self.name}: a <{tag}> of geometry "
                                      f"{geom.get('id')!r} has no vertex positions")
            positions = pos
            for p, sizes in self._polygons(tag, prim):
                idx = p.reshape(-1, stride)[:, offset]
                faces.append(_fan(idx, sizes, self.name))
        if positions is None:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
        f = np.concatenate(faces) if faces else np.zeros((0, 3), dtype=np.int64)
        if f.size and (f.min() < 0 or f.max() >= positions.shape[0]):
            raise MeshFormatError(f"{self.name}: geometry {geom.get('id')!r} indexes a vertex "
                                  f"beyond its {positions.shape[0]} positions")
        return positions, f

    def _polygons(self, tag: str, prim: ET.Element):
        """(indices, polygon sizes) per <p> of a primitive."""
        if tag == "triangles":
            for p in prim.findall(self.q("p")):
                idx = self._ints(p.text or "")
                yield idx, None
        elif tag == "polylist":
            vcount = prim.find(self.q("vcount"))
            sizes = self._ints(vcount.text or "") if vcount is not None else None
            for p in prim.findall(self.q("p")):
                yield self._ints(p.text or ""), sizes
        else:
            for p in prim.findall(self.q("p")):
                idx = self._ints(p.text or "")
                yield idx, "one"

    def _source(self, url: str) -> np.ndarray:
        src = self._ref(url)
        arr = src.find(self.q("float_array"))
        if arr is None:
            raise MeshFormatError(f"{self.name}: source {url!r} has no <float_array>")
        values = self._floats(arr.text or "", "<float_array>")
        stride, offset, count = 3, 0, values.size // 3
        acc = src.find(f"{self.q('technique_common')}/{self.q('accessor')}")
        if acc is not None:
            stride = int(acc.get("stride", "3"))
            offset = int(acc.get("offset", "0"))
            count = int(acc.get("count", str(values.size // stride)))
        if stride < 3 or offset + count * stride > values.size:
            raise MeshFormatError(f"{self.name}: source {url!r}: its accessor does not fit its "
                                  f"{values.size} numbers")
        return np.ascontiguousarray(values[offset:offset + count * stride]
                                    .reshape(count, stride)[:, :3])

    def _floats(self, text: str, what: str) -> np.ndarray:
        try:
            out = np.array(text.split(), dtype=np.float64)
        except ValueError as exc:
            raise MeshFormatError(f"{self.name}: {what} holds a non-number; re-export the "
                                  "file") from exc
        if not np.isfinite(out).all():
            raise MeshFormatError(f"{self.name}: {what} holds NaN or infinity; re-export the "
                                  "file")
        return out

    def _float(self, text: str, what: str) -> float:
        x = self._floats(text, what)
        if x.size != 1 or x[0] <= 0:
            raise MeshFormatError(f"{self.name}: {what} must be one positive number, got "
                                  f"{text!r}")
        return float(x[0])

    def _ints(self, text: str) -> np.ndarray:
        try:
            return np.array(text.split(), dtype=np.int64)
        except ValueError as exc:
            raise MeshFormatError(f"{self.name}: a <p> or <vcount> holds a non-integer; "
                                  "re-export the file") from exc


def _fan(idx: np.ndarray, sizes, name: str) -> np.ndarray:
    """Fan triangles (v0, v_k, v_k+1) of consecutive polygons of ``sizes`` vertices each
    (None: all triangles; "one": a single polygon)."""
    if sizes is None:
        if idx.size % 3:
            raise MeshFormatError(f"{name}: a <triangles> list is not a multiple of 3 long")
        return idx.reshape(-1, 3)
    if isinstance(sizes, str):
        sizes = np.array([idx.size])
    if int(sizes.sum()) != idx.size:
        raise MeshFormatError(f"{name}: <vcount> sums to {int(sizes.sum())} but <p> holds "
                              f"{idx.size} vertices")
    out = []
    start = 0
    for k in sizes.tolist():
        if k >= 3:
            v0 = idx[start]
            for j in range(1, k - 1):
                out.append((v0, idx[start + j], idx[start + j + 1]))
        start += k
    return np.array(out, dtype=np.int64).reshape(-1, 3)
