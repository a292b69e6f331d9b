"""MJCF (MuJoCo): bodies, their ``<inertial>`` and the geoms MuJoCo would give them mass from.

Rules from MuJoCo's XML reference (mujoco.readthedocs.io, XML Reference):
- ``<compiler angle>`` is "degree" by default (euler and axisangle angles), ``eulerseq`` "xyz"
  (lower case: moving axes), ``meshdir`` (else ``assetdir``) is where mesh files are, relative
  to the model file, ``strippath`` drops folders from file names, ``inertiafromgeom`` "auto"
  (an ``<inertial>`` wins when present; "true": MuJoCo ignores every ``<inertial>``),
  ``inertiagrouprange`` "0 5" (only geoms of those groups carry mass).
- Default classes: the top ``<default>`` is class "main"; nested ``<default class>`` inherit;
  an element takes its own ``class``, else the nearest enclosing body's or frame's
  ``childclass``, else "main"; its own attributes override the class's.
- Frames: ``pos`` and one of ``quat`` [w x y z], ``axisangle``, ``euler``, ``xyaxes``, ``zaxis``;
  ``<frame>`` elements compose; ``fromto`` (capsule, cylinder, box, ellipsoid) puts the frame
  midway between two points with +z from the first to the second (like ``zaxis``).
- Geom sizes are half-sizes: sphere radius; capsule and cylinder radius, half-length; box half
  edges; ellipsoid radii. With ``fromto`` the length is the points' distance and the other
  half-sizes equal size[0]. ``type`` defaults to sphere, ``density`` to 1000 kg/m³; ``mass``
  overrides density for its geom. A mesh geom's pos/quat place the mesh file's own frame
  (MuJoCo re-centres the mesh internally and compensates), after the asset's ``scale``.
- ``<inertial pos mass diaginertia [quat|euler|...]>`` or ``fullinertia="Ixx Iyy Izz Ixy Ixz
  Iyz"``: the tensor about the centre of mass with products as matrix entries (Ixy = -∫xy dm,
  as massprops), in the inertial frame's axes.
Unnamed bodies are called ``body#k`` with k MuJoCo's body id (depth-first order, world = 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

from massprops.robot.formats.mjcf_tree import expand_includes, replicate_frames, replicate_suffix
from massprops.robot.formats.msh import read_msh
from massprops.robot.formats.poses import (
    axisangle_matrix,
    euler_matrix,
    quat_matrix,
    xyaxes_matrix,
    zaxis_matrix,
)
from massprops.robot.formats.uris import resolve_uri
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node, parse_xml
from massprops.robot.model import Geometry, Link, MassRules, RobotModel, StatedInertial

__all__ = ["parse_mjcf"]

_ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
_DEFAULT_DENSITY = 1000.0


class _Compiler:
    def __init__(self, root: Node, v: Values, path: Path) -> None:
        attrs: dict[str, str] = {}
        node = None
        for node in root.findall("compiler"):
            attrs.update(node.attrs)
        self.node = node or root
        self.angle = attrs.get("angle", "degree")
        if self.angle not in ("degree", "radian"):
            raise v.error(self.node, f"angle={self.angle!r}: expected degree or radian")
        self.eulerseq = attrs.get("eulerseq", "xyz")
        if len(self.eulerseq) != 3 or any(c not in "xyzXYZ" for c in self.eulerseq):
            raise v.error(self.node, f"eulerseq={self.eulerseq!r}: expected 3 of x y z X Y Z")
        if attrs.get("coordinate", "local") != "local":
            raise v.error(self.node, "coordinate='global' was removed from MuJoCo; convert the "
                                     "model to local coordinates")
        self.fromgeom = attrs.get("inertiafromgeom", "auto")
        if self.fromgeom not in ("auto", "true", "false"):
            raise v.error(self.node, f"inertiafromgeom={self.fromgeom!r}: expected auto, true "
                                     "or false")
        folder = attrs.get("meshdir", attrs.get("assetdir", ""))
        self.meshdir = path.parent / folder
        self.assetdir = path.parent / attrs.get("assetdir", "")
        self.strippath = attrs.get("strippath", "false") == "true"
        text = attrs.get("inertiagrouprange")
        groups = v.numbers(self.node, text, "inertiagrouprange=", 2, 'inertiagrouprange="0 5"') \
            if text else np.array([0.0, 5.0])
        self.groups = (int(groups[0]), int(groups[1]))
        self.boundmass = _float(attrs, "boundmass", 0.0, v, self.node)
        self.boundinertia = _float(attrs, "boundinertia", 0.0, v, self.node)
        total = _float(attrs, "settotalmass", -1.0, v, self.node)
        self.settotalmass = total if total > 0 else None

    def radians(self, value: float) -> float:
        return math.radians(value) if self.angle == "degree" else value


def _float(attrs: dict[str, str], key: str, default: float, v: Values, node: Node) -> float:
    if key not in attrs:
        return default
    return float(v.numbers(node, attrs[key], f"{key}=", 1, f'{key}="0"')[0])


def _asset_path(file: str, ctx, node: Node) -> Path:
    """A model asset's file: relative to ``assetdir`` (else the model's folder)."""
    p = Path(file)
    if p.is_absolute():
        return p
    folder = ctx.compiler.assetdir
    return folder / p


def _enclosing_childclass(node: Node) -> str:
    parent = node.parent
    while parent is not None:
        if parent.tag in ("body", "frame") and "childclass" in parent.attrs:
            return parent.attrs["childclass"]
        parent = parent.parent
    return "main"


class _Defaults:
    """class name -> tag -> attributes (inherited from the enclosing classes)."""

    def __init__(self, root: Node, v: Values) -> None:
        self.classes: dict[str, dict[str, dict[str, str]]] = {"main": {}}
        self.v = v
        for top in root.findall("default"):
            self._collect(top, top.attrs.get("class", "main"), {})

    def _collect(self, node: Node, name: str, inherited: dict[str, dict[str, str]]) -> None:
        own = {tag: dict(attrs) for tag, attrs in inherited.items()}
        for child in node.children:
            if child.tag != "default":
                own[child.tag] = {**own.get(child.tag, {}), **child.attrs}
        self.classes[name] = own
        for child in node.findall("default"):
            if "class" not in child.attrs:
                raise self.v.error(child, 'a nested <default> needs class="..."')
            self._collect(child, child.attrs["class"], own)

    def attrs(self, node: Node, childclass: str) -> dict[str, str]:
        name = node.attrs.get("class", childclass)
        if name not in self.classes:
            raise self.v.error(node, f"class={name!r}: no such default class")
        return {**self.classes[name].get(node.tag, {}), **node.attrs}


def parse_mjcf(root: Node, data: bytes, path: Path, *, source: str = "collision",
               package_paths: Sequence[Path] = ()) -> RobotModel:
    """The bodies of an MJCF model (root ``<mujoco>``), its ``<include>`` files spliced in,
    ``<replicate>`` copies made, ``<attach>`` subtrees read from their own model files."""
    v = Values(path)
    if root.tag != "mujoco":
        raise v.error(root, "expected an MJCF file whose root element is <mujoco>")
    ctx = _context(root, path, v, package_paths)
    compiler = ctx.compiler
    warnings = []
    if compiler.fromgeom == "true":
        warnings.append("compiler inertiafromgeom=\"true\": MuJoCo ignores every <inertial>; "
                        "it computes the bodies from their geoms")
    links: list[Link] = []
    walker = _Walker(ctx, source, links, package_paths)
    for body_root in root.findall("worldbody"):
        walker.children(body_root, "main", (np.eye(3), np.zeros(3)), None, ("", ""))
    rules = MassRules(compiler.boundmass, compiler.boundinertia, compiler.settotalmass)
    return RobotModel(path, "mjcf", tuple(links), data, tuple(warnings), rules)


class _Context:
    """One model file's compiler settings, default classes, mesh assets and sub-models."""

    def __init__(self, root: Node, path: Path, v: Values,
                 package_paths: Sequence[Path]) -> None:
        expand_includes(root, path)
        self.root, self.path, self.v = root, path, v
        self.compiler = _Compiler(root, v, path)
        self.defaults = _Defaults(root, v)
        self.meshes = _meshes(root, self.defaults, self.compiler, v, path, package_paths)
        self.models = {}
        for asset in root.findall("asset"):
            for node in asset.findall("model"):
                name, file = node.attrs.get("name"), node.attrs.get("file")
                if not (name and file):
                    raise v.error(node, 'an asset <model> needs name="..." and file="..."')
                self.models[name] = (node, file)


