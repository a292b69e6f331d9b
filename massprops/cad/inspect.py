"""A CAD file to per-solid mass properties (with densities by name) and the assembly's total."""

from __future__ import annotations

import fnmatch
import os
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from massprops.cad.integrate import SolidIntegral, integrate_solid
from massprops.cad.read import CadFile, CadSolid, read_cad
from massprops.errors import MeshTopologyError, SceneError, UsageError, setting_ref
from massprops.files import read_input
from massprops.inertia import parallel_axis, principal_axes, rotate_inertia
from massprops.mesh.facesums import U
from massprops.mesh.integral import (
    ErrorBars,
    MassProperties,
    Uncertainty,
    check_density_mass,
    properties_from_moments,
)
from massprops.repair.bars import with_repair_bar

__all__ = ["CadInspection", "SolidResult", "inspect_cad", "load_density_map"]


@dataclass(frozen=True, eq=False)
class SolidResult:
    """One solid: its name, assembly path, placement (4, 4; translation in m), the integral
    (unit density, SI), the mass properties at its density (file frame, about its COM),
    the integration and input bars at that density (None where not applicable), warnings;
    density_source: where its density came from (see `material`)."""

    solid: CadSolid
    placement: np.ndarray
    integral: SolidIntegral
    properties: MassProperties
    integration: Uncertainty | None
    input: Uncertainty | None
    warnings: tuple[str, ...]
    repairs: dict | None = None
    density_source: str = "default"

    def material(self) -> dict:
        """{"name" (the file's material, else None), "density" (kg/m³, the one used),
        "source"}: source is "file" (the material's density in the file), "--density-map",
        "--density", "--mass" (the total mass's uniform density) or "default" (1 kg/m³)."""
        stated = self.solid.material or {}
        return {"name": stated.get("name"), "density": self.properties.density,
                "source": self.density_source}


@dataclass(frozen=True, eq=False)
class CadInspection:
    """What `massprops inspect` reports for a CAD file: ``solids`` in file order and, with
    more than one, ``total`` (the whole about its COM by parallel axes, file frame)."""

    file: CadFile
    solids: tuple[SolidResult, ...]
    total: tuple[MassProperties, Uncertainty | None, Uncertainty | None] | None
    warnings: tuple[str, ...]

    def as_dicts(self) -> list[dict]:
        """The contract's JSON objects: one per solid, then the total (several solids)."""
        f = self.file
        out: list[dict] = []
        for r in self.solids:
            d: dict[str, Any] = {"file": f.name, "solid": r.solid.name, "path": r.solid.path}
            d.update(r.properties.as_dict())
            d["material"] = r.material()
            d["uncertainty"] = _bars(r.properties, r.integration, r.input)
            cad = {"format": f.format, "unit": f.unit, "faces": dict(r.integral.faces),
                   "tolerance": r.integral.tolerance}
            if r.solid.colour is not None:
                cad["colour"] = list(r.solid.colour)
            if r.solid.material is not None:
                cad["material"] = dict(r.solid.material)
            d["cad"] = cad
            if r.repairs is not None:
                d["repairs"] = r.repairs
            d["placement"] = r.placement.tolist()
            d["warnings"] = list(r.warnings)
            out.append(d)
        if self.total is not None:
            props, integration, data = self.total
            d = {"file": f.name, "solid": "total", "path": "", "total": True}
            d.update(props.as_dict())
            d["uncertainty"] = _bars(props, integration, data)
            d["warnings"] = list(self.warnings)
            out.append(d)
        elif out:
            out[-1]["warnings"] = list(out[-1]["warnings"]) + list(self.warnings)
        return out


def _bars(props: MassProperties, integration: Uncertainty | None,
          data: Uncertainty | None) -> dict:
    out = {"rounding": props.uncertainty.rounding.as_dict(),
           "integration": None if integration is None else integration.as_dict(),
           "input": None if data is None else data.as_dict()}
    if props.uncertainty.repair is not None:
        out["repair"] = props.uncertainty.repair.as_dict()
    return out


