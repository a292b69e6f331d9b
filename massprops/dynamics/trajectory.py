"""Trajectory files: CSV (header with units) or NPZ, written atomically, never over an input."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from massprops.errors import UsageError

TRAJECTORY_EXTENSIONS: tuple[str, ...] = (".csv", ".npz")
"""The formats of a trajectory file (scene ``output.file``, ``simulate --output``)."""


def trajectory_output():
    """The output rule's `OutputKind` for a trajectory file (`massprops.io.atomic`)."""
    from massprops.io.atomic import OutputKind  # deferred: only when a file is written

    return OutputKind("a trajectory", TRAJECTORY_EXTENSIONS, "output")


COLUMNS = [
    ("t", "s", "t"),
    ("position", "m", ("x", "y", "z")),
    ("orientation", "", ("qw", "qx", "qy", "qz")),
    ("velocity", "m/s", ("vx", "vy", "vz")),
    ("angular_velocity", "rad/s", ("wx", "wy", "wz")),
    ("angular_velocity_body", "rad/s", ("wx_body", "wy_body", "wz_body")),
    ("angular_momentum", "kg*m^2/s", ("hx", "hy", "hz")),
    ("energy", "J", "energy"),
]
"""(Trajectory field, unit, column name(s)); world frame unless the name says body."""

JOINT_COLUMNS = [
    ("force_world", "N", ("fx", "fy", "fz")),
    ("force_body", "N", ("fx_body", "fy_body", "fz_body")),
    ("torque_world", "N*m", ("tx", "ty", "tz")),
    ("torque_body", "N*m", ("tx_body", "ty_body", "tz_body")),
]
"""Reaction columns of each joint k (JointLoads field, unit, names prefixed ``j{k}_``): the force
and, for a hinge, the torque the joint applies to the body; none for a free body."""


def _joint_arrays(traj):
    """(name, unit, labels, (n, 3) array) of every joint's reaction columns, scene order."""
    for k, joint in enumerate(getattr(traj, "joints", ())):
        for field, unit, labels in JOINT_COLUMNS:
            value = getattr(joint, field)
            if value is not None:
                yield f"joint{k}_{field}", unit, tuple(f"j{k}_{lab}" for lab in labels), value


def _table(traj) -> tuple[list[str], np.ndarray]:
    names, cols = [], []
    for field, unit, labels in COLUMNS:
        value = getattr(traj, field)
        if value is None:
            continue
        value = np.asarray(value, dtype=np.float64).reshape(len(traj.t), -1)
        labels = (labels,) if isinstance(labels, str) else labels
        names += [f"{lab} [{unit}]" if unit else lab for lab in labels]
        cols.append(value)
    for _, unit, labels, value in _joint_arrays(traj):
        names += [f"{lab} [{unit}]" for lab in labels]
        cols.append(value)
    return names, np.hstack(cols)


def trajectory_bytes(traj, suffix: str) -> bytes:
    """The file's content: CSV with full round-trip precision, or NPZ with one array per field."""
    names, table = _table(traj)
    buf = io.BytesIO()
    if suffix == ".csv":
        np.savetxt(buf, table, delimiter=",", fmt="%.17g", header=",".join(names), comments="")
    elif suffix == ".npz":
        arrays = {f: np.asarray(getattr(traj, f)) for f, _, _ in COLUMNS
                  if getattr(traj, f) is not None}
        arrays.update({name: value for name, _, _, value in _joint_arrays(traj)})
        np.savez(buf, columns=np.array(names), **arrays)  # type: ignore[arg-type]  # numpy's stub types **kwds as its own flags
    else:
        raise UsageError(f"trajectory file must end in .csv or .npz, got {suffix!r}")
    return buf.getvalue()


def write_trajectory(traj, path: str | Path, *, force: bool = False, protect=()) -> None:
    """Write ``traj`` to ``path`` (.csv or .npz) atomically, under the output rule
    (`massprops.io.atomic.check_output`): UsageError for another extension, OutputExistsError
    over an input or an existing file unless ``force``."""
    # deferred: file writing is needed only when a trajectory is saved
    from massprops.io.atomic import atomic_write_bytes, check_output

    path = check_output(path, trajectory_output(), force=force, protect=protect)
    atomic_write_bytes(path, trajectory_bytes(traj, path.suffix.lower()), force=force,
                       protect=protect)