def _context(root: Node, path: Path, v: Values, package_paths: Sequence[Path]) -> _Context:
    return _Context(root, path, v, package_paths)


class _Walker:
    """Depth-first over bodies (MuJoCo's id order), collecting geoms through frames."""

    def __init__(self, ctx: _Context, source, links, package_paths) -> None:
        self.ctx, self.source, self.links = ctx, source, links
        self.package_paths = package_paths
        self.next_id = 1
        self.sub_models: dict[str, _Context] = {}

    @property
    def v(self) -> Values:
        return self.ctx.v

    def children(self, node: Node, childclass: str, frame, geoms: list | None,
                 affix: tuple[str, str]) -> None:
        """Walk ``node``'s children: geoms go to ``geoms`` (None: the world's, dropped) in
        ``frame`` (the pose of ``node``'s frame in the body frame); bodies start a link whose
        name is ``affix[0] + name + affix[1]`` (attach prefix, replicate suffix)."""
        ctx = self.ctx
        for child in node.children:
            if child.tag == "body":
                self.body(child, child.attrs.get("childclass", childclass), affix)
            elif child.tag == "frame":
                attrs = ctx.defaults.attrs(child, childclass) if "class" in child.attrs else \
                    child.attrs
                inner = _compose(frame, _pose(attrs, child, ctx.compiler, self.v))
                self.children(child, child.attrs.get("childclass", childclass), inner, geoms,
                              affix)
            elif child.tag == "replicate":
                self.replicate(child, childclass, frame, geoms, affix)
            elif child.tag == "attach":
                self.attach(child, affix)
            elif child.tag == "geom" and geoms is not None:
                geom = self.geom(child, childclass, frame)
                if geom is not None:
                    geoms.append(geom)

    def replicate(self, node: Node, childclass: str, frame, geoms, affix) -> None:
        v = self.v
        count = v.number(node, "count")
        if count is None or count != int(count) or count < 1:
            raise v.error(node, f"count={node.attrs.get('count')!r}: expected a whole number "
                                ">= 1")
        offset = v.attr(node, "offset", 3, [0, 0, 0])
        angles = v.attr(node, "euler", 3, [0, 0, 0])
        compiler = self.ctx.compiler
        rotation = euler_matrix([compiler.radians(e) for e in angles], compiler.eulerseq)
        sep = node.attrs.get("sep", "")
        for i, pose in enumerate(replicate_frames(int(count), rotation, offset)):
            suffix = replicate_suffix(int(count), i, sep) + affix[1]
            self.children(node, childclass, _compose(frame, pose), geoms, (affix[0], suffix))

    def attach(self, node: Node, affix) -> None:
        """``<attach model body prefix>``: the named body of another model file, its subtree
        read with that file's compiler, defaults and assets, every name prefixed."""
        v, ctx = self.v, self.ctx
        name, body = node.attrs.get("model"), node.attrs.get("body")
        if name not in ctx.models:
            raise v.error(node, f"model={name!r}: no <asset><model name=...> of that name")
        if not body:
            raise v.error(node, 'massprops attaches one body: give body="..."')
        model_node, file = ctx.models[name]
        if name not in self.sub_models:
            sub_path = _asset_path(file, ctx, model_node)
            root, _ = parse_xml(sub_path)
            self.sub_models[name] = _Context(root, sub_path, Values(sub_path),
                                             self.package_paths)
        sub = self.sub_models[name]
        found = [b for b in sub.root.iter("body") if b.attrs.get("name") == body]
        if not found:
            raise v.error(node, f"body={body!r}: no such body in {sub.path}")
        outer, self.ctx = self.ctx, sub
        try:
            start = found[0]
            klass = start.attrs.get("childclass", _enclosing_childclass(start))
            self.body(start, klass, (affix[0] + node.attrs.get("prefix", ""), affix[1]))
        finally:
            self.ctx = outer

    def body(self, node: Node, childclass: str, affix=("", "")) -> None:
        body_id = self.next_id
        self.next_id += 1
        geoms: list[Geometry] = []
        warnings: list[str] = []
        inertial = node.find("inertial")
        stated = None
        compiler = self.ctx.compiler
        if inertial is not None:
            if compiler.fromgeom == "true":
                warnings.append(f"<inertial> (line {inertial.line}) is ignored by MuJoCo "
                                "(inertiafromgeom=true)")
            else:
                stated = _stated(inertial, compiler, self.v)
        own = node.attrs.get("name")
        name = affix[0] + own + affix[1] if own else f"body#{body_id}"
        # a link's own entry goes in before its children's, so the order is MuJoCo's id order
        at = len(self.links)
        self.children(node, childclass, (np.eye(3), np.zeros(3)), geoms, affix)
        self.links.insert(at, Link(name, node, stated, tuple(geoms), inertial, tuple(warnings)))

    def geom(self, node: Node, childclass: str, frame) -> Geometry | None:
        a = self.ctx.defaults.attrs(node, childclass)
        v = self.v
        compiler = self.ctx.compiler
        group = int(float(a.get("group", "0")))
        lo, hi = compiler.groups
        if self.source == "visual":
            if not (a.get("contype", "1").strip() == "0" and a.get("conaffinity", "1").strip()
                    == "0"):
                return None
        elif not lo <= group <= hi:
            return None
        # MuJoCo: a geom that names a mesh and no type is a mesh geom (else the type is sphere)
        kind = a.get("type", "mesh" if "mesh" in a else "sphere")
        density = float(a.get("density", _DEFAULT_DENSITY))
        mass = float(a["mass"]) if "mass" in a else None
        if (mass if mass is not None else density) == 0:
            return None  # a massless geom (a decoration, a camera box): no part of the body
        size = v.numbers(node, a["size"], "size=", (1, 2, 3), 'size="0.1 0.2 0.3"') \
            if "size" in a else np.zeros(0)
        pose = _pose(a, node, compiler, v)
        common: dict[str, Any] = {"node": node, "density": density, "mass": mass}
        if "fromto" in a and kind in ("capsule", "cylinder", "box", "ellipsoid"):
            ends = v.numbers(node, a["fromto"], "fromto=", 6, 'fromto="0 0 0 0 0 1"')
            length = float(np.linalg.norm(ends[3:] - ends[:3]))
            if length == 0:
                raise v.error(node, "fromto: the two points coincide; give distinct points")
            pose = (zaxis_matrix(ends[3:] - ends[:3]), (ends[:3] + ends[3:]) / 2)
            size = np.concatenate([size[:1], size[:1], [length / 2]]) if kind in (
                "box", "ellipsoid") else np.array([size[0] if size.size else 0.0, length / 2])
        rotation, translation = _compose(frame, pose)
        common.update(rotation=rotation, translation=translation)
        if a.get("shellinertia", "false") == "true":
            return Geometry(kind, problem="shellinertia=\"true\" (a hollow shell) is not "
                                          "supported; massprops integrates solids", **common)
        need = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
        if kind in need:
            if size.size < need[kind] or np.any(size[:need[kind]] <= 0):
                raise v.error(node, f"type {kind} needs {need[kind]} positive size value(s), "
                                    f"got size={a.get('size', '')!r}")
            s = [float(x) for x in size[:need[kind]]]
            if kind in ("capsule", "cylinder"):    # radius, half-length -> full length
                s[1] *= 2
            elif kind == "box":                    # half edges -> edges
                s = [2 * x for x in s]
            return Geometry(kind, dims=tuple(s), **common)
        if kind == "mesh":
            name = a.get("mesh")
            if name not in self.ctx.meshes:
                raise v.error(node, f"mesh={name!r}: no <mesh> asset of that name")
            mesh = self.ctx.meshes[name]
            warning = None
            rule = mesh["inertia"]
            if rule in ("exact", "shell") or (mesh["faces"] is None
                                               and mesh["vertices"] is not None):
                pass  # points only: the mesh is their hull, for MuJoCo and massprops alike
            elif rule == "convex":
                warning = (f"mesh {name!r}: MuJoCo's mesh inertia 'convex' integrates the "
                           "convex hull; massprops the mesh itself (add inertia=\"exact\" to "
                           "the <mesh> to make MuJoCo agree on a non-convex mesh)")
            else:
                warning = (f"mesh {name!r}: MuJoCo's mesh inertia {rule!r} (its default) "
                           "integrates the mesh's own faces, each face's pyramid volume taken "
                           "positive, which overcounts a non-convex mesh; massprops integrates "
                           "the exact volume (add inertia=\"exact\" to the <mesh> to make "
                           "MuJoCo agree)")
            return Geometry("mesh", path=mesh["path"], uri=mesh["uri"], scale=mesh["scale"],
                            problem=mesh["problem"], vertices=mesh["vertices"],
                            faces=mesh["faces"], warning=warning, rule=rule, **common)
        return Geometry(kind, problem=f"geom type {kind!r} (line {node.line}) has no volume "
                                      "massprops can integrate", **common)


