"""``massprops model``: a whole description, link by link, stated against computed.

`analyze_model` is the CLI's single call; `ModelReport.write` and `ModelReport.require_agreement`
serve ``--write`` and ``--check``.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import cast

import numpy as np

from massprops.errors import (
    CheckFailedError,
    MassPropsError,
    MeshTopologyError,
    NoVolumeError,
    RobotModelError,
    UsageError,
    error_message,
    setting_ref,
)
from massprops.robot.doctor.diagnose import Diagnosis, diagnose
from massprops.robot.doctor.shapes import shape_bases
from massprops.robot.doctor.validity import Validity, judge
from massprops.robot.formats.xacro_run import EXPANDED, expand_xacro, has_xacro, is_xacro
from massprops.robot.formats.xmltree import parse_xml, parse_xml_bytes
from massprops.robot.inertials.combine import LinkMass, MeshCache, combine, integrate_geometry
from massprops.robot.inertials.compare import Comparison, compare, relative_difference
from massprops.robot.model import Geometry, Link, RobotModel
from massprops.tolerances import WRITE_KEEP_RTOL

__all__ = ["LinkReport", "ModelReport", "analyze_model", "load_model", "FORMATS_BY_ROOT"]

SOURCES = ("auto", "collision", "visual")
"""auto: each link's collision geometry, or its visual geometry when it has none."""

FORMATS_BY_ROOT = {"robot": "urdf", "sdf": "sdf", "mujoco": "mjcf"}
"""Root element -> format: the file's content decides, not its extension (.xml is both)."""


@dataclass(frozen=True, eq=False)
class LinkReport:
    """One link: status "computed", "stated-only" (a stated inertial and no geometry at all:
    reported as it is) or "skipped"; ``reason`` why not computed; ``error`` True when the
    skip means an input could not be processed (a missing or unreadable mesh), False for a link
    that simply has nothing to compute (no geometry, a frame link). ``repairs``: mesh reference
    -> its ``repairs`` object, for the meshes a repair changed (None: none did). ``shapes``:
    the link's other shapes for the doctor (`doctor.shapes.shape_bases`), computed on demand.
    ``checked``: a ``--check`` ran (the row then has "diagnosis"); ``diagnosis``: why the
    stated inertial differs by more than its RTOL (`doctor.diagnose`), else None."""

    link: Link
    status: str
    reason: str | None
    error: bool
    computed: LinkMass | None
    comparison: Comparison | None
    warnings: tuple[str, ...]
    repairs: dict | None = None
    shapes: Callable[[], list] | None = field(default=None, repr=False)
    checked: bool = False
    diagnosis: Diagnosis | None = None

    @property
    def name(self) -> str:
        return self.link.name

    def stated_validity(self) -> Validity | None:
        """The stated inertial's `doctor.validity` tests (against the geometry when there is
        some), or None when nothing is stated."""
        s = self.link.stated
        if s is None:
            return None
        if self.comparison is not None and self.comparison.valid is not None:
            return self.comparison.valid
        return judge(s.mass, s.center_of_mass, s.inertia, None)

    def computed_validity(self) -> Validity | None:
        """The computed inertial's tests (an open mesh counted with signed volumes can fail
        them), or None when nothing was computed."""
        c = self.computed
        return None if c is None else judge(c.mass, c.center_of_mass, c.inertia, c.bounds)

    def stated_problems(self) -> tuple[str, ...]:
        v = self.stated_validity()
        return () if v is None else v.problems

    def as_dict(self, model: str) -> dict:
        """The contract's JSON object for this link, plus "line", "comparison", "source" (which
        geometry made it) and, where a repair changed a mesh, "repairs" (mesh -> record)."""
        s = self.link.stated
        valid = self.stated_validity()
        # stated_validity and computed_validity are None only when nothing is stated / computed
        stated = None if s is None else {
            "mass": s.mass, "center_of_mass": s.center_of_mass.tolist(),
            "inertia": s.inertia.tolist(), "valid": cast(Validity, valid).ok}
        computed = None
        if self.computed is not None:
            computed = {**self.computed.as_dict(),
                        "valid": cast(Validity, self.computed_validity()).as_dict()}
        return {"model": model, "link": self.name, "line": self.link.node.line,
                "status": self.status, "reason": self.reason, "stated": stated,
                **({"valid": valid.as_dict()} if valid is not None else {}),
                "computed": computed,
                "comparison": None if self.comparison is None else self.comparison.as_dict(),
                "source": self.link.source if self.link.geometries else None,
                **({"repairs": self.repairs} if self.repairs else {}),
                **({"diagnosis": None if self.diagnosis is None else self.diagnosis.as_dict()}
                   if self.checked else {}),
                "warnings": list(self.warnings)}


