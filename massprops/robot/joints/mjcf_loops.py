"""MJCF ``<equality>`` elements as loop joints (see `joints.frames`; read by `joints.mjcf`).

``<connect body1 body2 anchor>`` (anchor in body1's frame), or ``site1 site2`` (sites that meet
as written), is a spherical loop joint; ``<weld body1 body2 [anchor]>`` holding the pose as
written is a fixed one; both are always cut joints of the tree. ``<joint joint1 joint2
polycoef>`` and ``<tendon tendon1 tendon2 polycoef>`` over fixed tendons are couplings
(`coupling`) where the polynomial is linear. Other equalities (flex, spatial tendons, a
nonlinear polycoef), a weld's ``relpose`` or ``torquescale``, and sites apart as written are
refused in one line naming the element. ``r`` is the reader (`mjcf._Reader`: its values,
defaults, body poses and sites).
"""

from __future__ import annotations

import numpy as np

from massprops.robot.formats.xmltree import Node
from massprops.robot.joints.frames import IDENTITY, WORLD_LINK, RobotCoupling, RobotJoint

__all__ = ["coupling", "fixed_tendons", "loop_joint"]

COUPLINGS = ("joint", "tendon")
"""The equality elements that are couplings, not loop joints."""


def fixed_tendons(r, root: Node) -> dict:
    """name -> ((joint, coef), ...) of every ``<tendon><fixed>`` (its length Σ coef q)."""
    out = {}
    for group in root.findall("tendon"):
        for node in group.children:
            if node.tag == "fixed" and node.attrs.get("name"):
                out[node.attrs["name"]] = tuple(
                    (j.attrs.get("joint", ""), r.v.number(j, "coef", 1.0))
                    for j in node.children if j.tag == "joint")
    return out


def coupling(r, node: Node, k: int, tendons: dict) -> RobotCoupling | None:
    """``<joint joint1 joint2 polycoef>`` or ``<tendon tendon1 tendon2 polycoef>`` (fixed
    tendons): MuJoCo's y − y0 = a0 + a1 (x − x0) with y0, x0 the values at qpos0, which is
    where our coordinates (qpos − ref) are zero: Σ y's terms − a1 Σ x's terms = a0. Without
    joint2/tendon2 the first is held at y0 + a0. A polycoef with a2..a4 not 0 is refused."""
    v = r.v
    a = r.defaults.attrs(node, "main")
    if a.get("active", "true") == "false":
        return None
    first, second = f"{node.tag}1", f"{node.tag}2"
    if first not in a:
        raise v.error(node, f"<{node.tag}> equality needs {first}=")
    poly = v.numbers(node, a.get("polycoef", "0 1 0 0 0"), "polycoef=", (1, 2, 3, 4, 5),
                     'polycoef="0 1 0 0 0"')
    if np.any(poly[2:]):
        raise v.error(node, f"<{node.tag}> equality: polycoef {' '.join(f'{x:g}' for x in poly)} "
                            "is not linear; massprops couples coordinates linearly only "
                            "(a2 = a3 = a4 = 0)")

    def side(name: str) -> tuple:
        if node.tag == "joint":
            return ((name, 1.0),)
        if name not in tendons:
            raise v.error(node, f"no fixed tendon named {name!r}: a spatial tendon's length "
                                "is no linear joint relation; check the spelling")
        return tendons[name]

    terms = side(a[first])
    if second in a:
        slope = float(poly[1]) if poly.size > 1 else 1.0
        terms += tuple((j, -slope * c) for j, c in side(a[second]))
    name = a.get("name") or f"{node.tag}{k}"
    return RobotCoupling(name, terms, float(poly[0]), node)


