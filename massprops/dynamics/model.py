"""Value objects of a dynamics scene: the body, its initial state, the forces, the time settings.

Frames (stated once, see DESIGN.md):
- world: inertial frame; positions of the centre of mass (COM), velocities, gravity, anchors.
- body: the mesh's axes, origin at the mesh origin (explicit body: at the COM, or at
  ``body.center_of_mass`` if given). Force ``point``s are body coordinates.
- principal: origin at the COM, axes the principal axes (columns of ``principal_axes`` in body
  coordinates: v_body = R v_principal). Integrators work in this frame (J' diagonal).
Quaternions are scalar-first [w, x, y, z], unit, rotating body -> world: v_world = A(q) v_body.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from massprops.errors import UnphysicalInertiaError
from massprops.tolerances import (
    INERTIA_POSITIVE_RTOL,
    INERTIA_SYMMETRY_RTOL,
    INERTIA_TRIANGLE_RTOL,
)

if TYPE_CHECKING:
    from massprops.dynamics.joints.model import Joint
    from massprops.mesh.integral import ErrorBars

INF = math.inf


def _vec3(x, name: str) -> np.ndarray:
    a = np.array(x, dtype=np.float64)
    if a.shape != (3,):
        raise ValueError(f"{name}: expected a 3-vector, got shape {a.shape}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class MeshSource:
    """Where a mesh body's mass properties came from, kept for what varies them within their
    error bars (``sweep --bars``): the file ``path`` read in ``unit``, inspect's centre of mass
    ``center_of_mass`` (3,) m in the mesh frame, and its error bars ``bars`` (rounding, input,
    repair: absolute bounds, `massprops.mesh.integral.ErrorBars`)."""

    path: str
    unit: str
    center_of_mass: np.ndarray
    bars: ErrorBars


@dataclass(frozen=True, eq=False)
class RigidBody:
    """Mass properties as the dynamics needs them.

    mass : float, kg.
    principal_moments : (3,) float, kg·m², ascending, about the COM.
    principal_axes : (3, 3) float, proper rotation whose columns are the principal axes in body
        coordinates (v_body = R @ v_principal).
    center_of_mass : (3,) float, m, the COM in body coordinates.
    size : float, m, a length scale of the body (used to make position errors relative): the
        larger of the bounding radius about the COM and the largest radius of gyration.
    mesh : a mesh body's file and inspect's bars (`MeshSource`); None for an explicit body.
    """

    mass: float
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    center_of_mass: np.ndarray
    size: float
    mesh: MeshSource | None = None

    @property
    def inertia_body(self) -> np.ndarray:
        """(3, 3) kg·m², about the COM, body axes: R diag(moments) Rᵀ."""
        r = self.principal_axes
        return (r * self.principal_moments) @ r.T

    @classmethod
    def from_inertia(cls, mass: float, inertia_com, center_of_mass=(0.0, 0.0, 0.0),
                     size: float | None = None) -> RigidBody:
        """A body from an explicit inertia tensor about the COM in body axes.

        Raises UnphysicalInertiaError unless the tensor is symmetric, positive definite and each
        principal moment is at most the sum of the other two (see tolerances.INERTIA_*).
        """
        from massprops.inertia import principal_axes  # one place for the eigen-decomposition

        if not (math.isfinite(mass) and mass > 0):
            raise UnphysicalInertiaError(f"mass must be a positive finite number, got {mass!r}")
        j = np.array(inertia_com, dtype=np.float64)
        if j.shape != (3, 3) or not np.isfinite(j).all():
            raise UnphysicalInertiaError(
                f"inertia must be a finite 3x3 matrix, got shape {j.shape}")
        scale = float(np.abs(j).max())
        if scale == 0 or np.abs(j - j.T).max() > INERTIA_SYMMETRY_RTOL * scale:
            raise UnphysicalInertiaError("inertia is not symmetric (or is zero)")
        moments, axes = principal_axes(0.5 * (j + j.T))
        if moments[0] <= INERTIA_POSITIVE_RTOL * moments[2]:
            raise UnphysicalInertiaError(
                f"inertia is not positive definite: principal moments {moments.tolist()}")
        if moments[2] > (moments[0] + moments[1]) * (1 + INERTIA_TRIANGLE_RTOL):
            raise UnphysicalInertiaError(
                "inertia violates the triangle inequality: largest principal moment "
                f"{float(moments[2])!r} exceeds the sum of the others "
                f"{float(moments[0] + moments[1])!r}")
        radius = math.sqrt(moments[2] / mass)
        return cls(float(mass), moments, axes, _vec3(center_of_mass, "center_of_mass"),
                   float(size) if size is not None else radius)


@dataclass(frozen=True, eq=False)
class InitialState:
    """position, velocity: (3,) world, m and m/s, of the COM. orientation: (4,) unit quaternion
    [w, x, y, z], body -> world. angular_velocity: (3,) rad/s in ``angular_velocity_frame``."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0, 0, 0]))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity_frame: str = "world"  # "world" | "body"


