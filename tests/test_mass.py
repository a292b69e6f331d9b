"""Mass properties against independent truth: an exact rational oracle on the stored float
vertices, closed forms, Tonon's published tetrahedron, invariances, and the error bars."""

from __future__ import annotations

import json
import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
from conftest import exact_mass_properties
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from massprops.errors import DegenerateMeshError, MeshFormatError, UsageError
from massprops.mesh import Mesh, facesums
from massprops.mesh import integral as mass_module
from massprops.mesh.integral import mass_properties


def _eigenvalues_below(j, x) -> int | None:
    """How many eigenvalues of the symmetric j lie below x: the negative pivots of an LDLᵀ of
    j - x I (Sylvester's law of inertia); None on a zero pivot."""
    a = [[j[p][q] - (x if p == q else 0) for q in range(3)] for p in range(3)]
    negative = 0
    for p in range(3):
        if a[p][p] == 0:
            return None
        negative += a[p][p] < 0
        for r in range(p + 1, 3):
            f = a[r][p] / a[p][p]
            for c in range(p + 1, 3):
                a[r][c] -= f * a[p][c]
    return negative


def exact_eigenvalues(j) -> list[Fraction]:
    """The three eigenvalues of a rational symmetric 3x3, ascending, to 2**-80 of its size, by
    bisection on the inertia count (works for repeated eigenvalues too)."""
    size = sum(abs(j[p][q]) for p in range(3) for q in range(3))
    tol = size / 2**80
    out = []
    for k in range(3):
        lo, hi = -size, size
        while hi - lo > tol:
            mid = (lo + hi) / 2
            count = _eigenvalues_below(j, mid)
            while count is None:
                mid += tol / 7
                count = _eigenvalues_below(j, mid)
            lo, hi = (lo, mid) if count > k else (mid, hi)
        out.append((lo + hi) / 2)
    return out


# --- meshes ---------------------------------------------------------------------------------------
BOX_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


def box(a: float, b: float, c: float) -> tuple[np.ndarray, np.ndarray]:
    """a x b x c box centred at the origin; vertex i has x = ±a/2 by bit 2, y by bit 1, z bit 0."""
    v = np.array([[x, y, z] for x in (-a / 2, a / 2) for y in (-b / 2, b / 2)
                  for z in (-c / 2, c / 2)])
    return v, BOX_FACES.copy()


def hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convex hull of the points, faces wound outward."""
    h = ConvexHull(points)
    faces = h.simplices.copy()
    for f, eq in zip(faces, h.equations):
        a, b, c = points[f]
        if np.cross(b - a, c - a) @ eq[:3] < 0:
            f[1], f[2] = f[2], f[1]
    return np.ascontiguousarray(points), faces


def star(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A non-convex star-shaped polyhedron: a sphere triangulation with random radii."""
    rng = np.random.default_rng(seed)
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    _, faces = hull(d)
    return d * rng.uniform(0.3, 1.0, (n, 1)), faces


