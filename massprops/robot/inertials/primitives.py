"""Exact mass properties of the primitive solids of robot descriptions, per unit density.

Each solid sits in its own frame with its centre of mass at the origin; cylinder, capsule and
cone have their axis along z. Returned inertias are J = -∫ s̃ s̃ dV (m⁵: multiply by the density in
kg/m³ for kg·m²) about the centre of mass, in the primitive's axes: J_xx = ∫(y² + z²) dV,
J_xy = -∫ x y dV (zero here, every primitive is symmetric about its own axes).

Dimensions are the SI sizes of the *shape*, not of any one file format: full edge lengths of a
box, the cylinder part's full length of a capsule (without its caps), radii of an ellipsoid. The
parsers translate each format's convention (MJCF half-sizes, half-lengths, fromto) into these.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["Solid", "box", "capsule", "cone", "cylinder", "ellipsoid", "sphere", "PRIMITIVES"]


@dataclass(frozen=True, eq=False)
class Solid:
    """A primitive solid of unit density about its centre of mass.

    kind : "box", "sphere", "cylinder", "capsule", "ellipsoid" or "cone".
    dims : (k,) float, m, the arguments it was made from (see each constructor).
    volume : m³. inertia : (3, 3) float, m⁵ (kg·m² per kg/m³), about the centre, own axes.
    """

    kind: str
    dims: tuple[float, ...]
    volume: float
    inertia: np.ndarray

    def half_extents(self, rotation: np.ndarray) -> np.ndarray:
        """(3,) m: half-widths of the axis-aligned box around the solid after ``rotation``
        (3, 3) maps its axes into the target axes (v_target = rotation @ v_own)."""
        r = np.asarray(rotation, dtype=np.float64)
        d = self.dims
        if self.kind == "box":
            return np.abs(r) @ (np.asarray(d) / 2)
        if self.kind == "sphere":
            return np.full(3, d[0])
        if self.kind == "ellipsoid":
            return np.sqrt((r * r) @ (np.asarray(d) ** 2))
        axis = np.abs(r[:, 2])            # the z axis in target coordinates
        radius, half = d[0], d[1] / 2
        if self.kind == "cone":           # from the centre: the apex 3L/4 away, the base L/4
            return axis * 1.5 * half + radius * np.sqrt(np.maximum(0.0, 1.0 - axis * axis))
        if self.kind == "cylinder":       # a disc of radius r spans r·sqrt(1 - a_i²) on axis i
            return axis * half + radius * np.sqrt(np.maximum(0.0, 1.0 - axis * axis))
        return axis * half + radius       # capsule: the segment swept by a ball


def _positive(kind: str, **dims: float) -> None:
    for name, value in dims.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{kind}: {name} must be a positive finite length in metres, "
                             f"got {value!r}")


def _diagonal(a: float, b: float, c: float) -> np.ndarray:
    out = np.diag([a, b, c]).astype(np.float64)
    out.setflags(write=False)
    return out


def box(size_x: float, size_y: float, size_z: float) -> Solid:
    """A box of full edge lengths (m). V = abc, J_xx = V (b² + c²) / 12."""
    _positive("box", size_x=size_x, size_y=size_y, size_z=size_z)
    a2, b2, c2 = size_x**2, size_y**2, size_z**2
    v = size_x * size_y * size_z
    return Solid("box", (size_x, size_y, size_z), v,
                 _diagonal(v * (b2 + c2) / 12, v * (a2 + c2) / 12, v * (a2 + b2) / 12))


def sphere(radius: float) -> Solid:
    """A ball of ``radius`` (m). V = 4πr³/3, J = 2 V r² / 5 on each axis."""
    _positive("sphere", radius=radius)
    v = 4.0 * math.pi * radius**3 / 3
    j = 2.0 * v * radius**2 / 5
    return Solid("sphere", (radius,), v, _diagonal(j, j, j))


def ellipsoid(radius_x: float, radius_y: float, radius_z: float) -> Solid:
    """A solid ellipsoid of semi-axes (m). V = 4πabc/3, J_xx = V (b² + c²) / 5."""
    _positive("ellipsoid", radius_x=radius_x, radius_y=radius_y, radius_z=radius_z)
    a2, b2, c2 = radius_x**2, radius_y**2, radius_z**2
    v = 4.0 * math.pi * radius_x * radius_y * radius_z / 3
    return Solid("ellipsoid", (radius_x, radius_y, radius_z), v,
                 _diagonal(v * (b2 + c2) / 5, v * (a2 + c2) / 5, v * (a2 + b2) / 5))


def cylinder(radius: float, length: float) -> Solid:
    """A solid cylinder along z, centred: radius and full ``length`` (m). V = πr²L,
    J_zz = V r² / 2, J_xx = J_yy = V (3r² + L²) / 12."""
    _positive("cylinder", radius=radius, length=length)
    r2 = radius**2
    v = math.pi * r2 * length
    jxx = v * (3 * r2 + length**2) / 12
    return Solid("cylinder", (radius, length), v, _diagonal(jxx, jxx, v * r2 / 2))


def capsule(radius: float, length: float) -> Solid:
    """A cylinder of full ``length`` (m, between the caps' centres) along z, centred, closed by
    two hemispheres of ``radius``. Cylinder part Vc = πr²L, caps together Vh = 4πr³/3;
    J_zz = Vc r²/2 + 2 Vh r²/5;
    J_xx = Vc (3r² + L²)/12 + Vh (2r²/5 + L²/4 + 3Lr/8): each cap about its own centre of mass
    (3r/8 from its flat face) shifted by L/2 + 3r/8 (parallel axes). A zero ``length`` is a
    sphere."""
    _positive("capsule", radius=radius)
    if not (math.isfinite(length) and length >= 0):
        raise ValueError(f"capsule: length must be a finite length >= 0 in metres, got {length!r}")
    r2 = radius**2
    vc = math.pi * r2 * length
    vh = 4.0 * math.pi * radius**3 / 3
    caps = vh * (2 * r2 / 5 + length**2 / 4 + 3 * length * radius / 8)
    jxx = vc * (3 * r2 + length**2) / 12 + caps
    return Solid("capsule", (radius, length), vc + vh,
                 _diagonal(jxx, jxx, vc * r2 / 2 + 2 * vh * r2 / 5))


def cone(radius: float, length: float) -> Solid:
    """A solid right circular cone along z (apex towards +z) about its centre of mass, which is
    ``length``/4 above the base: base ``radius``, height ``length`` (m). V = πr²L/3,
    J_zz = 3 V r² / 10, J_xx = J_yy = 3 V (r²/20 + L²/80) (about the centre of mass; the parser
    shifts a format's cone frame onto it: SDF's frame is at mid-height, sdformat's Cone)."""
    _positive("cone", radius=radius, length=length)
    r2 = radius**2
    v = math.pi * r2 * length / 3
    jxx = 3 * v * (r2 / 20 + length**2 / 80)
    return Solid("cone", (radius, length), v, _diagonal(jxx, jxx, 3 * v * r2 / 10))


PRIMITIVES: dict[str, Callable[..., Solid]] = {
    "box": box, "sphere": sphere, "ellipsoid": ellipsoid, "cylinder": cylinder,
    "capsule": capsule, "cone": cone}
"""kind -> constructor, each taking the dims of ``Solid.dims`` in order."""