def loop_joint(r, node: Node, k: int) -> RobotJoint | None:
    v = r.v
    a = r.defaults.attrs(node, "main")
    if a.get("active", "true") == "false":
        return None
    if node.tag == "weld":
        return _weld(r, node, a, k)
    if node.tag != "connect":
        raise v.error(node, f"<{node.tag}> equality is not supported as a joint (only "
                            "<connect>, a spherical loop joint, and <weld>, a fixed one)")
    if "site1" in a:
        body1, body2, anchor = _sites(r, node, a)
    elif "body1" not in a:
        raise v.error(node, "<connect> needs body1= (and anchor=) or site1= and site2=")
    else:
        body1, body2 = a["body1"], a.get("body2", WORLD_LINK)
        anchor = v.numbers(node, a.get("anchor", "0 0 0"), "anchor=", 3, 'anchor="0 0 0"')
    for b in (body1, body2):
        if b != WORLD_LINK and b not in r.poses:
            raise v.error(node, f"no body named {b!r}; {_unknown_body(r)}")
    name = a.get("name") or f"connect{k}"
    return RobotJoint(name, "spherical", body2, body1, (np.eye(3), anchor), np.zeros((0, 3)),
                      node, loop=True)


_SITES_APART = 1e-9  # m: two sites "coincide" as written up to round-off of written numbers


def _unknown_body(r) -> str:
    """The hint for a body name not found: a <composite>'s bodies are not expanded here."""
    return (f"it may be one of the bodies made by <{r.generated[0]}> (expand the model first: "
            "mujoco.MjSpec, mj_saveLastXML)" if r.generated else "check the spelling")


def _sites(r, node: Node, a: dict):
    """A site-based connect (MuJoCo 3): (body1, body2, the anchor in body1's frame). The sites
    must coincide as written: massprops starts from the pose as written, closed."""
    v = r.v
    if "site2" not in a:
        raise v.error(node, "<connect site1=...> needs site2= as well")
    for s in (a["site1"], a["site2"]):
        if s not in r.sites:
            raise v.error(node, f"no site named {s!r}; check the spelling")
    (body1, p1), (body2, p2) = r.sites[a["site1"]], r.sites[a["site2"]]
    gap = float(np.linalg.norm(p1 - p2))
    if gap > _SITES_APART:
        raise v.error(node, f"sites {a['site1']!r} and {a['site2']!r} are {gap:.6g} m apart as "
                            "written: massprops starts from the written pose with every loop "
                            "closed; move a site or a body so that they meet")
    rot, t = r.poses[body1] if body1 != WORLD_LINK else IDENTITY
    return body1, body2, rot.T @ (p1 - t)


def _weld(r, node: Node, a: dict, k: int) -> RobotJoint:
    """``<weld body1 body2>`` holding the two bodies as written: a fixed loop joint (its point,
    where the reaction is reported, at ``anchor`` in body2's frame). A ``relpose`` other than
    the written one, a ``torquescale`` other than 1 and the site form are refused: each changes
    what is held."""
    v = r.v
    if "body1" not in a:
        raise v.error(node, "massprops reads <weld body1= body2=>; give the bodies (not sites)")
    if float(a.get("torquescale", "1")) != 1.0:
        raise v.error(node, f"<weld torquescale={a['torquescale']!r}>: a partly held turn is "
                            "not a joint; remove it (1 holds the turn fully)")
    body1, body2 = a["body1"], a.get("body2", WORLD_LINK)
    for b in (body1, body2):
        if b != WORLD_LINK and b not in r.poses:
            raise v.error(node, f"no body named {b!r}; {_unknown_body(r)}")
    if "relpose" in a:
        written = v.numbers(node, a["relpose"], "relpose=", 7, 'relpose="0 1 0 0 0 0 0"')
        if np.any(written[3:]):  # MuJoCo's all-zero quaternion: "the pose as written"
            raise v.error(node, "<weld relpose=...> holds a pose other than the written one; "
                                "massprops starts closed: remove relpose or move the bodies")
    anchor = v.numbers(node, a.get("anchor", "0 0 0"), "anchor=", 3, 'anchor="0 0 0"')
    two = r.poses[body2] if body2 != WORLD_LINK else IDENTITY
    one = r.poses[body1]
    point = two[0] @ anchor + two[1]
    at = (np.eye(3), one[0].T @ (point - one[1]))  # the point in body1's (the child's) frame
    return RobotJoint(a.get("name") or f"weld{k}", "fixed", body2, body1, at,
                      np.zeros((0, 3)), node, loop=True)