@dataclass(frozen=True, eq=False)
class ModelReport:
    """Every link of one description, in file order (MJCF: MuJoCo's body order)."""

    model: RobotModel
    name: str
    links: tuple[LinkReport, ...]

    @property
    def errors(self) -> list[str]:
        """One line per link that could not be computed because of a bad input."""
        return [f"{self._file_of(r)}:{r.link.node.line}: link {r.name!r}: {r.reason}"
                for r in self.links if r.error]

    def _file_of(self, r: LinkReport) -> str:
        """The file a link is written in: this one, or an included / attached one."""
        f = r.link.node.file
        return self.name if f is None or f == self.model.path else str(f)

    def failures(self, rtol: float) -> list[str]:
        """Links whose stated inertial differs by more than ``rtol`` (see compare.py), or is not
        physically valid; one short phrase each."""
        out = []
        for r in self.links:
            problems = r.stated_problems()
            if problems:
                out.append(f"{r.name} ({problems[0]})")
            elif r.comparison is not None and r.comparison.worst > rtol:
                c = r.comparison
                what = max((c.mass_rel, "mass"), (c.com_rel, "centre of mass"),
                           (c.inertia_rel, "inertia"))
                out.append(f"{r.name} ({what[1]} off by {what[0]:.3g})")
        return out

    def require_agreement(self, rtol: float) -> None:
        """CheckFailedError (exit 4) naming the links that differ by more than ``rtol``."""
        if not (math.isfinite(rtol) and rtol >= 0):
            raise UsageError(f"{setting_ref('check')} needs a tolerance >= 0, got {rtol!r}")
        bad = self.failures(rtol)
        if bad:
            raise CheckFailedError(
                f"{self.name}: {len(bad)} link(s) differ from their geometry by more than "
                f"{rtol:g}: {'; '.join(bad)}; fix the inertials (massprops model --write OUT)")

    def to_rewrite(self, rtol: float | None = None, *,
                   only_invalid: bool = False) -> list[LinkReport]:
        """The computed links whose inertial is off: none stated, or not physically valid, or
        differing from the computed one by more than ``rtol`` (default WRITE_KEEP_RTOL:
        round-off); with ``only_invalid``, only those whose stated inertial fails a validity
        test. A link whose computed inertial fails one is never chosen (nothing better to
        write); the others are kept as written."""
        keep = WRITE_KEEP_RTOL if rtol is None else rtol
        chosen = []
        for r in self.links:
            if r.computed is None or not cast(Validity, r.computed_validity()).ok:
                continue
            invalid = bool(r.stated_problems())
            if only_invalid:
                off = invalid
            else:
                off = (r.link.stated is None or invalid or r.comparison is None
                       or r.comparison.worst > keep)
            if off:
                chosen.append(r)
        return chosen

    def write(self, out: str | os.PathLike, *, force: bool = False,
              rtol: float | None = None, keep_mass: bool = False,
              only_invalid: bool = False) -> tuple[Rewrite, ...]:
        """Write the description with the inertial of every link that is off (`to_rewrite`)
        replaced, or added where it has none; every other byte as read. ``keep_mass``: the
        stated mass with the geometry's distribution (COM, and the tensor scaled to that mass;
        a link with no stated mass gets the computed one). Returns what changed, per link
        rewritten. Atomic, never over the input."""
        # deferred: a description loads only its own format's parser
        from massprops.robot.write.writeback import edited_bytes, write_description

        chosen = self.to_rewrite(rtol, only_invalid=only_invalid)
        written = [_written(r, keep_mass) for r in chosen]
        edits = [(r.link.node, r.link.inertial_node, w) for r, w in zip(chosen, written)]
        own = (self.model.path, Path(f"{self.model.path}{EXPANDED}"))
        elsewhere = [r.name for r in chosen
                     if r.link.node.file is not None and r.link.node.file not in own]
        if elsewhere:
            raise UsageError(f"{self.name}: {setting_ref('write')} edits this file only, but "
                             f"link(s) {', '.join(elsewhere[:3])} come from an included or "
                             "attached file; write the inertials there by hand or save the "
                             "compiled model (mujoco.mj_saveLastXML) first")
        data = edited_bytes(self.model.data, self.model.format, edits)
        write_description(data, out, source=self.model.path, force=force)
        keep = WRITE_KEEP_RTOL if rtol is None else rtol
        return tuple(Rewrite.of(r, w, keep) for r, w in zip(chosen, written))


