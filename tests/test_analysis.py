"""`inspect_mesh` on meshes large enough that the integral runs beside the health checks: the
results are those of the unit cube, repairs still apply, and errors keep their order."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from massprops import parallel
from massprops.errors import MeshTopologyError, UsageError
from massprops.inspection import file as analysis
from massprops.inspection.file import OVERLAP_TRIANGLES, inspect_mesh
from massprops.mesh import Mesh


def fine_cube_soup(k: int, *, inward: bool = False) -> Mesh:
    """The unit cube [0, 1]³ as an STL-like soup: each face a k x k grid, 12 k² triangles,
    counter-clockwise from outside (clockwise if ``inward``)."""
    g = np.arange(k + 1) / k
    tris = []
    for axis in range(3):
        for side in (0.0, 1.0):
            s, t = np.meshgrid(g, g, indexing="ij")
            p = np.empty(s.shape + (3,))
            p[..., axis], p[..., (axis + 1) % 3], p[..., (axis + 2) % 3] = side, s, t
            a, b, c, d = p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]
            quads = np.stack([np.stack([a, b, c], -2), np.stack([a, c, d], -2)]).reshape(-1, 3, 3)
            normal = np.cross(quads[:, 1] - quads[:, 0], quads[:, 2] - quads[:, 0])[:, axis]
            outward = (normal > 0) == (side == 1.0)
            quads[~outward] = quads[~outward][:, ::-1]
            tris.append(quads)
    soup = np.concatenate(tris)
    if inward:
        soup = soup[:, ::-1]
    m = soup.shape[0]
    return Mesh(np.ascontiguousarray(soup.reshape(-1, 3)), np.arange(3 * m).reshape(m, 3),
                name="cube.stl")


K = 53  # 12 · 53² = 33 708 triangles: above OVERLAP_TRIANGLES
UNIT_CUBE_INERTIA = np.eye(3) / 6  # m (a² + a²) / 12 with m = a = 1


def test_the_fine_cube_is_above_the_overlap_threshold():
    assert fine_cube_soup(K).faces.shape[0] >= OVERLAP_TRIANGLES


@pytest.mark.parametrize("inward", [False, True], ids=["outward", "inside-out"])
def test_a_large_soup_gives_the_unit_cube(inward):
    mesh = fine_cube_soup(K, inward=inward)
    result = inspect_mesh(mesh, density=2.0)
    p = result.properties
    assert p.volume == pytest.approx(1.0, rel=1e-13) and p.mass == pytest.approx(2.0, rel=1e-13)
    np.testing.assert_allclose(p.center_of_mass, [0.5, 0.5, 0.5], rtol=1e-13)
    np.testing.assert_allclose(p.inertia, 2.0 * UNIT_CUBE_INERTIA, atol=1e-13)
    assert result.health.flipped is inward
    assert result.health.unique_vertices == 6 * (K - 1) ** 2 + 12 * (K - 1) + 8
    assert (result.mesh is mesh) is not inward  # a flipped copy was integrated


def test_an_open_large_soup_is_refused_and_leaves_no_thread():
    cube = fine_cube_soup(K)
    holed = Mesh(cube.vertices, cube.faces[1:], name="holed.stl")
    before = threading.active_count()
    with pytest.raises(MeshTopologyError, match="holed.stl: mesh is not closed: 3 boundary edges"):
        inspect_mesh(holed, density=-1.0)  # the health error comes before the usage error
    assert threading.active_count() == before


def test_a_usage_error_is_raised_after_the_health_checks():
    with pytest.raises(UsageError, match="give a density or a mass, not both"):
        inspect_mesh(fine_cube_soup(K), density=1.0, mass=2.0)


def test_one_thread_and_two_give_the_same_bits(monkeypatch):
    """Every pass split over two threads is arranged so that the split cannot change a bit. 75:
    67 500 triangles, so that the edge pass (blocks of 32 768 triangles) splits too."""
    mesh = fine_cube_soup(75)
    rng = np.random.default_rng(5)
    shuffled = mesh.vertices.reshape(-1, 3, 3)[rng.permutation(mesh.faces.shape[0])]
    mesh = Mesh(shuffled.reshape(-1, 3) * 1.1 + 1e3, mesh.faces, name="moved.stl")
    two = inspect_mesh(mesh).as_dict()

    def at_once(fn, *args):
        out = fn(*args)
        return lambda: out

    monkeypatch.setattr(parallel, "in_background", at_once)
    monkeypatch.setattr(analysis, "in_background", at_once)
    assert inspect_mesh(mesh).as_dict() == two