def load_density_map(path: str | os.PathLike) -> list[tuple[str, float]]:
    """A flat YAML mapping of solid names or glob patterns to kg/m³, in file order."""
    import yaml  # a core dependency, only needed with --density-map

    name = os.fspath(path)
    text = read_input(name, what="a density map (YAML)")
    try:
        data = yaml.safe_load(text.decode("utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise SceneError(f"{name}: not UTF-8 text (byte {exc.start}); save it as UTF-8") from exc
    except yaml.YAMLError as exc:
        raise SceneError(f"{name}: not valid YAML ({exc}); expected 'name: density' lines") \
            from exc
    if not isinstance(data, dict):
        raise SceneError(f"{name}: expected a mapping of solid names or glob patterns to "
                         "densities in kg/m³, got " + type(data).__name__)
    out = []
    for key, value in data.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                np.isfinite(value) and value > 0):
            raise SceneError(f"{name}: {key}: expected a positive density in kg/m³, got "
                             f"{value!r}")
        out.append((str(key), float(value)))
    return out


def inspect_cad(path: str | os.PathLike, *, density: float | None = None,
                mass: float | None = None, unit: str | None = None,
                density_map: list[tuple[str, float]] | None = None,
                allow_open: bool = False, shell: float | None = None) -> CadInspection:
    """Read a CAD file and integrate every solid (see `massprops.cad.integrate`).

    density : kg/m³ for solids the map does not name (default: the density of the material the
    file assigns the solid, else 1; `SolidResult.material` says which). mass : kg, the TOTAL mass;
    the density (uniform) follows from the total volume; not with a density or a map.
    unit : BREP's unit (default m); for STEP/IGES only the file's own (else UsageError).
    shell : a wall thickness in metres: every face, open or closed, is the mid-surface of a
    wall that thick (`massprops.cad.shell`), its model bar under ``uncertainty.repair``.
    Raises MeshTopologyError for an open shell (unless allow_open or shell).
    """
    check_density_mass(density, mass)
    if mass is not None and density_map:
        raise UsageError(f"give {setting_ref('mass')} or {setting_ref('density_map')}, not both "
                         "(a total mass fixes one "
                         "uniform density)")
    cad = read_cad(path, unit=unit)
    if not cad.solids:
        raise MeshTopologyError(f"{cad.name}: holds no solid; check that the file has 3D "
                                "geometry (not only curves or points)")
    integrals, shells = [], []
    for solid in cad.solids:
        if shell is not None:
            from massprops.cad.shell import shell_solid  # same layer; only with --shell

            integral, bar, record = shell_solid(solid.shape, cad.scale,
                                                f"{cad.name}: {solid.path}", shell)
            integrals.append(integral)
            shells.append((bar, record))
            continue
        if not solid.closed and not allow_open:
            sewn = "" if solid.sewn is None else (
                f" (its loose faces do not close when sewn within the file's tolerance, "
                f"{solid.sewn:.3g} {cad.unit})")
            raise MeshTopologyError(
                f"{cad.name}: {solid.path} is an open shell, not a closed solid{sewn}: its "
                f"volume is undefined; close it in the CAD tool, or pass "
                f"{setting_ref('allow_open')}")
        integrals.append(integrate_solid(solid.shape, cad.scale, f"{cad.name}: {solid.path}",
                                         only_closed=solid.closed))
    densities, sources, warnings = _densities(cad, density_map or [], density)
    if mass is not None:
        total_volume = sum(i.moments.volume for i in integrals)
        densities = [mass / total_volume] * len(integrals)
        sources = ["--mass"] * len(integrals)
    results = []
    for k, (solid, integral, rho, source) in enumerate(zip(cad.solids, integrals, densities,
                                                            sources)):
        props = properties_from_moments(integral.origin, integral.moments, density=rho,
                                        mass=None, name=f"{cad.name}: {solid.name}")
        repairs = None
        if shells:
            bar, record = shells[k]
            props = with_repair_bar(props, _times(bar, rho))
            repairs = {"shell": record}
        notes = [] if solid.closed or shells else [
            "open shell integrated as if closed (--allow-open): the volume depends on where "
            "the origin is and is not a property of the part"]
        if solid.closed and solid.sewn is not None:
            faces = f"{solid.faces} loose face" + ("s" if solid.faces != 1 else "")
            notes.append(f"sewn from {faces} (the file has no solid around them) within "
                         f"the file's tolerance, {solid.sewn:.3g} {cad.unit}, into a closed "
                         "solid oriented outward; the gaps closed are in uncertainty.input")
        if integral.valid is False:
            notes.append("not a valid shape (OpenCASCADE's BRepCheck): the integral and its "
                         "bars describe the surfaces as stored, which may not bound the "
                         "intended solid; repair or re-export it from the CAD tool")
        placement = solid.placement.copy()
        placement[:3, 3] *= cad.scale
        results.append(SolidResult(solid, placement, integral, props,
                                   _integration(integral, props),
                                   _input(integral, props, cad,
                                          solid.sewn if solid.closed else None), tuple(notes),
                                   repairs, source))
    total = _total(results) if len(results) > 1 else None
    return CadInspection(cad, tuple(results), total, tuple(warnings))


def _densities(cad: CadFile, density_map: list[tuple[str, float]], default: float | None
               ) -> tuple[list[float], list[str], list[str]]:
    """Per solid, the density and where it came from: the first pattern in map order matching
    its name or path; else ``default`` (--density) when given; else the density of the material
    the file assigns it; else 1 kg/m³."""
    used = [False] * len(density_map)
    out, sources = [], []
    for solid in cad.solids:
        stated = (solid.material or {}).get("density")
        if default is not None:
            rho, source = default, "--density"
        elif stated is not None:
            rho, source = float(stated), "file"
        else:
            rho, source = 1.0, "default"
        for k, (pattern, value) in enumerate(density_map):
            if any(fnmatch.fnmatchcase(s, pattern) for s in (solid.name, solid.path)):
                rho, source, used[k] = value, "--density-map", True
                break
        out.append(rho)
        sources.append(source)
    warnings = [f"--density-map: pattern {p!r} matches no solid (names: "
                f"{', '.join(s.name for s in cad.solids)})"
                for (p, _), hit in zip(density_map, used) if not hit]
    return out, sources, warnings


def _integration(integral: SolidIntegral, props: MassProperties) -> Uncertainty | None:
    if integral.integration is None:
        return None
    dv, dc, dj = integral.integration
    rho = props.density
    dj = rho * dj
    return Uncertainty(dv, rho * dv, dc, dj, np.full(3, np.linalg.norm(dj, 2)))


def _input(integral: SolidIntegral, props: MassProperties, cad: CadFile,
           sewn: float | None = None) -> Uncertainty | None:
    """First order: every surface point may lie anywhere within the modelling tolerance τ
    (plus 2 ulps of the largest coordinate, plus half the last printed digit for IGES, plus
    the tolerance ``sewn`` (file unit) its loose faces were sewn at: a gap that wide, closed
    anywhere, moves the boundary that far), so ∫g dV moves by at most max|g| τ A
    (the mesh ``input`` bar's argument with η = τ in every direction)."""
    far = float(np.max(np.abs(integral.origin) + integral.reach))
    # float64 itself: far from the origin every stored point and pole is rounded to half an
    # ulp of its coordinates (a NURBS torus 1e10 sizes out is 7e-7 off in volume: its poles
    # moved independently); 2 ulps leave margin for the poles' weights
    tau = integral.tolerance + 2 * float(np.spacing(far))
    if cad.digits is not None:
        tau += far * 0.5 * 10.0 ** (1 - cad.digits)
    if sewn is not None:
        tau += sewn * cad.scale
    if tau == 0:
        return None
    flux = 1.01 * tau * integral.area
    reach = integral.reach * 2   # from the COM to the farthest box corner, per axis
    g = np.outer(reach, reach)
    g[np.diag_indices(3)] = np.roll(reach**2, 1) + np.roll(reach**2, 2)
    rho = props.density
    d_inertia = rho * g * flux
    volume = props.volume
    return Uncertainty(flux, rho * flux, reach * flux / volume, d_inertia,
                       np.full(3, np.linalg.norm(d_inertia, 2)))


def _total(results: list[SolidResult]
           ) -> tuple[MassProperties, Uncertainty | None, Uncertainty | None]:
    """The whole by parallel axes: M = Σm, c = Σ m c_i / M, J = Σ [J_i + m_i (|d|² I - d dᵀ)],
    d = c_i - c; each bar summed the same way (first order, plus the shift's rounding)."""
    masses = np.array([r.properties.mass for r in results])
    total = float(np.sum(masses))
    coms = np.array([r.properties.center_of_mass for r in results])
    # about the first solid's COM, so that far-away assemblies lose nothing to the offset
    base = coms[0]
    com = base + (masses[:, None] * (coms - base)).sum(axis=0) / total
    inertia = np.zeros((3, 3))
    for r, m, c in zip(results, masses, coms):
        inertia += parallel_axis(r.properties.inertia, m, c - com)
    moments, axes = principal_axes(inertia)
    span = np.max(np.abs(coms - com), axis=0)

    def summed(pick) -> Uncertainty | None:
        bars = [pick(r) for r in results]
        if all(b is None for b in bars):
            return None
        zero = Uncertainty(0.0, 0.0, np.zeros(3), np.zeros((3, 3)), np.zeros(3))
        bars = [zero if b is None else b for b in bars]
        dm = sum(b.mass for b in bars)
        dc = sum(m * b.center_of_mass + b.mass * span for b, m in zip(bars, masses)) / total
        shift = np.outer(span + dc, dc)
        dj = sum(b.inertia for b in bars) + np.outer(span, span) * 4 * dm + \
            4 * total * (shift + shift.T)
        return Uncertainty(sum(b.volume for b in bars), dm, dc, dj,
                           np.full(3, np.linalg.norm(dj, 2)))

    # every solid has a rounding bar, so the sum is one
    rounding = cast(Uncertainty, summed(lambda r: r.properties.uncertainty.rounding))
    extra = 8 * U * (np.abs(inertia) + total * np.outer(span, span))
    rounding = Uncertainty(rounding.volume, rounding.mass + 4 * U * total,
                           rounding.center_of_mass + 4 * U * (np.abs(com) + span),
                           rounding.inertia + extra,
                           rounding.principal_moments + np.linalg.norm(extra, 2)
                           + 32 * U * np.abs(moments).max())
    volume = float(sum(r.properties.volume for r in results))

    props = MassProperties(volume, total, total / volume, com, inertia, moments, axes,
                           ErrorBars(rounding, None,
                                     summed(lambda r: r.properties.uncertainty.repair)))
    return props, summed(lambda r: r.integration), summed(lambda r: r.input)


def _times(bar: Uncertainty, rho: float) -> Uncertainty:
    """A per-unit-density bar at density ``rho``."""
    return Uncertainty(bar.volume, rho * bar.mass, bar.center_of_mass, rho * bar.inertia,
                       rho * bar.principal_moments)


def local_inertial(result: SolidResult) -> tuple[np.ndarray, np.ndarray]:
    """(COM (3,), inertia (3, 3)) in the solid's own frame from the file (its placement
    undone): what a robot description's <inertial> holds for that link."""
    r = result.placement[:3, :3]
    t = result.placement[:3, 3]
    com = r.T @ (result.properties.center_of_mass - t)
    return com, rotate_inertia(result.properties.inertia, r.T)
