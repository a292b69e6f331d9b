"""A simulator compiler's changes to every body's inertial (MJCF ``boundmass``, ``boundinertia``,
``settotalmass``), applied to the stated and computed inertials alike so that both show what the
simulator will use.

Order (MuJoCo 4.0, checked against its compiled ``body_mass``/``body_inertia``): each body's
mass is raised to at least ``boundmass`` (its inertia left as it was: MuJoCo does not
scale it) and each of its principal moments to at least
``boundinertia`` (axes kept); then, with ``settotalmass``, every mass and inertia is multiplied
by settotalmass / (the sum of the bounded masses). The factor is one number for the model, so
its sum counts a body that has neither geometry nor inertial at ``boundmass`` (what MuJoCo gives
it) although such a body is not reported as computed.

`legacy_mesh_inertia` is MuJoCo's legacy mesh rule, which the inertia doctor tries as a cause
(``mujoco_legacy``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from massprops.inertia import principal_axes
from massprops.robot.inertials.combine import LinkMass
from massprops.robot.model import MassRules, StatedInertial

__all__ = ["apply_rules", "legacy_mesh_inertia"]


def apply_rules(reports: list, rules: MassRules) -> tuple[list, str | None]:
    """(reports with the rules applied, a one-line note for the model or None)."""
    bounded = []
    for r in reports:
        stated = _bound_stated(r.link.stated, rules)
        computed = _bound_computed(r.computed, rules)
        bounded.append((r, stated, computed))
    if rules.settotalmass is None:
        out = [_with(r, s, c, 1.0, rules) for r, s, c in bounded]
        return out, None
    total = 0.0
    for _r, s, c in bounded:
        if s is not None:
            total += s.mass
        elif c is not None:
            total += c.mass
        else:
            total += rules.boundmass
    if total <= 0:
        return [r for r, _, _ in bounded], ("compiler settotalmass ignored: the bodies have "
                                            "no mass to scale")
    factor = rules.settotalmass / total
    out = [_with(r, s, c, factor, rules) for r, s, c in bounded]
    return out, (f"compiler settotalmass={rules.settotalmass!r}: every mass and inertia "
                 f"scaled by {factor!r} (as MuJoCo compiles it)")


def _with(report, stated, computed, factor: float, rules: MassRules):
    if stated is not None and factor != 1.0:
        stated = StatedInertial(stated.mass * factor, stated.center_of_mass,
                                stated.inertia * factor, stated.node)
    if computed is not None and factor != 1.0:
        computed = _scaled(computed, factor)
    changed = stated is not report.link.stated or computed is not report.computed
    if not changed:
        return report
    link = replace(report.link, stated=stated)
    comparison = report.comparison
    if comparison is not None and stated is not None and computed is not None:
        # a cycle otherwise: compare needs combine
        from massprops.robot.inertials.compare import compare

        comparison = compare(stated, computed)
    warnings = report.warnings + ("the compiler's boundmass/boundinertia/settotalmass changed "
                                  "this body's inertial",)
    return replace(report, link=link, computed=computed, comparison=comparison,
                   warnings=warnings)


def _bound_stated(s: StatedInertial | None, rules: MassRules) -> StatedInertial | None:
    if s is None:
        return None
    mass, inertia = _bounds(s.mass, s.inertia, rules)
    if mass == s.mass and inertia is s.inertia:
        return s
    return StatedInertial(mass, s.center_of_mass, inertia, s.node)


def _bound_computed(c: LinkMass | None, rules: MassRules) -> LinkMass | None:
    if c is None:
        return None
    mass, inertia = _bounds(c.mass, c.inertia, rules)
    if mass == c.mass and inertia is c.inertia:
        return c
    moments, axes = principal_axes(inertia)
    return replace(c, mass=mass, inertia=inertia, principal_moments=moments, principal_axes=axes)


def _bounds(mass: float, inertia: np.ndarray, rules: MassRules) -> tuple[float, np.ndarray]:
    if rules.boundmass > 0 and mass < rules.boundmass:
        mass = rules.boundmass
    if rules.boundinertia > 0:
        moments, axes = principal_axes(inertia)
        if np.any(moments < rules.boundinertia):
            raised = np.maximum(moments, rules.boundinertia)
            inertia = axes @ np.diag(raised) @ axes.T
    return mass, inertia


def _scaled(c: LinkMass, factor: float) -> LinkMass:
    inertia = c.inertia * factor
    return replace(c, mass=c.mass * factor, inertia=inertia,
                   principal_moments=c.principal_moments * factor)


def legacy_mesh_inertia(vertices: np.ndarray, faces: np.ndarray
                        ) -> tuple[float, np.ndarray, np.ndarray]:
    """MuJoCo's ``inertia="legacy"`` mesh rule (the default of ``<mesh>``; user_mesh.cc), per
    unit density in the mesh frame: (volume m³, centre of mass (3,) m, inertia (3, 3) m⁵ about
    it).

    It integrates the mesh's own faces, not its hull: each face f spans a pyramid to a reference
    point, and the pyramid's volume is taken *positive*, |(c_f − p)·n_f| A_f / 3, whichever way
    the face points. The COM is the volume-weighted mean of the pyramids' centroids to p = the
    surface's area-weighted centroid; the volume and the second moments are then summed over the
    pyramids to that COM (tetrahedra (COM, a, b, c), ∫ x xᵀ dV = V/20 (Σ a aᵀ + s sᵀ), s = a+b+c),
    and the inertia is taken about the COM as it stands. For a convex mesh seen from inside the
    pyramids do not overlap and this is the exact integral; for a non-convex one a face seen
    from behind adds volume where the exact rule subtracts it, so it overcounts (more mass far
    out: larger moments)."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[np.asarray(faces, dtype=np.int64)]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    cross = np.cross(b - a, c - a)          # 2 A n
    centre = (a + b + c) / 3
    area2 = np.linalg.norm(cross, axis=1)
    facecen = (area2 @ centre) / area2.sum()
    vol = np.abs(np.einsum("ij,ij->i", centre - facecen, cross)) / 6
    com = (vol @ (0.75 * centre + 0.25 * facecen)) / vol.sum()
    a, b, c = a - com, b - com, c - com
    vol = np.abs(np.einsum("ij,ij->i", (a + b + c) / 3, np.cross(b - a, c - a))) / 6
    s = a + b + c
    second = sum(np.einsum("i,ij,ik->jk", vol / 20, p, p) for p in (a, b, c, s))
    inertia = np.trace(second) * np.eye(3) - second
    return float(vol.sum()), com, inertia
