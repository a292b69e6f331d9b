"""Frames of robot descriptions: each format's way of writing an orientation, as a matrix.

Every function returns the rotation A (3, 3) float64 taking coordinates in the child frame
(geometry, inertial) to the parent frame (link, body): v_parent = A v_child + t. Angles are in
radians here; the parsers convert MJCF degrees before calling.

- URDF ``rpy`` and SDF poses: roll about the fixed x axis, then pitch about fixed y, then yaw
  about fixed z: A = Rz(yaw) Ry(pitch) Rx(roll).
- MJCF ``euler`` with ``eulerseq``: one character per rotation, lower case about the axes that
  rotate with the frame (post-multiplied), upper case about the fixed axes (pre-multiplied).
- MJCF ``quat``: [w, x, y, z] (scalar first, like massprops), normalised here.
- MJCF ``axisangle`` (x, y, z, angle), ``xyaxes`` (the frame's x axis, then y made orthogonal to
  it, z = x × y) and ``zaxis`` (the shortest rotation taking +z to the given direction).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.rotation import quat_from_axis_angle, quat_to_matrix

__all__ = ["axis_rotation", "euler_matrix", "rpy_matrix", "xyaxes_matrix", "zaxis_matrix",
           "axisangle_matrix", "quat_matrix"]


def axis_rotation(axis: str, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad, right hand) about the coordinate axis "x", "y" or "z"."""
    c, s = math.cos(angle), math.sin(angle)
    i = "xyz".index(axis.lower())
    j, k = (i + 1) % 3, (i + 2) % 3
    out = np.eye(3)
    out[j, j], out[j, k], out[k, j], out[k, k] = c, -s, s, c
    return out


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF/SDF fixed-axis roll, pitch, yaw (rad): Rz(yaw) Ry(pitch) Rx(roll)."""
    return axis_rotation("z", yaw) @ axis_rotation("y", pitch) @ axis_rotation("x", roll)


def euler_matrix(angles, sequence: str) -> np.ndarray:
    """MJCF euler angles (rad) in the order of ``sequence`` (3 characters of xyzXYZ): lower case
    rotates about the moving axes (A = A·R), upper case about the fixed axes (A = R·A)."""
    a = np.eye(3)
    for ch, angle in zip(sequence, angles):
        r = axis_rotation(ch, float(angle))
        a = a @ r if ch.islower() else r @ a
    return a


def quat_matrix(quat) -> np.ndarray:
    """A from a quaternion [w, x, y, z] of any non-zero norm (normalised)."""
    return quat_to_matrix(np.asarray(quat, dtype=np.float64))


def axisangle_matrix(axis, angle: float) -> np.ndarray:
    """A from a non-zero axis and an angle (rad)."""
    return quat_to_matrix(quat_from_axis_angle(np.asarray(axis, dtype=np.float64), angle))


def xyaxes_matrix(x_axis, y_axis) -> np.ndarray:
    """A whose columns are the frame's x (normalised), y (made orthogonal to x, normalised) and
    z = x × y axes, given in the parent frame."""
    x = np.asarray(x_axis, dtype=np.float64)
    x = x / np.linalg.norm(x)
    y = np.asarray(y_axis, dtype=np.float64)
    y = y - (x @ y) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def zaxis_matrix(direction) -> np.ndarray:
    """The shortest rotation taking +z to ``direction`` (non-zero); a direction opposite to +z
    is reached by a half turn about x (MuJoCo's rule)."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    axis = np.cross([0.0, 0.0, 1.0], d)
    sin = float(np.linalg.norm(axis))
    if sin == 0.0:  # exactly along ±z: no axis to turn about
        return np.eye(3) if d[2] > 0 else axis_rotation("x", math.pi)
    return axisangle_matrix(axis, math.atan2(sin, float(d[2])))
