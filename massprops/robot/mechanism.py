"""`read_mechanism`: the joints and link poses of a parsed description, by its format.

The values and the frames are in `joints.frames`; one reader per format in `joints.urdf`,
`joints.sdf`, `joints.mjcf`. The parsed `RobotModel` keeps the XML tree the joints are read
from (every link's node; MJCF includes already spliced in).
"""

from __future__ import annotations

from pathlib import Path

from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node, parse_xml
from massprops.robot.joints.frames import Mechanism
from massprops.robot.joints.urdf import urdf_mechanism
from massprops.robot.model import RobotModel

__all__ = ["read_mechanism"]


def read_mechanism(model: RobotModel) -> Mechanism:
    """The joints and link poses of a parsed description (`analyze.load_model`); raises
    RobotModelError (one line) for a joint the systems engine cannot express."""
    if not model.links:
        root_name = {"urdf": "robot", "sdf": "sdf", "mjcf": "mujoco"}.get(model.format, "robot")
        raise Values(model.path).error(Node(root_name, {}, 1, 0, 0), "no links: nothing moves")
    root = _main_root(model)
    names = [link.name for link in model.links]
    if model.format == "urdf":
        return urdf_mechanism(root, model.path, names)
    if model.format == "sdf":
        from massprops.robot.joints.sdf import sdf_mechanism  # a description loads its own reader

        return sdf_mechanism(root, model.path, names)
    from massprops.robot.joints.mjcf import mjcf_mechanism  # a description loads its own reader

    return mjcf_mechanism(root, model.path, names)


def _main_root(model: RobotModel) -> Node:
    """The root element of the description's own file. A link's node leads up to it, except
    the bodies an MJCF ``<attach>`` reads from another file (their nodes lead to that file's
    root: reading it would simulate the attached model alone); with no link of its own the
    file is read again."""
    for link in model.links:
        root = link.node
        while root.parent is not None:
            root = root.parent
        # only MJCF attaches files; a URDF from xacro has the expanded text's name
        if model.format != "mjcf" or root.file is None or Path(root.file) == Path(model.path):
            return root
    return parse_xml(model.path)[0]
