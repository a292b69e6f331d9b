"""The sorting kernels behind mesh health, at sizes where they split work over two threads:
`sort_in_two`, exact welding and edge counting, each against an independent computation
(np.sort, a dict of exact coordinate rows, a Counter of directed edges)."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.mesh import topology as surface
from massprops.mesh import weld
from massprops.mesh.topology import connected_components, edges
from massprops.parallel import sort_in_two


# --- sort_in_two ---------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(rows=st.integers(0, 700), width=st.sampled_from([1, 3]), align=st.sampled_from([1, 7, 64]),
       cut=st.integers(0, 2**64 - 1), seed=st.integers(0, 2**32 - 1))
def test_sort_in_two_sorts_each_kind(rows, width, align, cut, seed):
    keys = np.random.default_rng(seed).integers(0, 2**64 - 1, width * rows, np.uint64,
                                                endpoint=True)
    split_at = np.uint64(cut)

    def blocks(lo, hi):
        assert 0 < hi - lo <= align
        k = keys[width * lo : width * hi]
        return k[k < split_at], k[k >= split_at]

    out, k = sort_in_two(lambda: blocks, rows, width, align)
    np.testing.assert_array_equal(out[:k], np.sort(keys[keys < split_at]))
    np.testing.assert_array_equal(out[k:], np.sort(keys[keys >= split_at]))


# --- welding at scale ----------------------------------------------------------------------------
def grouping_by_dict(rows: np.ndarray) -> tuple[list[int], list[int]]:
    """inv and reps as `weld` defines them, from a dict of python float tuples (-0.0 == 0.0)."""
    first_use: dict = {}
    for i, r in enumerate(map(tuple, rows.tolist())):
        first_use.setdefault(r, i)
    reps = sorted(set(first_use.values()))
    rank = {f: k for k, f in enumerate(reps)}
    return [rank[first_use[r]] for r in map(tuple, rows.tolist())], reps


def lattice_soup(n: int, seed: int) -> np.ndarray:
    """n rows drawn from a small lattice (many repeats), with signed zeros mixed in."""
    rng = np.random.default_rng(seed)
    rows = rng.integers(-3, 4, size=(n, 3)).astype(np.float64) * 0.25
    rows[rng.random((n, 3)) < 0.3] *= -1.0  # -0.0 where the value is 0
    return rows


@pytest.mark.parametrize("prefix_bits", [1, 8, 64], ids=["all-collide", "many-collide", "full"])
def test_weld_of_a_large_soup_matches_a_dict(prefix_bits):
    rows = lattice_soup(3 * weld._CHUNK + 11, seed=prefix_bits)
    inv, reps = weld.weld(rows, prefix_bits=prefix_bits)
    expected_inv, expected_reps = grouping_by_dict(rows)
    assert reps.tolist() == expected_reps
    assert inv.tolist() == expected_inv


def test_weld_is_the_same_on_every_run():
    rows = lattice_soup(2 * weld._CHUNK + 5, seed=3)
    first = weld.weld(rows)
    for _ in range(3):
        again = weld.weld(rows)
        assert np.array_equal(again[0], first[0]) and np.array_equal(again[1], first[1])


# --- edges ----------------------------------------------------------------------------------------
def edges_by_counter(tri: np.ndarray) -> dict:
    """{(u, v): (forward, backward)} for u < v, counted one directed edge at a time."""
    directed = Counter((int(a), int(b)) for t in tri.tolist() for a, b in zip(t, t[1:] + t[:1]))
    pairs = {(min(a, b), max(a, b)) for a, b in directed}
    return {(u, v): (directed[(u, v)], directed[(v, u)]) for u, v in sorted(pairs)}


def assert_edges(tri: np.ndarray, n_ids: int) -> None:
    e = edges(tri, n_ids)
    expected = edges_by_counter(tri)
    assert list(zip(e.u.tolist(), e.v.tolist())) == list(expected)
    forward = [f for f, _ in expected.values()]
    backward = [b for _, b in expected.values()]
    if e.forward is None:  # the closed 2-manifold case: once each way
        assert set(forward) | set(backward) == {1}
    else:
        assert e.forward.tolist() == forward and e.backward.tolist() == backward


def distinct_triangles(n_ids: int, m: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    tri = np.stack([rng.choice(n_ids, 3, replace=False) for _ in range(m)])
    return tri.astype(np.int32)


def grid_torus(nu: int, nv: int) -> np.ndarray:
    """(2 nu nv, 3) ids of a closed, consistently wound torus grid."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, (i + 1) % nu * nv + j
    c, d = (i + 1) % nu * nv + (j + 1) % nv, i * nv + (j + 1) % nv
    return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([a, c, d], -1).reshape(-1, 3)]).astype(np.int32)


@settings(max_examples=40, deadline=None)
@given(n_ids=st.integers(3, 12), m=st.integers(1, 40), seed=st.integers(0, 2**32 - 1))
def test_edges_match_a_counter(n_ids, m, seed):
    assert_edges(distinct_triangles(n_ids, m, seed), n_ids)


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["none", "hole", "flipped", "doubled"])
def test_edges_of_a_large_torus_match_a_counter(damage):
    """Larger than two blocks, so the keys are made and sorted on two threads."""
    tri = grid_torus(340, 100)
    assert tri.shape[0] > 2 * surface._CHUNK
    if damage == "hole":
        tri = tri[1:]
    elif damage == "flipped":
        tri[5] = tri[5, ::-1]
    elif damage == "doubled":
        tri = np.concatenate([tri, tri[:3]])
    assert_edges(tri, 340 * 100)


def test_connected_components_of_many_grids_side_by_side():
    """Three tori plus an isolated id: labels are each part's smallest id."""
    parts = [grid_torus(40, 30) + offset for offset in (0, 1200, 2400)]
    e = edges(np.concatenate(parts), 3601)
    labels = connected_components(3601, e.u, e.v)
    expected = np.concatenate([np.full(1200, k * 1200) for k in range(3)] + [[3600]])
    np.testing.assert_array_equal(labels, expected)