def _written(r: LinkReport, keep_mass: bool) -> LinkMass:
    """What ``--write`` puts in link ``r``: the computed inertial, or with ``keep_mass`` the
    stated mass and the computed distribution (COM as computed, tensor × m_stated / m)."""
    c, s = cast(LinkMass, r.computed), r.link.stated  # to_rewrite chose computed links only
    if not keep_mass or s is None or not (s.mass > 0) or s.mass == c.mass:
        return c
    f = s.mass / c.mass
    return replace(c, mass=s.mass, inertia=c.inertia * f,
                   principal_moments=c.principal_moments * f)


@dataclass(frozen=True)
class Rewrite:
    """What ``--write`` changed in one link: why it was rewritten, and the stated against the
    written inertial (mass kg, COM moved m, inertia changed: ‖ΔJ‖₂/‖J_written‖₂)."""

    link: str
    why: str
    mass: tuple[float | None, float]
    com_moved: float | None
    inertia_changed: float | None

    @classmethod
    def of(cls, r: LinkReport, w: LinkMass, rtol: float) -> Rewrite:
        s = r.link.stated
        if s is None:
            return cls(r.name, "none stated: added", (None, w.mass), None, None)
        problems = r.stated_problems()
        why = (f"invalid ({problems[0]})" if problems else
               f"off by {cast(Comparison, r.comparison).worst:.3g} (> {rtol:g})")
        return cls(r.name, why, (s.mass, w.mass),
                   float(np.linalg.norm(w.center_of_mass - s.center_of_mass)),
                   float(np.linalg.norm(w.inertia - s.inertia, 2) / np.linalg.norm(w.inertia, 2)))

    def phrase(self) -> str:
        """One line: the link, why, and what changed."""
        if self.mass[0] is None:
            return f"{self.link}: {self.why}, mass {self.mass[1]:.6g} kg"
        mass = (f"mass {self.mass[0]:.6g} kg kept" if self.mass[0] == self.mass[1] else
                f"mass {self.mass[0]:.6g} -> {self.mass[1]:.6g} kg")
        return (f"{self.link}: {self.why}: {mass}, COM moved {self.com_moved:.3g} m, "
                f"inertia changed by {self.inertia_changed:.3g}")


