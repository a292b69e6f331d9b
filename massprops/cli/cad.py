"""The CAD branch of ``inspect`` (STEP, IGES, BREP): print what `massprops.cad.inspect_cad`
computed, one object per solid and the total; the library does the work."""

from __future__ import annotations

from typing import Any

import click

from massprops.cli.common import (
    ELEMENT_FORMATS,
    StdoutClosed,
    check_outputs,
    element_comment,
    emit_json,
    guarded,
    say_warning,
    silence_stdout,
)


def inspect_cad_files(ctx: click.Context, paths: tuple[str, ...], out_format: str,
                      principal: bool, options: dict[str, Any],
                      density_map: str | None) -> int:
    """Inspect each CAD file in ``paths``; the worst exit code."""
    unit = options.get("unit")
    if ctx.get_parameter_source("unit") is click.core.ParameterSource.DEFAULT:
        unit = None  # the file's own unit (BREP: metres)
    repairs = options.get("repairs")
    if repairs is not None and (repairs.union or repairs.fill_holes):
        raise click.UsageError("--fill-holes and --union apply to meshes, not to CAD files "
                               "(their solids are closed by construction); --shell T applies "
                               "to both")
    if out_format == "csv":
        raise click.UsageError("--format csv is for meshes; use --json for CAD files")
    worst = 0
    try:
        for path in paths:
            worst = max(worst, _inspect_one(ctx, path, out_format, principal, options, unit,
                                            density_map))
    except StdoutClosed:   # the reader of stdout went away (| head): stop, quietly
        silence_stdout()
        return max(worst, 1)
    return worst


def _inspect_one(ctx: click.Context, path: str, out_format: str, principal: bool,
                 options: dict[str, Any], unit: str | None, density_map: str | None) -> int:
    """One CAD file: its exit code (errors reported as one line by ``guarded``)."""
    def run() -> None:
        # the CAD branch of the library: imported only when a CAD file is named
        from massprops.cad.inspect import inspect_cad, load_density_map

        mapping = None if density_map is None else load_density_map(density_map)
        repairs = options.get("repairs")
        result = inspect_cad(path, density=options.get("density"), mass=options.get("mass"),
                             unit=unit, density_map=mapping,
                             allow_open=options.get("allow_open", False),
                             shell=None if repairs is None else repairs.shell)
        try:
            _show(result, out_format, principal)
        except BrokenPipeError as exc:
            raise StdoutClosed from exc

    return guarded(ctx, run)


def _show(result: Any, out_format: str, principal: bool) -> None:
    records = result.as_dicts()
    for record in records:
        for w in record["warnings"]:
            say_warning(f"{record['file']}: {record['path'] or record['solid']}", w)
    if out_format == "json":
        for record in records:
            emit_json(record)
    elif out_format in ELEMENT_FORMATS:
        from massprops.cad.inspect import local_inertial  # CAD branch only
        from massprops.robot.write.elements import WRITERS

        for solid in result.solids:
            com, inertia = local_inertial(solid)
            comment = element_comment(out_format,
                                      f"{result.file.name}: {solid.solid.path} (its own frame)")
            if comment is not None:
                click.echo(comment)
            click.echo(WRITERS[out_format](solid.properties.mass, com, inertia,
                                           principal=principal))
    else:
        for record in records:
            _table(record)


def _table(d: dict) -> None:
    bars = d["uncertainty"]
    title = "total" if d.get("total") else f"{d['path']}"
    click.echo(f"{d['file']}: {title}")
    click.echo(f"  volume            {d['volume']:.12g} m³")
    click.echo(f"  mass              {d['mass']:.12g} kg  (density {d['density']:.6g} kg/m³)")
    click.echo("  center of mass    " + "  ".join(f"{x:.12g}" for x in d["center_of_mass"])
               + " m")
    click.echo("  inertia (COM)     " + "\n                    ".join(
        "  ".join(f"{x: .10e}" for x in row) for row in d["inertia"]) + " kg·m²")
    click.echo("  principal moments " + "  ".join(f"{x:.10e}" for x in d["principal_moments"]))
    if "cad" in d:
        faces = ", ".join(f"{k} {v}" for k, v in d["cad"]["faces"].items())
        click.echo(f"  faces             {faces}; tolerance {d['cad']['tolerance']:.3g} m")
        stated = d["cad"].get("material")
        used = d.get("material", {})
        if stated is not None or used.get("source") not in (None, "default"):
            name = "" if stated is None else f"{stated['name']}; "
            click.echo(f"  material          {name}density from {used.get('source')}")
    for kind in ("rounding", "integration", "input", "repair"):
        bar = bars.get(kind)
        if bar is not None:
            click.echo(f"  ± {kind:<15} volume {bar['volume']:.2g} m³, mass {bar['mass']:.2g} kg")


def align_cad_file(ctx: click.Context, input_path: str, output_path: str, force: bool,
                   as_json: bool, options: dict[str, Any]) -> int:
    """``align IN.step OUT``: the whole moved into its principal frame (exact or tessellated)."""
    unit = options.get("unit")
    if ctx.get_parameter_source("unit") is click.core.ParameterSource.DEFAULT:
        unit = None

    def run() -> None:
        # the CAD branch of the library: imported only when a CAD file is named
        from massprops.cad.inspect import inspect_cad
        from massprops.cad.write import align_cad, cad_output

        check_outputs([(output_path, cad_output())], force=force, inputs=[input_path])
        repairs = options.get("repairs")
        if repairs is not None and (repairs.union or repairs.fill_holes):
            raise click.UsageError("--fill-holes and --union apply to meshes, not to CAD files")
        result = inspect_cad(input_path, density=options.get("density"),
                             mass=options.get("mass"), unit=unit,
                             allow_open=options.get("allow_open", False),
                             shell=None if repairs is None else repairs.shell)
        for record in result.as_dicts():
            for w in record["warnings"]:
                say_warning(f"{record['file']}: {record['path'] or record['solid']}", w)
        aligned = align_cad(result, output_path, force=force)
        if as_json:
            emit_json({"input": input_path, "output": output_path, **aligned.as_dict()})
        else:
            how = "tessellated" if aligned.tessellated else "exact geometry"
            click.echo(f"{input_path} -> {output_path} ({how}): principal moments "
                       + "  ".join(f"{x:.10e}" for x in aligned.principal_moments) + " kg·m²")

    return guarded(ctx, run)
