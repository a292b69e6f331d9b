"""glTF 2.0 assets as containers: the JSON, the GLB chunks, the buffers, each mesh's triangles, the
node tree's transforms, and a copy of the asset written with a new JSON (buffers kept).

Read without any glTF library: a GLB is a 12-byte header (magic ``glTF``, version 2, length)
and chunks (length, type, data, 4-byte aligned), the first one JSON, the second, if any, the
binary buffer. A mesh is the triangles of all its primitives (modes 4, 5, 6; points and lines are
skipped with a note) from float32 ``POSITION`` accessors and unsigned indices; compressed
(Draco, meshopt), quantized or sparse positions are refused, one line saying which.
The copy (`asset_bytes`) keeps every chunk after the JSON byte for byte (the binary buffer and
any others) and writes the JSON with its data unchanged except what the caller changed.
"""

from __future__ import annotations

import base64
import json
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlparse

import numpy as np

from massprops.errors import MeshFileError, MeshFormatError
from massprops.files import read_input
from massprops.io import validate
from massprops.mesh.value import Mesh

__all__ = ["GltfAsset", "asset_bytes", "asset_mesh", "mesh_nodes", "node_linear", "read_asset",
           "relocated_uris"]

_MAGIC = b"glTF"
_JSON_CHUNK = 0x4E4F534A
_BIN_CHUNK = 0x004E4942
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
_INDEX_TYPES: dict[int, np.dtype] = {5121: np.dtype("<u1"), 5123: np.dtype("<u2"),
                                     5125: np.dtype("<u4")}
_FLOAT = 5126
_TRIANGLE_MODES = (4, 5, 6)  # TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN


@dataclass(frozen=True, eq=False)
class GltfAsset:
    """One glTF asset as read.

    path : the file (.glb or .gltf); relative URIs resolve against its folder.
    document : the JSON, parsed (keys in file order).
    binary : the GLB's binary chunk (buffer 0 without a uri); None for .gltf or without one.
    chunks_after_json : every GLB byte after the JSON chunk, as in the file (b"" for .gltf).
    buffers : buffer index -> its bytes, filled as meshes are read (each buffer loaded once).
    """

    path: Path
    document: dict
    binary: bytes | None
    chunks_after_json: bytes
    buffers: dict[int, bytes] = field(default_factory=dict, repr=False)

    @property
    def is_glb(self) -> bool:
        return self.path.suffix.lower() == ".glb"

    def list_of(self, key: str) -> list:
        value = self.document.get(key, [])
        if not isinstance(value, list):
            raise MeshFormatError(f"{self.path}: '{key}' is not a list; expected a glTF 2.0 "
                                  "asset")
        return value