def prism(n: int, radius: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Regular n-gon prism, circumradius ``radius``, z from 0 to ``height``."""
    t = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([radius * np.cos(t), radius * np.sin(t), np.zeros(n)])
    v = np.vstack([ring, ring + [0, 0, height], [[0, 0, 0], [0, 0, height]]])
    f = []
    for i in range(n):
        j = (i + 1) % n
        f += [[i, j, n + j], [i, n + j, n + i], [2 * n, j, i], [2 * n + 1, n + i, n + j]]
    return v, np.array(f)


def rotation(seed: int) -> np.ndarray:
    q = np.random.default_rng(seed).standard_normal(4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def mesh(v, f, name="test", **kw) -> Mesh:
    return Mesh(np.ascontiguousarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64),
                name=name, **kw)


def with_duplicates(v, f):
    """Every vertex stored twice; faces use either copy."""
    pick = np.random.default_rng(0).integers(0, 2, f.shape)
    return np.vstack([v, v]), f + pick * len(v)


def with_zero_area_faces(v, f):
    """Box-like mesh: split the edge (v0, v4) of face (0, 4, 5) at its midpoint m (exactly on the
    segment, only x differs) and close the T-junction with the zero-area face (0, 4, m), which
    carries the edges 0→4, 4→m, m→0 the split left unmatched; add the self-cancelling face
    (1, 1, 2) too. Rotated, m leaves the segment by an ulp: still a closed surface."""
    m = len(v)
    mid = (v[0] + v[4]) / 2
    rows = [list(t) for t in f.tolist() if list(t) != [0, 4, 5]]
    rows += [[0, m, 5], [m, 4, 5], [0, 4, m], [1, 1, 2]]
    return np.vstack([v, mid]), np.array(rows)


NEEDLE_POINTS = np.random.default_rng(7).random((40, 3)) * [1, 1e-6, 1e-6]
PLATE_POINTS = np.random.default_rng(8).random((40, 3)) * [1, 1, 1e-6]
SHAPES = {
    "box": box(3.0, 2.0, 1.5),
    "hull": hull(np.random.default_rng(3).random((40, 3))),
    "star": star(40, seed=4),
    "needle-box": box(1.0, 1e-6, 1e-6),
    "plate-box": box(1.0, 1.0, 1e-6),
    "needle-hull": hull(NEEDLE_POINTS),
    "plate-hull": hull(PLATE_POINTS),
    "dup-vertices": with_duplicates(*hull(np.random.default_rng(5).random((30, 3)))),
    "zero-area": with_zero_area_faces(*box(2.0, 1.0, 1.0)),
}
PLACEMENTS = {  # (scale, offset in sizes, rotation seed or None)
    "unit": (1.0, 0.0, None),
    "tilted": (1.0, 0.0, 11),
    "tilted-1e3-away": (1.0, 1e3, 12),
    "1e9-away": (1.0, 1e9, None),
    "tilted-1e9-away": (1.0, 1e9, 13),
    "micro-tilted-1e6-away": (1e-6, 1e6, 14),
    "mega-tilted-1e3-away": (1e6, 1e3, 15),
}
CASES = [(s, p) for s in SHAPES for p in PLACEMENTS]


def placed(shape: str, placement: str) -> tuple[np.ndarray, np.ndarray]:
    v, f = SHAPES[shape]
    scale, away, seed = PLACEMENTS[placement]
    if seed is not None:
        v = v @ rotation(seed).T
    direction = np.array([0.6, -0.48, 0.64])
    return v * scale + away * scale * direction, f


def ulp(x: float) -> float:
    return float(np.spacing(abs(float(x))))


# --- accuracy against the exact oracle, and the rounding bound ------------------------------------
@pytest.mark.parametrize("shape, placement", CASES, ids=[f"{s}-{p}" for s, p in CASES])
def test_matches_exact_oracle_within_its_rounding_bound(shape, placement):
    """Relative errors <= 1e-13 (COM: of the radius of gyration, on top of the half-ulp of storing
    it; inertia and principal moments: of the largest moment); each error <= its rounding bound,
    and the bound <= 1e3 x the error + 1000 ulps of the quantity's scale (~1e-13 relative). A
    rigorous bound counts every rounding in the chain: measured here 8-60 ulps for the volume,
    30-330 for the inertia, 50-580 for the principal moments, against true errors of 0-5 ulps."""
    v, f = placed(shape, placement)
    got = mass_properties(mesh(v, f, shape))
    volume, com, inertia = exact_mass_properties(v, f)
    moments = exact_eigenvalues(inertia)
    big = float(moments[2])
    gyration = math.sqrt(float(sum(inertia[i][i] for i in range(3))) / (2 * float(volume)))
    bound = got.uncertainty.rounding

    err_v = float(abs(Fraction(got.volume) - volume))
    assert err_v <= 1e-13 * float(volume)
    assert err_v <= bound.volume <= 1e3 * err_v + 1000 * ulp(volume)
    for i in range(3):
        err_c = float(abs(Fraction(float(got.center_of_mass[i])) - com[i]))
        assert err_c <= 1e-13 * gyration + ulp(com[i]) / 2
        assert err_c <= bound.center_of_mass[i]
        assert bound.center_of_mass[i] <= 1e3 * err_c + 1000 * ulp(gyration) + ulp(com[i]) / 2
        err_l = float(abs(Fraction(float(got.principal_moments[i])) - moments[i]))
        assert err_l <= 1e-13 * big
        assert err_l <= bound.principal_moments[i] <= 1e3 * err_l + 1000 * ulp(big)
        for j in range(3):
            err_j = float(abs(Fraction(float(got.inertia[i, j])) - inertia[i][j]))
            assert err_j <= 1e-13 * big
            assert err_j <= bound.inertia[i, j] <= 1e3 * err_j + 1000 * ulp(big)
    assert got.uncertainty.input is None


@pytest.mark.parametrize("layout", ["welded", "soup", "shuffled-soup"])
def test_several_blocks_and_every_vertex_layout(layout):
    """More faces than one block (pairwise sums per block, math.fsum across them), welded
    (shared vertices: the transposed-columns gather), as an STL soup (3 vertices per face in
    order: a transposed copy) or a soup whose faces list them out of order (the row gather),
    tilted and 1e3 sizes away, against the exact oracle."""
    v, f = star(2200, seed=6)
    assert len(f) > facesums.BLOCK
    v = v @ rotation(16).T + [1e3, -2e3, 5e2]
    if layout != "welded":
        v, f = v[f].reshape(-1, 3), np.arange(3 * len(f)).reshape(-1, 3)
    if layout == "shuffled-soup":
        order = np.random.default_rng(3).permutation(len(v))
        v, f = v[order], np.argsort(order)[f]
    got = mass_properties(mesh(v, f))
    volume, com, inertia = exact_mass_properties(v, f)
    bound = got.uncertainty.rounding
    assert abs(Fraction(got.volume) - volume) <= min(bound.volume, 1e-13 * volume)
    big = float(max(inertia[i][i] for i in range(3)))
    for i in range(3):
        err_c = float(abs(Fraction(float(got.center_of_mass[i])) - com[i]))
        assert err_c <= bound.center_of_mass[i]
        for j in range(3):
            err = float(abs(Fraction(float(got.inertia[i, j])) - inertia[i][j]))
            assert err <= min(bound.inertia[i, j], 1e-13 * big)


def test_far_mesh_beats_the_world_origin_integral():
    """1e6 sizes away, the COM-frame inertia is exact to ~1e-16 while the textbook sum about the
    world origin (what trimesh does) loses (distance/size)² x 1e-16 ≈ 100 %."""
    v, f = placed("hull", "unit")
    v = v + 1e6
    volume, com, inertia = exact_mass_properties(v, f)
    got = mass_properties(mesh(v, f))
    big = float(max(inertia[i][i] for i in range(3)))
    assert float(abs(Fraction(float(got.inertia[0, 0])) - inertia[0][0])) < 1e-14 * big
    a, b, c = (v[f[:, k]] for k in range(3))
    d = np.einsum("ij,ij->i", a, np.cross(b, c))
    s = a + b + c
    m2x = d @ (a[:, 1] ** 2 + b[:, 1] ** 2 + c[:, 1] ** 2 + s[:, 1] ** 2) / 120
    m2y = d @ (a[:, 2] ** 2 + b[:, 2] ** 2 + c[:, 2] ** 2 + s[:, 2] ** 2) / 120
    naive = (m2x + m2y) - d.sum() / 6 * (float(com[1]) ** 2 + float(com[2]) ** 2)
    assert abs(naive - float(inertia[0][0])) > 1e-3 * big


def test_thin_tilted_solids_take_the_double_double_path():
    """For a tilted plate of aspect 1e-6 the float64 determinants' own bound exceeds the target
    even about the centre of mass, so the pass is redone in double-double, which meets the exact
    volume to 1e-15."""
    v, f = placed("plate-hull", "tilted-1e3-away")
    m = mesh(v, f)
    volume, com, _ = exact_mass_properties(v, f)
    origin = np.array([float(c) for c in com])
    fast = facesums.face_sums(m, origin, accurate=False, area=False)
    reach = facesums.reach_of(fast)
    assert facesums.det_error(fast, reach) > mass_module._FAST_DET_TARGET * abs(fast.det)
    accurate = facesums.face_sums(m, origin, accurate=True, area=False)
    assert abs(Fraction(accurate.det / 6) - volume) <= 1e-15 * volume
    assert facesums.det_error(accurate, reach) < 1e-15 * abs(accurate.det)


def test_thin_tilted_plate_is_recentred_on_its_centre_of_mass():
    """The box centre of a tilted random plate lies off its mid-plane by far more than its
    thickness: about it the tetrahedra cancel (Σ|d| >> |Σd|), so the sums are redone about the
    estimated COM, where nothing cancels."""
    v, f = placed("plate-hull", "tilted")
    lo, hi = v.min(axis=0), v.max(axis=0)
    first = facesums.face_sums(mesh(v, f), (lo + hi) / 2, accurate=False, area=False)
    assert first.abs_det > mass_module._RECENTRE_RATIO * abs(first.det)
    got = mass_properties(mesh(v, f))
    volume, _, _ = exact_mass_properties(v, f)
    assert got.uncertainty.rounding.volume < 1e-14 * got.volume
    assert abs(Fraction(got.volume) - volume) <= 1e-15 * volume


def test_block_sum_depth_constant():
    n = facesums.BLOCK
    assert facesums.BLOCK_SUM_DEPTH == max(facesums.pairwise_depth(k) for k in range(n + 1))


def test_numpy_sums_are_pairwise_as_the_bound_assumes():
    """The rounding bound counts numpy's pairwise summation depth; a sequential sum of
    [1, u, u, ...] would lose every u and break it."""
    n = facesums.BLOCK
    row = np.full((2, n), 2.0**-53)
    row[:, 0] = 1.0
    exact = 1.0 + (n - 1) * 2.0**-53
    depth = facesums.sum_depth(n)
    assert abs(row.sum(axis=1)[0] - exact) <= facesums.gamma(depth) * exact


# --- closed forms and published values ----------------------------------------------------------
@pytest.mark.parametrize("a, b, c", [(3.0, 2.0, 2.0), (1.0, 1e-6, 1e-6), (5e-6, 7e-6, 1e-5),
                                     (4e5, 1e6, 3e5)], ids=["3x2x2", "needle", "micro", "mega"])
def test_box_closed_form(a, b, c):
    v, f = box(a, b, c)
    got = mass_properties(mesh(v + [7 * a, -3 * b, 2 * c], f), density=2.5)
    m = 2.5 * a * b * c
    assert got.mass == pytest.approx(m, rel=1e-14)
    expected = np.diag([m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b)]) / 12
    assert np.allclose(got.inertia, expected, rtol=0, atol=1e-14 * expected.max())
    assert np.allclose(got.center_of_mass, [7 * a, -3 * b, 2 * c], rtol=1e-15)


def test_seed_cuboid():
    """The seed's example: 3x2x2 cuboid turned 30° about z, mass 12, J as on slide 13,
    principal moments 8, 13, 13 and axes [[.866, -.5, 0], [.5, .866, 0], [0, 0, 1]]."""
    cs, sn = math.cos(math.pi / 6), math.sin(math.pi / 6)
    rz = np.array([[cs, -sn, 0], [sn, cs, 0], [0, 0, 1]])
    v, f = box(3.0, 2.0, 2.0)
    got = mass_properties(mesh(v @ rz.T, f, "cuboid"))
    assert got.mass == pytest.approx(12.0, rel=1e-15)
    expected = [[9.25, -2.1650635094610966, 0], [-2.1650635094610966, 11.75, 0], [0, 0, 13]]
    assert np.allclose(got.inertia, expected, rtol=0, atol=1e-13)
    assert np.allclose(got.principal_moments, [8, 13, 13], rtol=0, atol=1e-13)
    assert np.allclose(got.principal_axes, [[cs, -sn, 0], [sn, cs, 0], [0, 0, 1]], atol=1e-12)
    assert np.allclose(got.center_of_mass, 0, atol=1e-15)


def test_tonon_tetrahedron():
    """F. Tonon, J. Math. Stat. 1(1):8-11 (2005), numerical example: vertices, centroid and
    inertia about it at unit density (a, b, c the diagonal; a' = ∫yz, b' = ∫xz, c' = ∫xy), as
    reproduced in trimesh's tests/test_inertia.py, which notes that Eq. 2's E_Q needs b' and c'
    swapped: J = [[a, -c', -b'], [-c', b, -a'], [-b', -a', c]]. The paper prints 5 decimals and
    deviates from the exact values by ~2e-8 relative; det = 11239.4001852988 (6 x volume)."""
    v = np.array([[8.33220, -11.86875, 0.93355], [0.75523, 5.0, 16.37072],
                  [52.61236, 5.0, -5.38580], [2.0, 5.0, 3.0]])
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    got = mass_properties(mesh(v, f, "tonon"))
    a, b, c = 43520.33257, 194711.28938, 191168.76173
    ap, bp, cp = 4417.66150, -46343.16662, 11996.20119
    expected = np.array([[a, -cp, -bp], [-cp, b, -ap], [-bp, -ap, c]])
    assert got.volume == pytest.approx(11239.4001852988 / 6, rel=1e-13)
    assert np.allclose(got.center_of_mass, v.mean(axis=0), rtol=1e-15)   # a tetrahedron's
    assert np.allclose(got.center_of_mass, [15.92492, 0.78281, 3.72962], rtol=0, atol=3e-5)
    # (the paper prints x = 15.92492; the vertex mean is 15.9249475, as trimesh also notes)
    assert np.abs(got.inertia - expected).max() < 5e-8 * b


@pytest.mark.parametrize("n", [3, 6, 17], ids=["triangle", "hexagon", "17-gon"])
def test_regular_prism_closed_form(n):
    """Circumradius R, height h: V = n R² sin(2π/n) h / 2; J_zz = m R² (2 + cos(2π/n)) / 6 (sum of
    the fan triangles' polar moments); J_xx = J_yy = J_zz / 2 + m h² / 12 (n-fold symmetry)."""
    radius, height = 0.7, 2.3
    v, f = prism(n, radius, height)
    got = mass_properties(mesh(v, f))
    volume = n * radius**2 * math.sin(2 * math.pi / n) * height / 2
    jzz = volume * radius**2 * (2 + math.cos(2 * math.pi / n)) / 6
    assert got.volume == pytest.approx(volume, rel=1e-14)
    assert np.allclose(got.inertia, np.diag([jzz / 2 + volume * height**2 / 12] * 2 + [jzz]),
                       rtol=0, atol=1e-14 * jzz)
    assert np.allclose(got.center_of_mass, [0, 0, height / 2], rtol=0, atol=1e-15)


# --- invariances ----------------------------------------------------------------------------------
HULL_V, HULL_F = SHAPES["hull"]
HULL_V = np.round(HULL_V * 2.0**20) / 2.0**20   # 20 fractional bits: translations by multiples
HULL = mass_properties(mesh(HULL_V, HULL_F))    # of 2**-20 up to 1e6 are exact


@settings(max_examples=50, deadline=None)
@given(steps=st.lists(st.integers(-(2**40), 2**40), min_size=3, max_size=3))
def test_translation_moves_only_the_centre_of_mass(steps):
    """An exact translation (so the stored mesh really is the same solid) by up to 1e6."""
    offset = np.array(steps) * 2.0**-20
    got = mass_properties(mesh(HULL_V + offset, HULL_F))
    assert got.volume == pytest.approx(HULL.volume, rel=1e-13)
    assert np.allclose(got.center_of_mass, HULL.center_of_mass + offset, rtol=0,
                       atol=1e-13 + 2 * np.spacing(np.abs(offset).max() + 1))
    assert np.abs(got.inertia - HULL.inertia).max() < 1e-13 * HULL.principal_moments[2]


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_rotation_rotates_the_tensor_and_keeps_the_moments(seed):
    q = rotation(seed)
    got = mass_properties(mesh(HULL_V @ q.T, HULL_F))
    big = HULL.principal_moments[2]
    assert np.abs(got.inertia - q @ HULL.inertia @ q.T).max() < 1e-13 * big
    assert np.abs(got.principal_moments - HULL.principal_moments).max() < 1e-13 * big
    assert np.allclose(got.center_of_mass, q @ HULL.center_of_mass, rtol=0, atol=1e-14)
    for k in range(3):   # distinct moments: each axis is the rotated axis up to sign
        assert abs(abs(got.principal_axes[:, k] @ q @ HULL.principal_axes[:, k]) - 1) < 1e-10


@settings(max_examples=50, deadline=None)
@given(scale=st.floats(1e-6, 1e6))
def test_scaling_multiplies_mass_by_s3_and_inertia_by_s5(scale):
    got = mass_properties(mesh(HULL_V * scale, HULL_F))
    assert got.mass == pytest.approx(HULL.mass * scale**3, rel=1e-13)
    assert np.abs(got.inertia - HULL.inertia * scale**5).max() < 1e-13 * HULL.principal_moments[
        2] * scale**5


@pytest.mark.parametrize("shape", ["box", "star", "needle-hull"])
def test_reversed_windings_are_inside_out(shape):
    v, f = SHAPES[shape]
    with pytest.raises(DegenerateMeshError, match="test: is inside out"):
        mass_properties(mesh(v, f[:, ::-1]))


# --- density, mass and the JSON form ------------------------------------------------------------
def test_mass_sets_the_density():
    v, f = box(3.0, 2.0, 2.0)
    got = mass_properties(mesh(v, f), mass=24.0)
    assert got.density == pytest.approx(2.0, rel=1e-15) and got.mass == 24.0
    assert np.allclose(got.inertia, 2 * mass_properties(mesh(v, f)).inertia, rtol=1e-15)
    assert got.uncertainty.rounding.mass == 0.0


@pytest.mark.parametrize("kw, match", [({"density": 1.0, "mass": 1.0}, "not both"),
                                       ({"density": -1.0}, "density must be"),
                                       ({"mass": float("nan")}, "mass must be")],
                         ids=["both", "negative", "nan"])
def test_bad_density_or_mass(kw, match):
    v, f = box(1.0, 1.0, 1.0)
    with pytest.raises(UsageError, match=match):
        mass_properties(mesh(v, f), **kw)


def test_as_dict_is_plain_json():
    v, f = box(3.0, 2.0, 2.0)
    out = mass_properties(mesh(v, f, coordinate_dtype=np.dtype(np.float32)), density=7850).as_dict()
    assert set(out) >= {"volume", "mass", "density", "center_of_mass", "inertia",
                        "principal_moments", "principal_axes", "uncertainty"}
    assert json.loads(json.dumps(out)) == out
    assert type(out["inertia"][0][1]) is float and len(out["principal_axes"]) == 3
    assert set(out["uncertainty"]) == {"rounding", "input"}
    assert out["uncertainty"]["input"]["volume"] > 0


# --- refusals -------------------------------------------------------------------------------------
def test_flat_mesh_encloses_no_volume():
    v, f = box(1.0, 1.0, 1.0)
    v[:, 2] = 0.25                                     # squash: every face in one plane
    with pytest.raises(DegenerateMeshError, match=r"flat: encloses no volume \(flat\?\)"):
        mass_properties(mesh(v, f, "flat"))


@pytest.mark.parametrize("v, f, error, match", [
    (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), DegenerateMeshError, "no triangles"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0.0]]), np.array([[0, 1, 2], [0, 2, 1]]),
     MeshFormatError, "finite"),
    (np.eye(3), np.array([[0, 1, 3]]), MeshFormatError, "face indices"),
    (box(1e110, 1e110, 1e110)[0], BOX_FACES, MeshFormatError, "too large for float64"),
], ids=["empty", "nan", "bad-index", "overflow"])
def test_refusals(v, f, error, match):
    with pytest.raises(error, match=match):
        mass_properties(mesh(v, f, "bad"))