def load_model(path: str | os.PathLike, *, source: str = "auto",
               package_paths: Sequence[str | os.PathLike] = (),
               xacro_args: Mapping[str, str] | None = None) -> RobotModel:
    """Parse a URDF, SDF or MJCF file (told apart by its root element) into the neutral model;
    a ``.xacro`` file is expanded first by xacro with ``xacro_args`` (`xacro_run`)."""
    if source not in SOURCES:
        raise UsageError(f"source must be one of {', '.join(SOURCES)}, got {source!r}")
    p = Path(path)
    said: list[str] = []  # xacro's own warnings, for the model's
    if is_xacro(p):
        if not p.is_file():
            parse_xml(p)  # the reader's own "no such file" / "is a directory" message
        data = expand_xacro(p, xacro_args, package_paths=[Path(d) for d in package_paths],
                            notes=said)
        root = parse_xml_bytes(data, f"{p}{EXPANDED}")
    else:
        root, data = parse_xml(p)
    note = None
    if root.tag == "robot" and not is_xacro(p) and has_xacro(root):
        # a .urdf still holding xacro (e.g. $(optenv ...) left by a partial expansion): what
        # ROS tools do with it is run xacro, so do that rather than refuse the robot
        data = expand_xacro(p, xacro_args, package_paths=[Path(d) for d in package_paths],
                            notes=said)
        root = parse_xml_bytes(data, f"{p}{EXPANDED}")
        note = "the file holds xacro expressions: expanded by xacro first"
    fmt = FORMATS_BY_ROOT.get(root.tag)
    if fmt is None:
        raise RobotModelError(f"{p}:{root.line}: <{root.tag}>: not a robot description; expected "
                              "a root element <robot> (URDF), <sdf> (SDF) or <mujoco> (MJCF)")
    if fmt == "urdf":
        # deferred: a description loads only its own format's parser
        from massprops.robot.formats.urdf import parse_urdf as parse
    elif fmt == "sdf":
        # deferred: a description loads only its own format's parser
        from massprops.robot.formats.sdf import parse_sdf as parse
    else:
        # deferred: a description loads only its own format's parser
        from massprops.robot.formats.mjcf import parse_mjcf as parse
    model = parse(root, data, p, source=source, package_paths=[Path(d) for d in package_paths])
    if not model.links:
        said.append("no links: nothing to compute (a file of xacro macros only? give the file "
                    "that calls them)" if is_xacro(p) else "no links: nothing to compute")
    if note is None and not said:
        return model
    return replace(model, warnings=(*([note] if note else []), *said, *model.warnings))


def analyze_model(path: str | os.PathLike, *, source: str = "auto",
                  density: float | None = None,
                  package_paths: Sequence[str | os.PathLike] = (),
                  allow_open: bool = False,
                  xacro_args: Mapping[str, str] | None = None,
                  repairs=None, check: float | None = None) -> ModelReport:
    """Every link of the description at ``path``: its geometry integrated, against its stated
    inertial.

    source : "auto" (default: collision geometry, else visual with a note), "collision" or
        "visual" (MJCF: see mjcf.py; auto is collision there, MuJoCo's mass geoms).
    repairs : a `massprops.repair.RepairOptions` applied to every mesh (per mesh, reported
        per link), or None.
    check : RTOL of ``--check``: every link whose stated inertial differs by more gets a
        `doctor.diagnose.Diagnosis` (the others None); None: no diagnosis.
    density : kg/m³ for every geometry; default: keep each link's stated mass (the density
        follows from its geometry's volume); MJCF bodies without an inertial use their geoms'
        own density/mass (MuJoCo's rule); URDF/SDF links without a stated mass are skipped.
    Raises RobotModelError (malformed description), MeshFileError (unreadable file); a link
    whose meshes cannot be used is reported as skipped with ``error`` set, not raised.
    """
    if density is not None and not (math.isfinite(density) and density > 0):
        raise UsageError(f"density must be a positive finite number, got {density!r}")
    model = load_model(path, source=source, package_paths=package_paths, xacro_args=xacro_args)
    meshes = MeshCache(allow_open=allow_open, repairs=repairs)
    reports = [_link(link, model, meshes, density, source) for link in model.links]
    if model.rules.any:
        from massprops.robot.inertials.rules import apply_rules  # only MJCF compilers ask for it

        reports, note = apply_rules(reports, model.rules)
        # boundinertia may raise a computed tensor's moments: a warning of invalidity made
        # before it goes where the tensor MuJoCo will use passes
        reports = [_drop_stale_invalid(r) for r in reports]
        if note:
            model = replace(model, warnings=model.warnings + (note,))
    if check is not None:
        if not (math.isfinite(check) and check >= 0):
            raise UsageError(f"{setting_ref('check')} needs a tolerance >= 0, got {check!r}")
        other = _OtherGeometry(path, model, meshes, density, package_paths, xacro_args)
        reports = [replace(r, checked=True, diagnosis=_diagnosis(r, check, other))
                   for r in reports]
    return ModelReport(model, str(path), tuple(reports))