def read_asset(path: str | os.PathLike[str]) -> GltfAsset:
    """The asset at ``path``: a GLB by its magic bytes, else glTF JSON text. MeshFileError if it
    cannot be read, MeshFormatError naming the file if it is no glTF 2.0 asset."""
    path = Path(os.fspath(path))
    data = read_input(path, what="a glTF file")
    binary, rest = None, b""
    if data[:4] == _MAGIC:
        text, binary, rest = _glb_chunks(data, path)
    else:
        text = data
    try:
        document = json.loads(text.decode("utf-8-sig"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise MeshFormatError(f"{path}: not glTF JSON ({exc}); expected a .gltf or .glb "
                              "asset") from exc
    info = document.get("asset") if isinstance(document, dict) else None
    version = str(info.get("version", "")) if isinstance(info, dict) else ""
    if not version.startswith("2."):
        raise MeshFormatError(f"{path}: asset.version is {version or 'missing'!r}; expected a "
                              "glTF 2.0 asset")
    return GltfAsset(path, document, binary, rest)


def _glb_chunks(data: bytes, path: Path) -> tuple[bytes, bytes | None, bytes]:
    """(JSON text, binary chunk or None, every byte after the JSON chunk) of a GLB."""
    if len(data) < 20:
        raise MeshFormatError(f"{path}: a GLB of {len(data)} bytes; expected a 12-byte header "
                              "and a JSON chunk")
    _, version, length = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise MeshFormatError(f"{path}: GLB version {version}; expected 2")
    if length > len(data):
        raise MeshFormatError(f"{path}: the GLB header says {length} bytes, the file has "
                              f"{len(data)}; the file is truncated")
    json_length, json_type = struct.unpack_from("<II", data, 12)
    if json_type != _JSON_CHUNK or 20 + json_length > length:
        raise MeshFormatError(f"{path}: the first GLB chunk is not a whole JSON chunk; "
                              "expected one")
    rest = data[20 + json_length:length]
    binary = None
    if len(rest) >= 8:
        bin_length, bin_type = struct.unpack_from("<II", rest, 0)
        if bin_type == _BIN_CHUNK:
            if 8 + bin_length > len(rest):
                raise MeshFormatError(f"{path}: the binary chunk runs past the end of the "
                                      "file; the file is truncated")
            binary = rest[8:8 + bin_length]
    # padding: spaces by the spec; some writers pad with NULs, which JSON does not allow
    return data[20:20 + json_length].rstrip(b" \x00"), binary, rest


def asset_bytes(asset: GltfAsset, document: dict) -> bytes:
    """The file of ``asset`` with ``document`` as its JSON: a GLB with the JSON chunk (padded
    with spaces to 4 bytes) followed by the original chunks byte for byte, or JSON text."""
    if not asset.is_glb:
        return (json.dumps(document, ensure_ascii=False, indent=2, allow_nan=False)
                + "\n").encode("utf-8")
    text = json.dumps(document, ensure_ascii=False, separators=(",", ":"),
                      allow_nan=False).encode("utf-8")
    text += b" " * (-len(text) % 4)
    rest = asset.chunks_after_json
    header = struct.pack("<4sII", _MAGIC, 2, 12 + 8 + len(text) + len(rest))
    return header + struct.pack("<II", len(text), _JSON_CHUNK) + text + rest


def relocated_uris(document: dict, source_dir: Path, target_dir: Path) -> dict:
    """``document`` with the relative URIs of its buffers and images rewritten to lead from
    ``target_dir`` to the same files they named from ``source_dir``; unchanged (the same
    object) when both are one folder. data: URIs and URLs stay as they are."""
    if os.path.realpath(source_dir) == os.path.realpath(target_dir):
        return document
    out = dict(document)
    for key in ("buffers", "images"):
        items = document.get(key)
        if not isinstance(items, list):
            continue
        out[key] = [_relocated(item, source_dir, target_dir) for item in items]
    return out


def _relocated(item: Any, source_dir: Path, target_dir: Path) -> Any:
    uri = item.get("uri") if isinstance(item, dict) else None
    if not isinstance(uri, str) or _has_scheme(uri):
        return item
    target = os.path.abspath(source_dir / unquote(uri))
    try:
        relative = os.path.relpath(target, os.path.abspath(target_dir))
    except ValueError as exc:  # another drive (Windows): no relative path exists
        raise MeshFileError(f"{target}: no relative path leads to it from {target_dir}; write "
                            "the copy beside the input") from exc
    return {**item, "uri": quote(relative.replace(os.sep, "/"))}


def _has_scheme(uri: str) -> bool:
    """data:, http:, file:, ... (a Windows drive letter is no scheme)."""
    scheme = urlparse(uri).scheme
    return len(scheme) > 1


def node_linear(node: dict) -> np.ndarray:
    """(3, 3) float: the linear part of a node's local transform (parent <- node): the matrix's
    upper left block, or R(rotation) diag(scale) (rotation [x, y, z, w], glTF's order)."""
    if "matrix" in node:
        m = np.asarray(node["matrix"], dtype=np.float64)
        return m.reshape(4, 4).T[:3, :3]  # stored column-major
    x, y, z, w = (float(c) for c in node.get("rotation", (0.0, 0.0, 0.0, 1.0)))
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return rotation * np.asarray(node.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)


def mesh_nodes(asset: GltfAsset) -> list[tuple[int, int, np.ndarray]]:
    """(node index, mesh index, (3, 3) linear part of the node's transform to the scene root,
    its ancestors' included) for each node that has a mesh, in node order."""
    nodes = asset.list_of("nodes")
    parent: dict[int, int] = {}
    for i, node in enumerate(nodes):
        for child in node.get("children", []) if isinstance(node, dict) else []:
            if not isinstance(child, int) or not 0 <= child < len(nodes) or child in parent:
                raise MeshFormatError(f"{asset.path}: node {i} lists child {child!r}; "
                                      "expected each node in at most one parent")
            parent[child] = i
    found = []
    for i, node in enumerate(nodes):
        if not isinstance(node, dict) or "mesh" not in node:
            continue
        linear, at, seen = np.eye(3), i, {i}
        while True:
            linear = node_linear(nodes[at]) @ linear
            if at not in parent:
                break
            at = parent[at]
            if at in seen:
                raise MeshFormatError(f"{asset.path}: node {i}'s ancestors form a loop; "
                                      "expected a tree")
            seen.add(at)
        found.append((i, _index(node["mesh"], len(asset.list_of("meshes")), asset.path,
                                f"node {i}: mesh"), linear))
    return found


def _buffer(asset: GltfAsset, index: int) -> bytes:
    """Buffer ``index``'s bytes, loaded on first use."""
    if index not in asset.buffers:
        asset.buffers[index] = _load_buffer(asset, index)
    return asset.buffers[index]


def _load_buffer(asset: GltfAsset, index: int) -> bytes:
    buffer = asset.list_of("buffers")[index]
    uri = buffer.get("uri")
    if uri is None:
        if asset.binary is None or index != 0:
            raise MeshFormatError(f"{asset.path}: buffer {index} has no uri and no GLB "
                                  "binary chunk holds it")
        return asset.binary
    if uri.startswith("data:"):
        header, _, payload = uri.partition(",")
        if not header.endswith(";base64"):
            raise MeshFormatError(f"{asset.path}: buffer {index}: a data: URI without "
                                  "base64; expected base64 data")
        try:
            return base64.b64decode(payload, validate=True)
        except ValueError as exc:
            raise MeshFormatError(f"{asset.path}: buffer {index}: bad base64 data") from exc
    if _has_scheme(uri):
        raise MeshFileError(f"{asset.path}: buffer {index} is at {uri}; massprops reads "
                            "local files and data: URIs")
    return read_input(asset.path.parent / unquote(uri), what="a glTF buffer")


def asset_mesh(asset: GltfAsset, index: int, name: str) -> Mesh:
    """Mesh ``index`` of ``asset`` in its own coordinates (the node space of any node that uses
    it; metres, as glTF says), its triangle primitives together; float32 coordinates."""
    mesh = asset.list_of("meshes")[index]
    points, faces, notes, offset = [], [], [], 0
    for k, primitive in enumerate(mesh.get("primitives", [])):
        mode = primitive.get("mode", 4)
        if mode not in _TRIANGLE_MODES:
            notes.append(f"primitive {k} (mode {mode}: points or lines) has no surface; skipped")
            continue
        where = f"{name}: primitive {k}"
        if "POSITION" not in primitive.get("attributes", {}):
            raise MeshFormatError(f"{where}: no POSITION attribute; expected vertex positions")
        xyz = _accessor(asset, primitive["attributes"]["POSITION"], where, position=True)
        if "indices" in primitive:
            flat = _accessor(asset, primitive["indices"], where).reshape(-1)
        else:
            flat = np.arange(xyz.shape[0], dtype=np.int64)
        validate.require_in_range(flat, xyz.shape[0], where, lambda t: f"index {t + 1}")
        faces.append(_triangles(flat, mode, where) + offset)
        points.append(xyz)
        offset += xyz.shape[0]
    vertices = np.concatenate(points) if points else np.empty((0, 3))
    triangles = np.concatenate(faces) if faces else np.empty((0, 3), dtype=np.int64)
    validate.require_content(vertices.shape[0], triangles.shape[0], name)
    validate.require_finite(vertices, name, lambda i: f"position {i + 1}")
    return Mesh(np.ascontiguousarray(vertices, dtype=np.float64), triangles,
                coordinate_dtype=np.dtype(np.float32), name=name, notes=tuple(notes))


def _triangles(flat: np.ndarray, mode: int, where: str) -> np.ndarray:
    """(m, 3) int64 corners of the triangles of a primitive (glTF 2.0 §3.7.2.1)."""
    flat = flat.astype(np.int64)
    if mode == 4:
        if flat.size % 3:
            raise MeshFormatError(f"{where}: {flat.size} triangle indices; expected a multiple "
                                  "of 3")
        return flat.reshape(-1, 3)
    i = np.arange(max(flat.size - 2, 0))
    if mode == 5:  # strip: every other triangle turned so that all wind the same way
        odd = i % 2
        return np.column_stack([flat[i], flat[i + 1 + odd], flat[i + 2 - odd]])
    return np.column_stack([flat[i + 1], flat[i + 2], np.full(i.size, flat[0] if flat.size
                                                              else 0)])


def _index(value: Any, n: int, path: Path, what: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < n:
        raise MeshFormatError(f"{path}: {what} {value!r} does not exist; expected 0..{n - 1}")
    return value


def _accessor(asset: GltfAsset, index: Any, where: str,
              position: bool = False) -> np.ndarray:
    """Accessor ``index`` as an array: (count, 3) float64 for positions, (count,) for indices."""
    path = asset.path
    accessors = asset.list_of("accessors")
    index = _index(index, len(accessors), path, f"{where}: accessor")
    acc = accessors[index]
    what = f"{where}: accessor {index}"
    if "sparse" in acc or "bufferView" not in acc:
        raise MeshFormatError(f"{what} is sparse or has no buffer view (Draco or meshopt "
                              "compression?); massprops reads plain accessors")
    kind, component = acc.get("type"), acc.get("componentType")
    if position and (kind != "VEC3" or component != _FLOAT):
        raise MeshFormatError(f"{what}: POSITION of type {kind} {component}; expected VEC3 "
                              "float (5126), not quantized (KHR_mesh_quantization)")
    if not position and (kind != "SCALAR" or component not in _INDEX_TYPES):
        raise MeshFormatError(f"{what}: indices of type {kind} {component}; expected SCALAR "
                              "unsigned 5121, 5123 or 5125")
    dtype: np.dtype = np.dtype("<f4") if position else _INDEX_TYPES[component]
    width = _COMPONENTS[kind]
    views = asset.list_of("bufferViews")
    view = views[_index(acc["bufferView"], len(views), path, f"{what}: bufferView")]
    data = _buffer(asset, _index(view.get("buffer"), len(asset.list_of("buffers")), path,
                                 f"{what}: buffer"))
    count = int(acc.get("count", 0))
    element = width * dtype.itemsize
    stride = int(view.get("byteStride") or element)
    view_start = int(view.get("byteOffset", 0))
    view_end = view_start + int(view.get("byteLength", 0))
    start = view_start + int(acc.get("byteOffset", 0))
    end = start + (stride * (count - 1) + element if count else 0)
    if count < 0 or stride < element or end > view_end or view_end > len(data):
        raise MeshFormatError(f"{what}: {count} elements run past the end of their buffer "
                              "view or buffer; the file is truncated or inconsistent")
    if count == 0:
        return np.empty((0, width) if position else (0,), dtype=np.float64 if position
                        else np.int64)
    array = np.ndarray((count, width), dtype=dtype, buffer=data, offset=start,
                       strides=(stride, dtype.itemsize))
    return array.astype(np.float64) if position else array[:, 0].astype(np.int64)
