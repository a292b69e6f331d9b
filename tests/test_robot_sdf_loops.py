"""SDF closed chains: a link may be the child of several joints (Cassie's push rods close its
legs that way). The joint that closes the loop is marked as the loop joint wherever the loop is
written, even when parent -> child runs round the ring (a cycle of carriers)."""

from __future__ import annotations

import json

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