# --- coordinates beyond float64 (issue 30): refused up front, exit 1, no numpy warning ----------
@pytest.mark.parametrize("size", [1e300, 1e200, 1e62])
def test_coordinates_too_large_are_refused_before_any_product(size):
    from massprops.inspection.file import inspect_mesh

    v, f = box(2 * size, 2 * size, 2 * size)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning (overflow) would fail the test here
        with pytest.raises(MeshFormatError) as caught:
            inspect_mesh(mesh(v, f, "big.obj"))
    assert str(caught.value) == (
        f"big.obj: coordinates too large for float64 mass properties: vertex 1 has |x| = "
        f"{size:.3g} m, but the inertia integrates coordinates to the fifth power, finite only "
        f"for |x| below 6e+60 m (12 triangles); rescale the mesh or give the unit its "
        f"coordinates are in (unit)")


def test_coordinate_limit_is_a_real_bound():
    """(float64 max / (2000 m))^(1/5): every result finite just below it, for boxes reaching the
    limit on both sides of the origin and on one (the integral's origin inside the box)."""
    limit = mass_module.coordinate_limit(12)
    assert limit == pytest.approx((np.finfo(np.float64).max / 24000) ** 0.2)
    assert 5e60 < limit < 1e61
    assert mass_module.coordinate_limit(10**9) == pytest.approx(limit * (12 / 1e9) ** 0.2)
    v, f = box(2.0, 2.0, 2.0)
    for shifted in (v, v + 1.0):  # [-1, 1]³ and [0, 2]³, scaled to reach 0.999 limit
        vertices = shifted * (0.999 * limit / np.abs(shifted).max())
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            props = mass_properties(mesh(vertices, f))
        values = [props.volume, props.mass, *props.center_of_mass, *props.inertia.ravel(),
                  *props.uncertainty.rounding.inertia.ravel()]
        assert all(math.isfinite(x) for x in values)
        assert props.principal_moments.max() > 1e300
    with pytest.raises(MeshFormatError, match="too large for float64"):
        mass_properties(mesh(v * 1.001 * limit, f))


