"""Value objects of the joints that hold a body to the world (the scene's ``joints:`` list).

Frames as in massprops.dynamics.model: ``point`` and ``axis`` are body coordinates (the mesh's
axes and origin), ``anchor`` and ``world_axis`` world coordinates. Axes are unit vectors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class SphericalJoint:
    """The body point ``point`` (3,) m, body coordinates (None: the centre of mass) is held at
    the world point ``anchor`` (3,) m; the body may turn freely about it (a ball joint, a top's
    tip, a gimbal)."""

    anchor: np.ndarray
    point: np.ndarray | None = None

    kind = "spherical"


@dataclass(frozen=True, eq=False)
class RevoluteJoint:
    """The body may only turn about its axis ``axis`` (3,) unit, body coordinates, through
    ``point`` (3,) m body coordinates (None: the centre of mass), held on the world axis through
    ``anchor`` (3,) m with direction ``world_axis`` (3,) unit (None: where the initial
    orientation turns ``axis``): a hinge, a rotor in its bearings, a compound pendulum.

    damping : N·m·s/rad, a torque -damping·θ̇ about the axis (θ̇ the rate about ``axis``).
    torque : N·m, a driving torque about ``axis`` (right hand) while start <= t < end (s).
    """

    axis: np.ndarray
    anchor: np.ndarray
    point: np.ndarray | None = None
    world_axis: np.ndarray | None = None
    damping: float = 0.0
    torque: float = 0.0
    start: float = -math.inf
    end: float = math.inf

    kind = "revolute"


Joint = SphericalJoint | RevoluteJoint
