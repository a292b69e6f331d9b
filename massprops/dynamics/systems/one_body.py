"""A one-body scene (``body:``, optionally held by ``joints:``) as a system of one body.

The contract: "A one-body scene is the same as a system of one body". This module is the
translation only; it runs nothing.

Frames and conventions:
- the one-body scene's *body frame* has the mesh's axes and its origin at the mesh origin (an
  explicit body: at the centre of mass, or at ``body.center_of_mass``); its ``point``s (forces,
  springs, joints) are body coordinates, c = ``RigidBody.center_of_mass`` the COM in it;
- the system body's frame has the same axes and its origin at the COM, so its inertia is the
  one-body inertia about the COM in the body axes, and a body point p sits at
  x = com0 + R0 (p - c) in the world at t = 0;
- system joints, forces and springs take world points at t = 0 (R0 = A(initial.orientation),
  com0 = initial.position); quaternions are scalar-first [w, x, y, z], body -> world;
- the one body is named ``"body"``, the joints ``j0``, ``j1``, ... in scene order (the systems
  scene's defaults).

A held scene's initial state is already on its joints (`joints.scene.bind_scene` projects it,
or refuses it without ``project_initial``), so the system is built at that pose and is not
projected again (``project=False``).
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.joints.model import Joint, SphericalJoint
from massprops.dynamics.model import Gravity, PointForce, Scene, Spring, Torque
from massprops.dynamics.systems.model import (
    WORLD,
    BodyDrag,
    BodyForce,
    BodySpring,
    SystemBody,
    SystemInitial,
    SystemJoint,
    SystemScene,
)
from massprops.rotation import quat_to_matrix

__all__ = ["BODY", "as_system"]

BODY = "body"
"""The name of the one body in the system."""


def as_system(scene: Scene) -> SystemScene:
    """The system of one body that moves as ``scene`` does (a validated, bound `Scene`, as
    `dynamics.scene.load_scene` returns it).

    ``time`` is carried over as it is: a one-body-only method it names (exact, splitting*) is
    refused by `run.simulate_system` unless the caller names a system method. The scene's
    ``notes`` (a projection onto the joints) and ``body_source`` have no place in a SystemScene:
    the caller keeps them from ``scene``."""
    body, ini = scene.body, scene.initial
    rot0 = quat_to_matrix(np.asarray(ini.orientation, np.float64))
    com0 = np.array(ini.position, np.float64)
    com_body = np.asarray(body.center_of_mass, np.float64)

    def world(point) -> np.ndarray | None:
        """A body point (body coordinates; None: the COM) in the world at t = 0."""
        return None if point is None else com0 + rot0 @ (np.asarray(point, np.float64) - com_body)

    inertia = body.inertia_body
    inertia = 0.5 * (inertia + inertia.T)  # R diag(I) Rᵀ is symmetric only to round-off
    system_body = SystemBody(BODY, float(body.mass), inertia, rot0, com0, float(body.size))

    gravity = np.zeros(3)
    forces: list[BodyForce] = []
    springs: list[BodySpring] = []
    drags: list[BodyDrag] = []
    for term in scene.forces:
        if isinstance(term, Gravity):
            gravity = gravity + np.asarray(term.g, np.float64)
        elif isinstance(term, PointForce):
            forces.append(BodyForce("force", 0, np.array(term.vector, np.float64), term.frame,
                                    world(term.point), term.start, term.end))
        elif isinstance(term, Torque):
            forces.append(BodyForce("torque", 0, np.array(term.vector, np.float64), term.frame,
                                    None, term.start, term.end))
        elif isinstance(term, Spring):
            # the systems spring acts on its second body with d = x_b - x_a: the one-body
            # spring's d = point - anchor when the world is first
            point = world(term.point) if term.point is not None else com0
            springs.append(BodySpring(WORLD, 0, np.array([term.anchor, point], np.float64),
                                      float(term.stiffness), float(term.rest_length),
                                      float(term.damping)))
        else:  # Drag: the last of the scene's force kinds (each one's translation is tested)
            drags.append(BodyDrag(0, float(term.linear), float(term.angular)))

    joints = tuple(_joint(f"j{k}", j) for k, j in enumerate(scene.joints))
    omega = np.asarray(ini.angular_velocity, np.float64)
    omega_world = rot0 @ omega if ini.angular_velocity_frame == "body" else omega.copy()
    initial = SystemInitial(rates=_rates(joints, omega_world), project=False,
                            velocities={} if joints else {
                                BODY: (np.array(ini.velocity, np.float64), omega_world)})
    return SystemScene((system_body,), joints, gravity, tuple(forces), tuple(springs), initial,
                       scene.time, scene.output, source=scene.source,
                       input_files=tuple(scene.input_files), warnings=tuple(scene.warnings),
                       drags=tuple(drags), length=float(body.size))


def _joint(name: str, joint: Joint) -> SystemJoint:
    """A one-body joint (world -> body; spherical or revolute) as a system joint at the world
    anchor."""
    anchor = np.array(joint.anchor, np.float64)
    if isinstance(joint, SphericalJoint):
        return SystemJoint(name, "spherical", WORLD, 0, anchor, np.zeros((0, 3)))
    # revolute: bind_scene has set world_axis (given, or where the start turns ``axis``)
    axis = np.asarray(joint.world_axis, np.float64)
    return SystemJoint(name, "revolute", WORLD, 0, anchor,
                       (axis / np.linalg.norm(axis))[None, :], damping=float(joint.damping),
                       drive=float(joint.torque), start=joint.start, end=joint.end)


def _rates(joints: tuple[SystemJoint, ...], omega_world: np.ndarray) -> dict:
    """The first joint's initial rates (the tree joint; a second spherical joint closes the
    hinge as a cut joint and takes none): a spherical joint's rates are the body's angular
    velocity relative to the world in the joint frame (the world's axes), a revolute joint's
    the turn rate about its world axis (`systems.tree`)."""
    if not joints:
        return {}
    first = joints[0]
    if first.kind == "spherical":
        return {first.name: tuple(float(w) for w in omega_world)}
    return {first.name: (float(omega_world @ first.axes[0]),)}
