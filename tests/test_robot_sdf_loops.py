"""SDF closed chains: a link may be the child of several joints (Cassie's push rods close its
legs that way). The joint that closes the loop is marked as the loop joint wherever the loop is
written, even when parent -> child runs round the ring (a cycle of carriers)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from massprops.dynamics.systems.description import describe

INERTIA = ('<inertial><pose>{c} 0 0 0 0 0</pose><mass>{m}</mass><inertia><ixx>0.001</ixx>'
           '<iyy>0.002</iyy><izz>0.002</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>'
           '</inertial>')


def joint(name, parent, child, x, z):
    return (f'<joint name="{name}" type="revolute"><pose relative_to="__model__">{x} 0 {z} 0 0 0'
            f'</pose><parent>{parent}</parent><child>{child}</child><axis><xyz>0 1 0</xyz>'
            '</axis></joint>')


def four_bar(d_parent: str, d_child: str) -> str:
    """Ground (welded to the world), crank, coupler, rocker, hinges about y; the last hinge D
    between the rocker and the ground written in either direction."""
    links = "".join(
        f'<link name="{n}"><pose>{x} 0 {z} 0 0 0</pose>{INERTIA.format(c=c, m=m)}</link>'
        for n, x, z, c, m in (("ground", 0, 0, 0, 5), ("crank", 0, 0, 0.05, 1),
                              ("coupler", 0.1, 0.15, 0.15, 0.8), ("rocker", 0.5, 0, -0.05, 0.6)))
    return (f'<sdf version="1.7"><model name="fb">{links}'
            '<joint name="W" type="fixed"><parent>world</parent><child>ground</child></joint>'
            + joint("A", "ground", "crank", 0, 0) + joint("B", "crank", "coupler", 0.1, 0.15)
            + joint("C", "coupler", "rocker", 0.45, 0.2) + joint("D", d_parent, d_child, 0.5, 0)
            + '</model></sdf>')


def test_the_closing_joint_is_the_loop(tmp_path):
    (tmp_path / "ring.sdf").write_text(four_bar("rocker", "ground"))
    loops = {j.name: j.loop for j in describe(tmp_path / "ring.sdf").joints}
    assert loops == {"A": False, "B": False, "C": False, "D": True}


@pytest.mark.slow
def test_a_ring_of_carriers_moves_as_the_same_loop_written_the_other_way(tmp_path, run):
    """Written rocker -> ground (each link carried once, round the ring, the ground also welded
    to the world) or ground -> rocker: one mechanism, one motion (the crank falls under
    gravity); the loop stays closed."""
    out = {}
    for name, d in (("ring", ("rocker", "ground")), ("tree", ("ground", "rocker"))):
        (tmp_path / f"{name}.sdf").write_text(four_bar(*d))
        result = run("simulate", tmp_path / f"{name}.sdf", "--duration", "0.3", "--json")
        assert result.exit_code == 0, result.stderr
        out[name] = json.loads(result.stdout)
    assert out["ring"]["diagnostics"]["degrees_of_freedom"] == 1
    assert out["ring"]["diagnostics"]["constraint_residual"]["position"] < 1e-10
    for name in "ABC":
        ring = out["ring"]["final"]["joints"][name]["coordinates"][0]
        assert abs(ring) > 1e-3  # it moved
        assert ring == pytest.approx(out["tree"]["final"]["joints"][name]["coordinates"][0],
                                     abs=1e-8)


def test_a_joint_may_name_frames_for_its_links(tmp_path):
    """SDF 1.7+: <parent>/<child> may name a <frame>, standing for the link it is attached to
    (through other frames); the joint is then the same as one naming the links."""
    links = ('<link name="a"><pose>0 0 1 0 0 0</pose>' + INERTIA.format(c=0.1, m=1) + '</link>'
             '<link name="b"><pose>0.3 0 1 0 0 0</pose>' + INERTIA.format(c=0.2, m=2)
             + '</link><frame name="fa" attached_to="a"><pose>0.1 0 0 0 0 0</pose></frame>'
             '<frame name="fa2" attached_to="fa"/><frame name="fb" attached_to="b"/>')
    descs = {}
    for case, (parent, child) in {"links": ("a", "b"), "frames": ("fa2", "fb")}.items():
        (tmp_path / f"{case}.sdf").write_text(
            f'<sdf version="1.8"><model name="m">{links}'
            '<joint name="w" type="fixed"><parent>world</parent><child>a</child></joint>'
            f'<joint name="j" type="revolute"><parent>{parent}</parent><child>{child}</child>'
            '<axis><xyz>0 1 0</xyz></axis></joint></model></sdf>')
        descs[case] = describe(tmp_path / f"{case}.sdf")
    for case in descs:
        (j,) = descs[case].joints
        assert j.name == "j" and j.kind == "revolute"
    a, b = descs["links"].joints[0], descs["frames"].joints[0]
    assert (a.a, a.b) == (b.a, b.b)
    assert np.allclose(a.point, b.point) and np.allclose(a.axes, b.axes)
