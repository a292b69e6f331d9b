"""Mass properties varied as a body's can vary: every draw a valid inertial.

- ``mass``: the body keeps its distribution, so the inertia about the centre of mass scales
  with the mass (J' = J m'/m); a mesh body's shape and centre of mass stay.
- ``inertia`` (``relative:P`` only: a tensor): the body's second moments about its centre of
  mass, Σ = ∫ x xᵀ dm = ½ tr(J) I − J, are stretched as by a small random deformation of its
  density, Σ' = L Σ L with L = exp(D), D a symmetric Gaussian matrix (its law the same in every
  frame: diagonal sd P/2, off-diagonal P/(2√2)), so each second moment varies by about P and the
  principal moments by 0.7P to P. Σ' is positive definite for every draw, so J' = tr(Σ') I − Σ'
  is positive definite and within the triangle inequalities by construction, and the centre of
  mass does not move.
- A body with a shape (a mesh body) is judged as the doctor judges a link
  (`robot.doctor.validity.judge`): a draw that no non-negative density inside the shape's
  bounding ellipsoid can have is drawn again (at most MAX_REDRAWS times), and counted.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np

from massprops.errors import ComputationError
from massprops.robot.doctor.bounds import bounds_of
from massprops.robot.doctor.validity import judge

MAX_REDRAWS = 100
"""Draws of one sample's mass properties before the sample fails (its row says why)."""

MASS_KEYS = ("mass", "inertia")
"""The last step of a body's mass-property keys (``body.mass``, ``bodies.upper.inertia``)."""


def stretched(rng: np.random.Generator, inertia: np.ndarray, p: float) -> np.ndarray:
    """J' = tr(Σ') I − Σ', Σ' = L Σ L, L = exp(D) (the module's rule); kg·m², same frame."""
    a = rng.standard_normal((3, 3)) * (p / 2.0)
    d = 0.5 * (a + a.T)
    w, v = np.linalg.eigh(d)
    stretch = (v * np.exp(w)) @ v.T
    sigma = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    sigma = stretch @ sigma @ stretch
    sigma = 0.5 * (sigma + sigma.T)
    return np.trace(sigma) * np.eye(3) - sigma


@functools.lru_cache(maxsize=8)
def shape_bounds(path: str, unit: str):
    """The doctor's bounds (hull and ellipsoid) of the mesh at ``path`` in metres, body frame."""
    from massprops.io import read_mesh  # deferred: only a mesh body's shape reads its file

    mesh = read_mesh(Path(path), unit=unit)
    return bounds_of(np.asarray(mesh.vertices[np.unique(mesh.faces)], dtype=np.float64))


@dataclasses.dataclass(frozen=True)
class MassChange:
    """One ``--vary`` of a body's mass or inertia: ``body`` the body's name (None: the one body
    of a ``body:`` scene), ``what`` "mass" or "inertia"."""

    key: str
    body: str | None
    what: str


def draw_valid(rng, changes: list[tuple[MassChange, object]], mass: float, inertia: np.ndarray,
               com: np.ndarray, bounds) -> tuple[float, np.ndarray, dict[str, object], int]:
    """(mass, inertia, the drawn values by key, redraws) of one body under ``changes`` ((change,
    spec) in command order), each draw judged valid (`judge`) against ``bounds`` (None: the
    tensor tests only). ComputationError after MAX_REDRAWS failed draws."""
    for attempt in range(MAX_REDRAWS + 1):
        m, j, said = mass, inertia, {}
        for change, spec in changes:
            if change.what == "mass":
                new = spec.draw(rng, m)  # type: ignore[attr-defined]
                if not new > 0:
                    break
                j, m = j * (new / m), new
                said[change.key] = new
            else:
                j = stretched(rng, j, spec.relative_sd)  # type: ignore[attr-defined]
                said[change.key] = j.tolist()
        else:
            if judge(m, com, j, bounds).ok:
                return m, j, said, attempt
    raise ComputationError(f"no valid inertial in {MAX_REDRAWS + 1} draws (every one broke a "
                           "validity test: the spread is too wide for the body's shape)")
