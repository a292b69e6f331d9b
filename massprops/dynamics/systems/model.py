"""Value objects of a system scene: bodies placed at t = 0, joints, forces, initial values.

Frames: *world* (inertial); each body's frame has its origin at the body's centre of mass and
the body's own axes (the mesh's axes; an explicit body's given axes). ``rotation0`` turns body
-> world at t = 0 (the assembly pose), ``com0`` is the centre of mass in world at t = 0. Joint
points and axes are world coordinates at t = 0, as the contract says.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from massprops.dynamics.model import MeshSource, OutputSettings, TimeSettings

WORLD = -1
"""Body index of the world (the ground) in joints and forces."""

JOINT_DOFS = {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 3,
              "fixed": 0, "distance": 5, "free": 6}
"""Rates (degrees of freedom) a joint leaves between its two bodies when it is a tree joint; a
distance joint is always a cut joint (one constraint: 5 relative freedoms)."""

ONE_AXIS = ("revolute", "prismatic")
"""Joints that may carry damping, a spring (stiffness, rest) and a drive (torque or force)."""


@dataclass(frozen=True, eq=False)
class SystemBody:
    """name; mass kg; inertia (3, 3) kg·m² about the COM, body axes; rotation0 (3, 3) body ->
    world at t = 0; com0 (3,) m world at t = 0; size m (a length scale); mesh: a mesh body's
    file and inspect's bars (`dynamics.model.MeshSource`, its axes the body axes), else None."""

    name: str
    mass: float
    inertia: np.ndarray
    rotation0: np.ndarray
    com0: np.ndarray
    size: float
    mesh: MeshSource | None = None


@dataclass(frozen=True, eq=False)
class SystemJoint:
    """A joint between bodies ``a`` and ``b`` (indices; WORLD = -1), second body ``b``.

    kind : one of JOINT_DOFS except "free". point (3,) m world at t = 0 (distance: None);
    axes (k, 3) unit, world at t = 0 (revolute, prismatic, cylindrical: 1; universal: 2);
    points (2, 3) the distance joint's end points on a and b (world, t = 0).
    damping N·m·s/rad or N·s/m; stiffness N·m/rad or N/m about ``rest``; drive N·m or N
    while start <= t < end. loop: never a tree joint (a robot description's closing joint).
    """

    name: str
    kind: str
    a: int
    b: int
    point: np.ndarray | None
    axes: np.ndarray
    points: np.ndarray | None = None
    damping: float = 0.0
    stiffness: float = 0.0
    rest: float = 0.0
    drive: float = 0.0
    start: float = -math.inf
    end: float = math.inf
    loop: bool = False  # always a cut joint (a description's loop-closing joint)


@dataclass(frozen=True, eq=False)
class JointCoupling:
    """A linear relation between one-axis joints' coordinates, Σ c_i q_i = constant (a URDF or
    SDF ``<mimic>``, an MJCF joint or fixed-tendon equality): ``terms`` ((scene joint index,
    c_i), ...), the first the follower whose unit (rad or m) the relation is written in;
    ``where`` the ``file:line: element: `` of its messages."""

    name: str
    terms: tuple
    constant: float = 0.0
    where: str = ""


@dataclass(frozen=True, eq=False)
class BodyForce:
    """kind "force" (N) or "torque" (N·m) on ``body``, ``vector`` in ``frame`` (world or body
    axes); a force acts at ``point`` (world at t = 0; None: the COM); start <= t < end."""

    kind: str
    body: int
    vector: np.ndarray
    frame: str = "world"
    point: np.ndarray | None = None
    start: float = -math.inf
    end: float = math.inf


@dataclass(frozen=True, eq=False)
class BodySpring:
    """Spring-damper between a point of body ``a`` and a point of body ``b`` (either may be
    WORLD), points world at t = 0; the force law of the one-body spring (model.Spring)."""

    a: int
    b: int
    points: np.ndarray
    stiffness: float
    rest_length: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True, eq=False)
class BodyDrag:
    """Drag on ``body``: the force −linear·v at its centre of mass and the torque −angular·ω,
    v and ω its world velocities (N·s/m, N·m·s/rad; the one-body `model.Drag`)."""

    body: int
    linear: float = 0.0
    angular: float = 0.0


@dataclass(frozen=True, eq=False)
class SystemInitial:
    """positions / rates: joint name -> tuple of values (rad, m; rad/s, m/s); velocities: body
    name -> (velocity (3,), angular velocity (3,)) world, for floating bodies;
    project: project an inconsistent start onto the joints."""

    positions: dict = field(default_factory=dict)
    rates: dict = field(default_factory=dict)
    velocities: dict = field(default_factory=dict)
    project: bool = False


@dataclass(frozen=True, eq=False)
class SystemScene:
    """A validated system scene (see the contract's "simulate systems of bodies")."""

    bodies: tuple[SystemBody, ...]
    joints: tuple[SystemJoint, ...]
    gravity: np.ndarray
    forces: tuple[BodyForce, ...]
    springs: tuple[BodySpring, ...]
    initial: SystemInitial
    time: TimeSettings
    output: OutputSettings
    source: str = "<scene>"
    input_files: tuple[Path, ...] = ()
    warnings: tuple[str, ...] = ()
    places: dict = field(default_factory=dict)  # "initial.positions.A" -> "file:line: key: "
    robot: str | None = None  # the description a `model:` scene names (outputs add `holding`)
    couplings: tuple[JointCoupling, ...] = ()  # a description's mimic/equality relations
    drags: tuple[BodyDrag, ...] = ()
    length: float | None = None  # the size a scene fixes (one body's: the contract's metric)
    notes: tuple[str, ...] = ()  # what the scene's own checks said, placed (file:line: key: )

    @property
    def size(self) -> float:
        """m, the system's length scale: ``length`` where the scene fixes it, else the extent
        of the assembly and the largest body."""
        if self.length is not None:
            return self.length
        points = [b.com0 for b in self.bodies] + [j.point for j in self.joints
                                                   if j.point is not None]
        spread = float(np.ptp(np.array(points), axis=0).max()) if len(points) > 1 else 0.0
        return max(spread, max(b.size for b in self.bodies))

    def where(self, key: str) -> str:
        """``file:line: key: `` of a scene key, for messages found after reading."""
        return self.places.get(key, f"{self.source}: {key}: ")