def _compose(a, b):
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def _pose(a: dict[str, str], node: Node, compiler: _Compiler, v: Values):
    pos = v.numbers(node, a["pos"], "pos=", 3, 'pos="0 0 0"') if "pos" in a else np.zeros(3)
    own = [k for k in _ORIENTATIONS if k in node.attrs]
    given = own or [k for k in _ORIENTATIONS if k in a]
    if len(given) > 1:
        raise v.error(node, f"give one orientation, got {' and '.join(given)}")
    if not given:
        return np.eye(3), pos
    key = given[0]
    text = node.attrs.get(key, a.get(key, ""))
    if key == "quat":
        q = v.numbers(node, text, "quat=", 4, 'quat="1 0 0 0"')
        if not np.any(q):
            raise v.error(node, "quat= is zero; use 1 0 0 0 for no rotation")
        return quat_matrix(q), pos
    if key == "axisangle":
        x = v.numbers(node, text, "axisangle=", 4, 'axisangle="0 0 1 90"')
        if not np.any(x[:3]):
            raise v.error(node, "axisangle= has a zero axis")
        return axisangle_matrix(x[:3], compiler.radians(x[3])), pos
    if key == "euler":
        x = v.numbers(node, text, "euler=", 3, 'euler="0 0 90"')
        return euler_matrix([compiler.radians(e) for e in x], compiler.eulerseq), pos
    if key == "xyaxes":
        x = v.numbers(node, text, "xyaxes=", 6, 'xyaxes="1 0 0 0 1 0"')
        if np.linalg.norm(np.cross(x[:3], x[3:])) == 0:
            raise v.error(node, "xyaxes= has parallel or zero axes")
        return xyaxes_matrix(x[:3], x[3:]), pos
    x = v.numbers(node, text, "zaxis=", 3, 'zaxis="0 0 1"')
    if not np.any(x):
        raise v.error(node, "zaxis= is zero")
    return zaxis_matrix(x), pos


