"""The principal frame: the rigid map that puts a mesh's COM at the origin and its axes along the
principal axes, and the mesh rewritten in it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from massprops.mesh import Mesh
from massprops.mesh.integral import MassProperties


@dataclass(frozen=True, eq=False)
class Alignment:
    """The map v ↦ rotation @ v + translation from mesh coordinates to principal coordinates.

    rotation : (3, 3) float, Rᵀ where R's columns are the principal axes (mesh frame).
    translation : (3,) float, m, -Rᵀ c with c the centre of mass (mesh frame).
    principal_moments : (3,) float, kg·m², ascending: the diagonal of the aligned inertia tensor.
    mesh : the mesh in principal coordinates; faces and winding unchanged.
    """

    rotation: np.ndarray
    translation: np.ndarray
    principal_moments: np.ndarray
    mesh: Mesh

    def as_dict(self) -> dict:
        return {"rotation": self.rotation.tolist(), "translation": self.translation.tolist(),
                "principal_moments": self.principal_moments.tolist()}


def to_principal_frame(vertices: np.ndarray, props: MassProperties) -> np.ndarray:
    """Vertices (n, 3) m, mesh frame -> principal frame: Rᵀ (v - c).

    The COM is subtracted before rotating: v - c is exact or nearly so for vertices near c, while
    Rᵀv + (-Rᵀc) would lose (|c|/size) ulps for a part far from the origin.
    """
    return (vertices - props.center_of_mass) @ props.principal_axes


def align_mesh(mesh: Mesh, props: MassProperties) -> Alignment:
    """Rewrite ``mesh`` (whose mass properties are ``props``) in its principal frame."""
    r = props.principal_axes
    moved = mesh.with_vertices(to_principal_frame(mesh.vertices, props))
    return Alignment(r.T.copy(), -(r.T @ props.center_of_mass), props.principal_moments.copy(),
                     moved)
