"""The ``<inertial>`` element of each format, as text to paste or to write back, and the mass
properties of the engines' formats (glTF's ``KHR_physics_rigid_bodies``, USD's
``PhysicsMassAPI``), which state them in the principal frame.

Every writer takes (mass kg, center_of_mass (3,) m, inertia (3, 3) kg·m² about the COM in the
link/mesh axes) and returns the element; the inertial frame is the link frame moved to the COM
(rpy / orientation zero), so the six numbers are the tensor's own entries: products as matrix
entries, ixy = J_xy = -∫xy dm, the convention all three formats share with massprops. Numbers are
Python's repr of the float64: the shortest text that reads back as the same float.
``WRITERS`` maps a format name to its writer; the CLI's ``--format`` choices are its keys.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from massprops.errors import setting_ref

__all__ = ["WRITERS", "gltf_motion", "gltf_motion_object", "mjcf_inertial", "sdf_inertial",
           "urdf_inertial", "usd_mass"]

Writer = Callable[..., str]


def _num(x: float) -> str:
    return repr(float(x) + 0.0)  # + 0.0: a -0.0 prints as 0.0


def _nums(values) -> str:
    return " ".join(_num(x) for x in values)


def _six(j: np.ndarray) -> tuple[float, ...]:
    """ixx ixy ixz iyy iyz izz of a (symmetrised) tensor."""
    j = 0.5 * (np.asarray(j, dtype=np.float64) + np.asarray(j, dtype=np.float64).T)
    return j[0, 0], j[0, 1], j[0, 2], j[1, 1], j[1, 2], j[2, 2]


def urdf_inertial(mass: float, center_of_mass, inertia, *, indent: str = "  ",
                  newline: str = "\n", principal: bool = False) -> str:
    """URDF ``<inertial>``: origin at the COM with rpy 0, mass, the six entries."""
    _no_principal(principal, "urdf")
    ixx, ixy, ixz, iyy, iyz, izz = (_num(x) for x in _six(inertia))
    return newline.join([
        "<inertial>",
        f'{indent}<origin xyz="{_nums(center_of_mass)}" rpy="0 0 0"/>',
        f'{indent}<mass value="{_num(mass)}"/>',
        f'{indent}<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" '
        f'izz="{izz}"/>',
        "</inertial>"])


def sdf_inertial(mass: float, center_of_mass, inertia, *, indent: str = "  ",
                 newline: str = "\n", principal: bool = False) -> str:
    """SDF ``<inertial>``: pose at the COM (rpy 0), mass, inertia with its six children."""
    _no_principal(principal, "sdf")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    entries = [f"{indent * 2}<{k}>{_num(x)}</{k}>" for k, x in zip(keys, _six(inertia))]
    return newline.join([
        "<inertial>",
        f"{indent}<pose>{_nums(center_of_mass)} 0 0 0</pose>",
        f"{indent}<mass>{_num(mass)}</mass>",
        f"{indent}<inertia>", *entries, f"{indent}</inertia>",
        "</inertial>"])


def mjcf_inertial(mass: float, center_of_mass, inertia, *, indent: str = "  ",
                  newline: str = "\n", principal: bool = False) -> str:
    """MJCF ``<inertial>``: pos, mass and fullinertia="Ixx Iyy Izz Ixy Ixz Iyz"; with
    ``principal``, quat (principal frame -> body, [w x y z]) and diaginertia (ascending)."""
    pos = f'pos="{_nums(center_of_mass)}" mass="{_num(mass)}"'
    if principal:
        # deferred: writing a stated inertial needs no eigen-solver unless principal
        from massprops.inertia import principal_axes
        from massprops.rotation import matrix_to_quat

        moments, axes = principal_axes(np.asarray(inertia, dtype=np.float64))
        return (f'<inertial {pos} quat="{_nums(matrix_to_quat(axes))}" '
                f'diaginertia="{_nums(moments)}"/>')
    ixx, ixy, ixz, iyy, iyz, izz = _six(inertia)
    return f'<inertial {pos} fullinertia="{_nums([ixx, iyy, izz, ixy, ixz, iyz])}"/>'


def _no_principal(principal: bool, name: str) -> None:
    if principal:
        # deferred: writing a stated inertial needs no eigen-solver unless principal
        from massprops.errors import UsageError

        raise UsageError(f"{setting_ref('principal')} is for {setting_ref('format')} mjcf (quat + "
                         f"diaginertia); {name} gets the tensor in the link axes")


def _principal(inertia) -> tuple[np.ndarray, np.ndarray]:
    """(ascending moments, the principal frame's quaternion [w, x, y, z], w >= 0): the
    rotation taking principal-frame coordinates into the mesh/link frame."""
    # deferred: only the engines' formats (and mjcf --principal) need the eigen-solver
    from massprops.inertia import principal_axes
    from massprops.rotation import matrix_to_quat

    moments, axes = principal_axes(np.asarray(inertia, dtype=np.float64))
    return moments, matrix_to_quat(axes)


def gltf_motion_object(mass: float, center_of_mass, inertia) -> dict[str, object]:
    """glTF ``KHR_physics_rigid_bodies`` motion as a dict: ``{"mass", "centerOfMass",
    "inertiaDiagonal", "inertiaOrientation"}``; kg, m, kg·m² in the node's (mesh's) frame; the
    diagonal is the principal moments (ascending) in the frame the orientation gives, a unit
    quaternion in glTF's order [x, y, z, w] taking that frame into the node's (w >= 0).
    ``inspect --format gltf`` prints it, ``--write-physics`` puts it on the nodes."""
    moments, q = _principal(inertia)
    return {"mass": float(mass) + 0.0,
            "centerOfMass": [float(x) + 0.0 for x in center_of_mass],
            "inertiaDiagonal": [float(x) + 0.0 for x in moments],
            "inertiaOrientation": [float(x) + 0.0 for x in (*q[1:], q[0])]}


def gltf_motion(mass: float, center_of_mass, inertia, *, indent: str = "  ",
                newline: str = "\n", principal: bool = False) -> str:
    """`gltf_motion_object` as one JSON object on one line. Always principal: ``principal`` is
    accepted and changes nothing."""
    # deferred: json only for this format
    import json

    return json.dumps(gltf_motion_object(mass, center_of_mass, inertia))


def usd_mass(mass: float, center_of_mass, inertia, *, indent: str = "    ",
             newline: str = "\n", principal: bool = False, name: str = "Body") -> str:
    """A usda prim with ``PhysicsMassAPI`` applied: ``physics:mass`` (kg),
    ``physics:centerOfMass`` (m, the prim's frame), ``physics:diagonalInertia`` (kg·m², the
    principal moments ascending) and ``physics:principalAxes`` (the quaternion taking the
    principal frame into the prim's, USD's order: real first). ``name``: the prim's name (made
    a valid identifier). Always principal, as USD states it."""
    moments, q = _principal(inertia)
    ident = "".join(c if c.isalnum() or c == "_" else "_" for c in name) or "Body"
    if ident[0].isdigit():
        ident = "_" + ident
    return newline.join([
        f'def Xform "{ident}" (',
        f'{indent}prepend apiSchemas = ["PhysicsMassAPI"]',
        ")",
        "{",
        f"{indent}float physics:mass = {_num(mass)}",
        f"{indent}point3f physics:centerOfMass = ({', '.join(_num(x) for x in center_of_mass)})",
        f"{indent}float3 physics:diagonalInertia = ({', '.join(_num(x) for x in moments)})",
        f"{indent}quatf physics:principalAxes = ({', '.join(_num(x) for x in q)})",
        "}"])


WRITERS: dict[str, Writer] = {"urdf": urdf_inertial, "sdf": sdf_inertial, "mjcf": mjcf_inertial,
                              "gltf": gltf_motion, "usd": usd_mass}
"""format name -> writer of its element: the robot formats' ``<inertial>``, glTF's
``KHR_physics_rigid_bodies`` motion, USD's ``PhysicsMassAPI`` prim."""
