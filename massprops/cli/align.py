"""``massprops align``: the mesh moved into its principal frame, written atomically."""

from __future__ import annotations

from typing import Any

import click

from massprops.cli.app import cli
from massprops.cli.common import emit_json, guarded, inspect_kwargs, mass_options, say_warning


@cli.command()
@click.argument("input_path", metavar="IN")
@click.argument("output_path", metavar="OUT")
@mass_options
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never IN).")
@click.option("--json", "as_json", is_flag=True, help="Print the applied map as JSON.")
@click.pass_context
def align(ctx: click.Context, input_path: str, output_path: str, force: bool, as_json: bool,
          **mesh_options: Any) -> None:
    """Write OUT: the mesh IN moved into its principal frame (COM at the origin, axes along the
    principal axes, ascending moments). Faces and winding are unchanged; with --union OUT is
    the united mesh, with --fill-holes the capped one."""
    options = inspect_kwargs(mesh_options)
    from massprops.cad import is_cad_path  # no OpenCASCADE: extensions only

    if is_cad_path(input_path):
        from massprops.cli.cad import align_cad_file  # the CAD branch, CAD inputs only

        ctx.exit(align_cad_file(ctx, input_path, output_path, force, as_json, options))

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.inspection.align import align_mesh
        from massprops.inspection.file import inspect_file
        from massprops.io import write_mesh
        from massprops.io.dispatch import check_mesh_output

        check_mesh_output(output_path, force=force, protect=(input_path,))  # before any work
        result = inspect_file(input_path, **options)
        for w in result.warnings:
            say_warning(result.mesh.name, w)
        aligned = align_mesh(result.mesh, result.properties)
        write_mesh(aligned.mesh, output_path, force=force, protect=(input_path,))
        if as_json:
            repairs = result.repairs_as_dict()
            emit_json({"input": input_path, "output": output_path, **aligned.as_dict(),
                       **({} if repairs is None else {"repairs": repairs})})
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_alignment

            print_alignment(input_path, output_path, aligned, result.repairs)

    ctx.exit(guarded(ctx, run))