def _stated(node: Node, compiler: _Compiler, v: Values) -> StatedInertial:
    if "mass" not in node.attrs or "pos" not in node.attrs:
        raise v.error(node, "an <inertial> needs pos= and mass=")
    rotation, pos = _pose(node.attrs, node, compiler, v)
    mass = cast(float, v.number(node, "mass"))  # mass= is there (checked above)
    if "fullinertia" in node.attrs:
        f = v.numbers(node, node.attrs["fullinertia"], "fullinertia=", 6,
                      'fullinertia="Ixx Iyy Izz Ixy Ixz Iyz"')
        j = np.array([[f[0], f[3], f[4]], [f[3], f[1], f[5]], [f[4], f[5], f[2]]])
    elif "diaginertia" in node.attrs:
        j = np.diag(v.numbers(node, node.attrs["diaginertia"], "diaginertia=", 3,
                              'diaginertia="0.1 0.1 0.1"'))
    else:
        raise v.error(node, "an <inertial> needs diaginertia= or fullinertia=")
    return StatedInertial(mass, pos, rotation @ j @ rotation.T, node)


def _meshes(root: Node, defaults: _Defaults, compiler: _Compiler, v: Values, path: Path,
            package_paths: Sequence[Path]) -> dict[str, dict]:
    out = {}
    for asset in root.findall("asset"):
        for node in asset.findall("mesh"):
            a = defaults.attrs(node, "main")
            file = a.get("file", "")
            name = a.get("name") or Path(file).stem
            scale = v.numbers(node, a["scale"], "scale=", 3, 'scale="1 1 1"') if "scale" in a \
                else np.ones(3)
            entry: dict[str, Any] = {"uri": file, "scale": scale, "path": None, "problem": None,
                     "vertices": None, "faces": None, "inertia": a.get("inertia", "legacy")}
            if "vertex" in a:
                counts = [len(a[k].split()) for k in ("vertex", "face") if k in a]
                if any(c % 3 for c in counts):
                    raise v.error(node, "vertex= and face= need 3 numbers per vertex and face")
                entry["vertices"] = v.numbers(node, a["vertex"], "vertex=", counts[0],
                                              'vertex="0 0 0 1 0 0 0 1 0 0 0 1"').reshape(-1, 3)
                if "face" in a:
                    entry["faces"] = v.numbers(node, a["face"], "face=", counts[1],
                                               'face="0 2 1 0 1 3"').astype(np.int64).reshape(
                                                   -1, 3)
                # else MuJoCo makes the convex hull of the points (`combine.MeshCache`)
                entry["uri"] = f"<mesh name={name!r}> (line {node.line})"
            elif file:
                ref = Path(file).name if compiler.strippath else file
                entry["path"], entry["problem"] = resolve_uri(ref, compiler.meshdir, path,
                                                              package_paths)
                if entry["problem"] is None and entry["path"].suffix.lower() == ".msh":
                    read_msh(entry)
            else:
                entry["problem"] = (f"<mesh name={name!r}> (line {node.line}) has neither file= "
                                    "nor vertex=; give one")
            for legacy in ("refpos", "refquat"):
                if legacy in a:
                    entry["problem"] = f"<mesh {legacy}=> (line {node.line}) is not supported"
            out[name] = entry
    return out