def _diagnosis(r: LinkReport, rtol: float, other: _OtherGeometry) -> Diagnosis | None:
    """Why link ``r``'s stated inertial differs by more than ``rtol``, or None if it does not."""
    if r.comparison is None or r.comparison.worst <= rtol:
        return None

    def shapes() -> list:
        bases = r.shapes() if r.shapes is not None else []
        return bases + other.bases(r)

    return diagnose(r.link.stated, r.computed, shapes, relative_difference)


class _OtherGeometry:
    """The links computed from the other geometry set (visual for collision, and back), read on
    the first link that asks: the doctor's ``other_geometry``."""

    def __init__(self, path, model, meshes, density, package_paths, xacro_args) -> None:
        self.args = (path, package_paths, xacro_args)
        self.model, self.meshes, self.density = model, meshes, density
        self._links: dict[str, dict] = {}

    def bases(self, r: LinkReport) -> list:
        other = "visual" if r.link.source == "collision" else "collision"
        if other not in self._links:
            path, package_paths, xacro_args = self.args
            try:
                model = load_model(path, source=other, package_paths=package_paths,
                                   xacro_args=xacro_args)
                self._links[other] = {link.name: link for link in model.links}
            except MassPropsError:
                self._links[other] = {}
        link = self._links[other].get(r.name)
        if link is None or not link.geometries or link.source != other:
            return []
        o = _link(link, self.model, self.meshes, self.density, other)
        if o.computed is None:
            return []
        c = o.computed
        return [((("other_geometry", {"source": other}, f"of the {other} geometry"),),
                 c.mass, c.center_of_mass, c.inertia)]


_NOT_VALID = "computed inertial not valid, never written"


def _drop_stale_invalid(r: LinkReport) -> LinkReport:
    """``r`` without its invalidity warning when its computed inertial (after the rules) passes."""
    v = r.computed_validity()
    if v is None or not v.ok:
        return r
    return replace(r, warnings=tuple(w for w in r.warnings if not w.startswith(_NOT_VALID)))


def _invalid_warning(validity: Validity, geometries: Sequence[Geometry], parts: Sequence
                     ) -> str:
    """One line for a link whose computed inertial fails a validity test: the test, and the
    mesh and defect that make an integral of the geometry do that (a positive density, however
    overlapped, never fails them): inward-facing pieces partly outside every solid (counted there
    with negative density), or an open surface integrated as it is."""
    from massprops.mesh.health import LOOSE_CAVITY, OPEN_SURFACE  # the rare path only

    bad = validity.problems
    head = (f"{_NOT_VALID}: {bad[0]}"
            + (f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""))
    causes = []
    for g, part in zip(geometries, parts):
        loose = [m.group(1) for w in part.warnings
                 if (m := re.match(rf"component (\d+) \(a cavity: faces inward\) {LOOSE_CAVITY}",
                                   w))]
        if loose:
            one = len(loose) == 1
            which = (f"component {loose[0]} faces inward and is" if one else
                     f"components {', '.join(loose)} face inward and are")
            it = ("it counts", "it is a solid, its") if one else ("they count", "they are "
                                                                   "solids, their")
            causes.append(f"{g.uri}: {which} {LOOSE_CAVITY.removeprefix('is ')}, so {it[0]} "
                          f"there with negative density (if {it[1]} faces are reversed in the "
                          "file: fix them there)")
        elif any(w.startswith(OPEN_SURFACE) for w in part.warnings):
            causes.append(f"{g.uri}: an open surface integrated as it is "
                          f"({setting_ref('allow_open')}), its signed volumes not a solid's")
    if not causes:
        return f"{head}; no defect of the geometry found to explain it"
    return f"{head}: {'; '.join(causes)}"


