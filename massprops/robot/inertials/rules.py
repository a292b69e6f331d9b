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
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from massprops.inertia import principal_axes
from massprops.robot.inertials.combine import LinkMass
from massprops.robot.model import MassRules, StatedInertial

__all__ = ["apply_rules"]


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

