"""The free-fall frame of a floating system: a system held by nothing (no joint, spring or cut
to the world) runs in the frame that starts with its centre of mass's velocity V0 and falls
with gravity g, P(t) = V0 t + ½ g t² (m, world axes, from the assembly's middle, `localized`).

Why. The engine's spatial vectors are about a point fixed in the world (`tree`): a body's
spatial inertia carries m |c|² and its velocity v − ω × c, so a system that travels d from that
point keeps its inertias to (d / size)² × eps and its velocities to (d / size) × eps, as an
assembly far from the origin did before `assemble.localized`. A two-link system thrown at
1000 m/s for 10 s could not be run at all (its error control saw that noise: two million steps
by 9.7 s); at 10 m/s its joint angle was 5e-11 rad off the same system at rest. In the falling
frame the fictitious force −m g on every body cancels its weight exactly, so the frame's system
has no gravity, starts with every body's velocity less V0, and stays where it started as far as
only gravity and its own joints, springs and dampers move its centre (body forces and torques
still move it, by what they add).

Joint coordinates, rates and reactions are the same in both frames (uniform translation
satisfies every joint between bodies, and the reactions are forces between bodies); positions,
points, velocities and energies are carried back to the world frame for the outputs
(`to_world`): x + P(t), v + V0 + g t, and the energy E + Σ m V·v + ½ M |V|² − g·Σ m (x + P)
with V = V0 + g t, which is the world frame's energy exactly (gravity's potential about the
assembly's middle, as for any system).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.assemble import Tree
from massprops.dynamics.systems.model import WORLD, SystemScene

__all__ = ["Falling", "falling_frame"]


@dataclass(frozen=True, eq=False)
class Falling:
    """velocity V0 (3,) m/s and gravity g (3,) m/s², world axes; masses (b,) kg of the bodies;
    free: the first rate index of each free joint (the system's roots), whose first three rates
    are their body's centre-of-mass velocity."""

    velocity: np.ndarray
    gravity: np.ndarray
    masses: np.ndarray
    free: tuple[int, ...]

    def start(self, y0: np.ndarray, nq: int) -> np.ndarray:
        """The start state ``y0`` (nq + nv,) in the falling frame: every root's velocity less
        V0 (the joints' rates are relative: every body's velocity loses V0)."""
        y = np.array(y0, dtype=float)
        for iu in self.free:
            y[nq + iu:nq + iu + 3] -= self.velocity
        return y

    def motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(P, V) (n, 3): the frame's position and velocity at the times ``t`` (n,) s."""
        t = np.asarray(t, dtype=float)[:, None]
        return self.velocity * t + 0.5 * self.gravity * t * t, self.velocity + self.gravity * t

    def to_world(self, samples, origin: np.ndarray):
        """``samples`` (`outputs.Samples`, positions about the world origin: ``origin`` added)
        of the falling frame, in the world frame (see the module doc)."""
        p, v = self.motion(samples.t)
        energy = samples.energy
        if energy is not None:
            m = self.masses[None, :, None]
            momentum = np.sum(m * samples.velocity, axis=1)
            moment = np.sum(m * (samples.position - origin), axis=1)
            total = float(self.masses.sum())
            energy = (energy + np.einsum("ij,ij->i", v, momentum)
                      + 0.5 * total * np.einsum("ij,ij->i", v, v)
                      - (moment + total * p) @ self.gravity)
        points = None if samples.joint_points is None else samples.joint_points + p[:, None]
        return dataclasses.replace(samples, position=samples.position + p[:, None],
                                   velocity=samples.velocity + v[:, None], energy=energy,
                                   joint_points=points)


def falling_frame(scene: SystemScene, tree: Tree, y0: np.ndarray) -> Falling | None:
    """The falling frame of ``scene`` started at ``y0`` (its tree's state), or None where the
    world holds the system (a joint, spring or cut to the world, or drag) or the frame would
    not move (no gravity, the centre at rest)."""
    if any(WORLD in (j.a, j.b) for j in scene.joints) \
            or any(WORLD in (s.a, s.b) for s in scene.springs):
        return None
    if any(d.linear or d.angular for d in scene.drags):  # drag holds it back against the air,
        return None  # at rest in the world: a frame falling freely would leave it behind
    nq = tree.nq
    kin = tr.kinematics(tree, y0[:nq], y0[nq:])
    masses = np.array([b.mass for b in tree.bodies], dtype=float)
    velocity = kin.V[:, 3:] + np.cross(kin.V[:, :3], kin.com)  # each centre's velocity
    v0 = masses @ velocity / masses.sum()
    gravity = np.array(scene.gravity, dtype=float)
    if not (v0.any() or gravity.any()):
        return None
    free = tuple(j.iu for j in tree.joints if j.kind == "free")
    return Falling(v0, gravity, masses, free)
