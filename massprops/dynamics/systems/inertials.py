"""A description's stated inertials as the systems engine takes them (`description.describe`).

SDFormat's default for a link without ``<inertial>`` (sdformat's Link: 1 kg, unit moments at
the link origin, as Gazebo simulates it); the judgement of stated tensors: a negative or
non-finite mass is refused, a tensor no rigid body has (negative moment, triangle inequality) is
said once and simulated as written, unless the body it ends up in (welded links lumped) has a
negative moment, which makes the mass matrix indefinite and is refused. Every refusal is one
line naming the file, the line and the link, and what to do.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.errors import RobotModelError
from massprops.tolerances import INERTIA_VALIDITY_RTOL

__all__ = ["check_bodies", "judged", "sdf_defaults"]


def sdf_defaults(model, masses: dict) -> list[str]:
    """SDFormat gives a link without ``<inertial>`` 1 kg and unit moments at its origin
    (sdformat's Link, as Gazebo simulates it): those links get it, named in one warning."""
    bare = [link.name for link in model.links
            if link.name not in masses and link.inertial_node is None]
    for name in bare:
        masses[name] = (1.0, np.zeros(3), np.eye(3))
    if not bare:
        return []
    return [f"link(s) {', '.join(map(repr, bare[:4]))}{' ...' if len(bare) > 4 else ''} have "
            "no <inertial>: SDFormat's default, 1 kg with unit moments (kg·m²) at the link "
            "origin, as Gazebo simulates them"]


_FIX = ("fix the inertial, or simulate a scene with 'inertials: computed' (from the link's "
        "geometry)")


def judged(masses: dict, path: Path, nodes: dict) -> tuple[list[str], float]:
    """(one warning naming the links whose stated tensor no rigid body has, the tolerance of a
    negative moment); RobotModelError for a negative or non-finite mass or entry.

    A tensor with a negative principal moment or one breaking the triangle inequality is said
    and simulated as written (URDF tools take them; CAD exports carry -3.5e-8 on a welded
    antenna, TIAGo): what matters is the body it joins (`check_bodies`). A moment counts as
    negative below -INERTIA_VALIDITY_RTOL times the description's scale (the largest link
    inertia about its frame's origin), so a point mass written with zeros, or with -5e-20
    round-off (iCub), is a point mass."""
    # the scale: each link's inertia about its own frame's origin, the largest of them
    largest = max((float(np.abs(j).max()) + abs(m) * float(c @ c)
                   for m, c, j in masses.values()), default=0.0)
    tol = INERTIA_VALIDITY_RTOL * largest if np.isfinite(largest) else 0.0
    broken = []
    for name, (mass, com, inertia) in masses.items():
        node = nodes.get(name)
        if not (np.isfinite(mass) and mass >= 0 and np.isfinite(com).all()
                and np.isfinite(inertia).all()):
            where = "" if node is None else f"{node.file or path}:{node.line}: "
            raise RobotModelError(f"{where or f'{path}: '}link {name!r}: the stated inertial "
                                  f"has a negative or non-finite mass or entry; {_FIX}")
        moments = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
        if moments[0] < -tol or moments[2] > moments[0] + moments[1] + tol:
            broken.append(name)
    if not broken:
        return [], tol
    return [f"link(s) {', '.join(map(repr, broken[:4]))}{' ...' if len(broken) > 4 else ''}: "
            "the stated inertia is not physically valid (a negative principal moment, or one "
            "above the sum of the other two): simulated as written"], tol


def check_bodies(desc, tol: float, nodes: dict) -> None:
    """RobotModelError when a body the engine integrates (a link, or links welded together) has
    a negative principal moment beyond ``tol``: its mass matrix is indefinite."""
    for body in desc.bodies:
        low = float(np.linalg.eigvalsh(0.5 * (body.inertia + body.inertia.T))[0])
        if low < -tol:
            members = [n for n, k in desc.body_of.items() if k == desc.bodies.index(body)]
            node = nodes.get(body.name)
            where = f"{desc.path}: " if node is None else f"{node.file or desc.path}:{node.line}: "
            welded = [repr(n) for n in members if n != body.name]
            also = f" (welded to {', '.join(welded[:4])})" if welded else ""
            raise RobotModelError(f"{where}link {body.name!r}{also} has a negative "
                                  f"principal moment ({low:.6g} kg·m²) from its stated "
                                  f"inertials: no body has it; {_FIX}")
