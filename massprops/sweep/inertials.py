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
- ``center_of_mass[i]``: the centre of mass moves in the body frame, the inertia about it
  unchanged (the mass distribution shifts; where that leaves the body is `sample`'s to say).
- ``--bars`` (`Bars`): a mesh body's mass properties within the error bars inspect reports,
  widened K times (``--bars-scale``). Inspect's bars are bounds (rounding, input and repair,
  added), so a bar becomes a rectangular draw, uniform within ± K bars (GUM's law for a bound
  and nothing more): the mass (the inertia scaled with it, the distribution kept) and each
  component of the centre of mass. The inertia is then `stretched`, P = K b / (√3 λ_max) (b the
  principal moments' bar, which bounds each moment's move; √3: the sd of a rectangular draw
  over ± b): the tensor's own, frame-free law, Gaussian, its spread the rectangular one's.
  Since the inertia's bar already holds the mass's share of the error, the tensor varies by up
  to √2 more than its bar: on the safe side.
- A body with a shape (a mesh body) is judged as the doctor judges a link
  (`robot.doctor.validity.judge`): a draw that no non-negative density inside the shape's
  bounding ellipsoid can have (its centre of mass outside the shape's hull, too) is drawn again
  (at most MAX_REDRAWS times), and counted.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path
from typing import Any

import numpy as np

from massprops.dynamics.model import MeshSource
from massprops.errors import ComputationError
from massprops.robot.doctor.bounds import bounds_of
from massprops.robot.doctor.validity import judge

MAX_REDRAWS = 100
"""Draws of one sample's mass properties before the sample fails (its row says why)."""

MASS_KEYS = ("mass", "inertia", "center_of_mass")
"""A body's mass-property keys' step after the body (``body.mass``, ``bodies.upper.inertia``,
``body.center_of_mass[2]``)."""


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
    """One variation of a body's mass properties: ``body`` the body's name (None: the one body
    of a ``body:`` scene), ``what`` "mass", "inertia", "center_of_mass" (its component
    ``axis``) or "bars" (``--bars``; ``key`` then the body's prefix, ``body`` or
    ``bodies.NAME``, that its drawn values' keys start with)."""

    key: str
    body: str | None
    what: str
    axis: int = 0


def prefix(body: str | None) -> str:
    """The keys' start for ``body``'s mass properties: ``body`` or ``bodies.NAME``."""
    return "body" if body is None else f"bodies.{body}"


def total_bar(source: MeshSource, name: str) -> np.ndarray:
    """Inspect's bar of quantity ``name`` ("mass", "center_of_mass", "principal_moments"):
    rounding + input + repair, each a bound, so their sum bounds the whole; its units."""
    parts = (source.bars.rounding, source.bars.input, source.bars.repair)
    return sum((np.asarray(getattr(u, name), dtype=np.float64) for u in parts if u is not None),
               start=np.zeros(()))


@dataclasses.dataclass(frozen=True, eq=False)
class Bars:
    """One mesh body's ``--bars`` draw (the module's rule), its bars already widened:
    ``mass`` kg and ``center_of_mass`` (3,) m, half-widths of the rectangular draws (mesh
    frame); ``stretch`` the P of the inertia's `stretched` draw."""

    mass: float
    center_of_mass: np.ndarray
    stretch: float

    @classmethod
    def of(cls, source: MeshSource, inertia: np.ndarray, scale: float) -> Bars:
        """``source``'s bars widened ``scale`` times, for the body's ``inertia`` (kg·m²)."""
        largest = float(np.linalg.eigvalsh(inertia)[-1])
        moment_bar = float(np.max(total_bar(source, "principal_moments")))
        return cls(scale * float(total_bar(source, "mass")),
                   scale * total_bar(source, "center_of_mass") * np.ones(3),
                   scale * moment_bar / (math.sqrt(3.0) * largest))

    def draw(self, rng: np.random.Generator, mass: float, inertia: np.ndarray,
             com: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """(mass kg, inertia kg·m² about the COM, COM (3,) m) drawn about the given ones."""
        m = mass + self.mass * rng.uniform(-1.0, 1.0)
        j = inertia * (m / mass)
        c = com + self.center_of_mass * rng.uniform(-1.0, 1.0, 3)
        return m, stretched(rng, j, self.stretch), c


def draw_valid(rng, changes: list[tuple[MassChange, Any]], mass: float, inertia: np.ndarray,
               com: np.ndarray, bounds) -> tuple[float, np.ndarray, np.ndarray,
                                                 dict[str, object], int]:
    """(mass, inertia, COM, the drawn values by key, redraws) of one body under ``changes``
    ((change, spec; a `Bars` for "bars") in command order), from its ``mass`` kg, ``inertia``
    kg·m² about the COM and ``com`` (3,) m, body frame (a mesh body's: the mesh frame), each
    draw judged valid (`judge`) against ``bounds`` (None: the tensor tests only).
    ComputationError after MAX_REDRAWS failed draws."""
    for attempt in range(MAX_REDRAWS + 1):
        m, j, c, said = mass, inertia, np.array(com, dtype=np.float64), {}
        for change, spec in changes:
            if change.what == "mass":
                new = spec.draw(rng, m)
                if not new > 0:
                    break
                j, m = j * (new / m), new
                said[change.key] = new
            elif change.what == "center_of_mass":
                c[change.axis] = said[change.key] = spec.draw(rng, float(c[change.axis]))
            elif change.what == "bars":
                m, j, c = spec.draw(rng, m, j, c)
                if not m > 0:
                    break
                said.update({f"{change.key}.mass": m, f"{change.key}.inertia": j.tolist(),
                             f"{change.key}.center_of_mass": c.tolist()})
            else:
                j = stretched(rng, j, spec.relative_sd)
                said[change.key] = j.tolist()
        else:
            if judge(m, c, j, bounds).ok:
                return m, j, c, said, attempt
    raise ComputationError(f"no valid inertial in {MAX_REDRAWS + 1} draws (every one broke a "
                           "validity test: the spread is too wide for the body's shape)")
