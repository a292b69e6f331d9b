"""`--plot` of a system: the mechanism as a stick figure at several instants with the path of each
joint (seen along the normal of its plane when the motion is planar, in 3-D otherwise), and the
magnitude of every joint's reaction force and torque over time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.dynamics.plots import _pyplot, save_figure

INSTANTS = 6
"""Stick figures drawn, evenly spaced over the run (the last one darkest)."""

PLANAR_RTOL = 1e-9
"""The motion is planar when every point stays within this fraction of the system's size of
one plane (the smallest spread of the points' best-fit plane)."""


def _sticks(result) -> list[list[tuple[int, int]]]:
    """Per body: pairs of indices into [joint points..., COM of the body (-1 - body)] to join."""
    scene = result.scene
    out = []
    for i in range(len(scene.bodies)):
        touching = [k for k, j in enumerate(scene.joints) if i in (j.a, j.b)]
        nodes = touching if len(touching) > 1 else touching + [-1 - i]
        out.append([(nodes[a], nodes[b]) for a in range(len(nodes))
                    for b in range(a + 1, len(nodes))])
    return out


def _point(samples, node: int, s: int) -> np.ndarray:
    return samples.position[s, -1 - node] if node < 0 else samples.joint_points[s, node]


def _screen(normal: np.ndarray) -> np.ndarray:
    """(2, 3) in-plane screen axes: up is world z (world y for a horizontal plane), right is
    world x (world y when the plane holds no x), so a mechanism in x-z reads as drawn."""
    def in_plane(v: np.ndarray) -> np.ndarray:
        w = v - (v @ normal) * normal
        return w / np.linalg.norm(w)

    z, y, x = np.eye(3)[2], np.eye(3)[1], np.eye(3)[0]
    up = in_plane(z if abs(normal @ z) < 0.9 else y)
    right = x if abs(normal @ x) < 0.9 else (y if abs(normal @ y) < 0.9 else z)
    right = right - (right @ up) * up
    right = in_plane(right)
    return np.stack([right, up])


def plot_system(result, path: str | Path, *, force: bool = False, protect=()) -> None:
    """The mechanism panel and the reactions panel, written as a PNG (see module doc)."""
    plt = _pyplot()
    s = result.samples
    cloud = np.concatenate([s.position.reshape(-1, 3), s.joint_points.reshape(-1, 3)])
    centre = cloud.mean(axis=0)
    _, spread, axes = np.linalg.svd(cloud - centre, full_matrices=False)
    planar = spread[-1] / np.sqrt(len(cloud)) <= PLANAR_RTOL * result.scene.size
    fig = plt.figure(figsize=(13, 5.5), constrained_layout=True)
    grid = fig.add_gridspec(2, 2, width_ratios=(1.1, 1.0))
    mech = fig.add_subplot(grid[:, 0], **({} if planar else {"projection": "3d"}))

    basis = _screen(axes[2]) if planar else np.eye(3)

    def view(p: np.ndarray) -> np.ndarray:
        return basis @ p if planar else p

    n = len(s.t)
    sticks = _sticks(result)
    for m, idx in enumerate(np.linspace(0, n - 1, min(INSTANTS, n)).astype(int)):
        shade = 0.25 + 0.75 * m / max(INSTANTS - 1, 1)
        for pairs in sticks:
            for a, b in pairs:
                seg = np.array([view(_point(s, a, idx)), view(_point(s, b, idx))])
                mech.plot(*seg.T, color=(0, 0, 0, shade), lw=1.5)
    for k, joint in enumerate(result.scene.joints):
        path_k = np.array([view(p) for p in s.joint_points[:, k]])
        # the end marked: a joint that stays put (an axle, a fixed pivot) is a dot, not nothing
        mech.plot(*path_k.T, lw=0.8, label=joint.name, marker="o", ms=3,
                  markevery=[len(path_k) - 1])
    mech.set_title("mechanism (seen along its plane's normal)" if planar else "mechanism (3-D)")
    if planar:
        mech.set_aspect("equal", adjustable="datalim")
    mech.legend(fontsize=7, loc="best")
    react = fig.add_subplot(grid[0, 1])
    twist = fig.add_subplot(grid[1, 1], sharex=react)
    for k, joint in enumerate(result.scene.joints):
        react.plot(s.t, np.linalg.norm(s.force[:, k], axis=1), label=joint.name)
        twist.plot(s.t, np.linalg.norm(s.torque[:, k], axis=1), label=joint.name)
    react.set_ylabel("|reaction force| [N]")
    twist.set_ylabel("|reaction torque| [N·m]")
    twist.set_xlabel("t [s]")
    react.legend(fontsize=7, loc="best")
    save_figure(fig, path, force=force, protect=protect)
    plt.close(fig)