# --- forces: one frozen dataclass per kind; scene.py maps YAML type names to them ---
@dataclass(frozen=True, eq=False)
class Gravity:
    """Uniform field g (3,) world, m/s²; acts at the COM (no torque)."""

    g: np.ndarray


@dataclass(frozen=True, eq=False)
class PointForce:
    """vector (3,) N in ``frame`` ("world" or "body"), applied at ``point`` (3,) body coordinates
    (None: the COM, no torque), while start <= t < end (s)."""

    vector: np.ndarray
    frame: str = "world"
    point: np.ndarray | None = None
    start: float = -INF
    end: float = INF


@dataclass(frozen=True, eq=False)
class Torque:
    """vector (3,) N·m in ``frame`` ("world" or "body"), while start <= t < end (s)."""

    vector: np.ndarray
    frame: str = "world"
    start: float = -INF
    end: float = INF


@dataclass(frozen=True, eq=False)
class Spring:
    """Spring-damper from world ``anchor`` (3,) to body ``point`` (3,) body coordinates (None: COM).

    Force on the body, d = p_world - anchor, L = |d|, u = d / L:
    rest_length > 0: f = -(k (L - rest_length) + c dL/dt) u;
    rest_length == 0: f = -k d - c d' (isotropic, no singularity at L = 0).
    """

    anchor: np.ndarray
    stiffness: float
    point: np.ndarray | None = None
    rest_length: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True, eq=False)
class Drag:
    """f = -linear v (world, N·s/m), n = -angular ω (N·m·s)."""

    linear: float = 0.0
    angular: float = 0.0


ForceTerm = Gravity | PointForce | Torque | Spring | Drag


@dataclass(frozen=True)
class TimeSettings:
    """duration (s); integrator name from the registry or "auto"; rtol for adaptive methods;
    step (s) for fixed-step methods (None: the integrator chooses)."""

    duration: float
    integrator: str = "auto"
    rtol: float = 1e-9
    step: float | None = None


@dataclass(frozen=True)
class OutputSettings:
    """every: sampling interval (s) of the trajectory (None: no trajectory unless asked);
    file: .csv or .npz path, already resolved against the scene's folder."""

    every: float | None = None
    file: Path | None = None


@dataclass(frozen=True, eq=False)
class Scene:
    """A whole scene, validated. ``source`` names the file for messages; ``body_source`` says
    where the mass properties came from (mesh path or "explicit"); ``input_files`` are the files
    the scene reads (its mesh), which no output may replace; ``warnings`` what the mesh's health
    check said (a flipped or open mesh); ``joints`` what holds the body to the world
    (massprops.dynamics.joints; empty: a free body); ``notes`` what the scene's own checks said
    (an initial state projected onto the joints)."""

    body: RigidBody
    initial: InitialState
    forces: tuple[ForceTerm, ...]
    time: TimeSettings
    output: OutputSettings
    source: str = "<scene>"
    body_source: str = "explicit"
    input_files: tuple[Path, ...] = ()
    warnings: tuple[str, ...] = ()
    joints: tuple[Joint, ...] = ()
    notes: tuple[str, ...] = ()