def _link(link: Link, model: RobotModel, meshes: MeshCache, density: float | None,
          source: str) -> LinkReport:
    warnings = list(link.warnings)

    def skipped(reason: str, error: bool) -> LinkReport:
        return LinkReport(link, "skipped", reason, error, None, None, tuple(warnings))

    if not link.geometries:
        if link.stated is not None and link.stated.mass > 0:
            return LinkReport(link, "stated-only", "no geometry: the stated inertial is "
                              "reported as it is", False, None, None, tuple(warnings))
        return skipped("no geometry (a frame or dummy link)" if not link.stated else
                       "no geometry to compute its inertial from", False)
    if link.source == "visual" and source == "auto" and model.format != "mjcf":
        warnings.append("source: visual (the link has no collision geometry)")
    for g in link.geometries:
        if g.problem:
            return skipped(g.problem, True)
    warnings.extend(g.warning for g in link.geometries if g.warning)
    parts = []
    used = []  # the geometries in parts: all but sheets beside other geometry
    sheets: list[tuple[Geometry, NoVolumeError]] = []
    repaired: dict = {}
    for g in link.geometries:
        try:
            part = integrate_geometry(g, meshes)
        except NoVolumeError as exc:
            if len(link.geometries) > 1 and g.mass is None:
                sheets.append((g, exc))  # adds nothing beside the others (MuJoCo: ~0 too)
                continue
            return skipped(f"{g.uri or g.kind} (line {g.node.line}): {error_message(exc)}", True)
        except MassPropsError as exc:
            hint = ""
            if isinstance(exc, MeshTopologyError) and link.source == "collision":
                hint = "; or --from visual to compute the link from its visual geometry"
            return skipped(f"{g.uri or g.kind} (line {g.node.line}): {error_message(exc)}{hint}",
                           True)
        warnings.extend(f"{g.uri}: {w}" for w in part.warnings)
        if part.repairs:
            repaired[g.uri or g.kind] = part.repairs
        parts.append(part)
        used.append(g)
    if sheets and not parts:
        g, flat = sheets[0]
        return skipped(f"{g.uri or g.kind} (line {g.node.line}): {error_message(flat)}", True)
    warnings.extend(f"{g.uri}: encloses no volume (a sheet or slivers): counted as zero volume "
                    "beside the link's other geometry" for g, _exc in sheets)
    stated = link.stated

    def split(parts) -> tuple[list[float], float | None] | None:
        """(each part's mass, the link's total to report) by the link's mass rule."""
        if density is not None:
            return [density * p.volume for p in parts], None
        weights = [g.mass if g.mass is not None else (g.density or 1.0) * p.volume
                   for g, p in zip(used, parts)]
        if stated is not None and stated.mass > 0:
            return [stated.mass * w / sum(weights) for w in weights], stated.mass
        if link.auto_mass is not None:  # SDF auto: the densities' shares of the given mass
            return [link.auto_mass * w / sum(weights) for w in weights], link.auto_mass
        if model.format == "mjcf" or all(g.density is not None for g in used):
            return weights, None
        return None

    shares = split(parts)
    if shares is None:
        return skipped(f"no stated mass to keep and no {setting_ref('density')}: give "
                       f"{setting_ref('density')} RHO "
                       "(kg/m³)", False)
    computed = combine(parts, *shares)
    if stated is None:
        if model.format != "mjcf" and link.inertial_node is None:  # MJCF, SDF auto: the sum
            warnings.append("no stated inertial: nothing to compare")
        comparison = None
    else:
        comparison = compare(stated, computed)
    if not np.isfinite(computed.inertia).all():
        return skipped("the computed inertia is not finite", True)
    validity = judge(computed.mass, computed.center_of_mass, computed.inertia, computed.bounds)
    if not validity.ok:
        warnings.append(_invalid_warning(validity, used, parts))
    return LinkReport(link, "computed", None, False, computed, comparison, tuple(warnings),
                      repaired or None,
                      shapes=lambda: shape_bases(used, parts, meshes, split))