def test_density_beyond_float64_is_refused_without_warnings():
    v, f = box(2e60, 2e60, 2e60)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(MeshFormatError) as caught:
            mass_properties(mesh(v, f, "big.obj"), density=1e300)
    assert str(caught.value).startswith("big.obj: mass properties beyond float64's range")
    assert "8e+180 m³ at 1e+300 kg/m³" in str(caught.value)
    assert "give a smaller density or mass" in str(caught.value)


# --- float32 coordinates: the input error bar -----------------------------------------------------
@pytest.mark.parametrize("shape, scale", [("hull", 1e-3), ("star", 1.0), ("plate-box", 25.4e-3)],
                         ids=["hull-mm", "star-m", "plate-in"])
def test_input_bound_covers_half_ulp_float32_perturbations(shape, scale):
    """Coordinates stored as float32 in the file unit, then scaled: moving every one by ±half a
    float32 ulp (random signs, and all outward) changes each quantity by <= the input bound."""
    v, f = SHAPES[shape]
    file32 = (v * 30 + 100).astype(np.float32)          # file values, away from 0
    base = mesh(file32.astype(np.float64) * scale, f, coordinate_dtype=np.dtype(np.float32),
                coordinate_scale=scale)
    ref = mass_properties(base)
    bound = ref.uncertainty.input
    half = np.spacing(np.abs(file32)).astype(np.float64) / 2
    rng = np.random.default_rng(9)
    centre = file32.astype(np.float64).mean(axis=0)
    signs = [rng.choice([-1.0, 1.0], size=v.shape) for _ in range(6)]
    signs.append(np.sign(file32 - centre))              # every vertex pushed outward
    for sign in signs:
        moved = mass_properties(mesh((file32 + sign * half) * scale, f))
        assert abs(moved.volume - ref.volume) <= bound.volume
        assert abs(moved.mass - ref.mass) <= bound.mass
        assert (np.abs(moved.center_of_mass - ref.center_of_mass) <= bound.center_of_mass).all()
        assert (np.abs(moved.inertia - ref.inertia) <= bound.inertia).all()
        assert (np.abs(moved.principal_moments - ref.principal_moments)
                <= bound.principal_moments).all()
    outward = mass_properties(mesh((file32 + signs[-1] * half) * scale, f))
    assert abs(outward.volume - ref.volume) > 0.05 * bound.volume  # the bound is not vacuous
