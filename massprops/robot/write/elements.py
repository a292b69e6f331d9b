"""The ``<inertial>`` element of each format, as text to paste or to write back.

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

__all__ = ["WRITERS", "mjcf_inertial", "sdf_inertial", "urdf_inertial"]

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


WRITERS: dict[str, Writer] = {"urdf": urdf_inertial, "sdf": sdf_inertial, "mjcf": mjcf_inertial}
"""format name -> writer of its ``<inertial>`` element."""
