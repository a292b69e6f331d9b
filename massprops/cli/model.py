"""``massprops model``: the inertials of a robot description's links against their geometry."""

from __future__ import annotations

import click

from massprops.cli.app import cli
from massprops.cli.common import emit_json, guarded, non_negative, positive, say_error, say_warning


@cli.command()
@click.argument("description", metavar="FILE")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per link, one per line.")
@click.option("--check", "rtol", type=float, default=None, metavar="RTOL",
              callback=non_negative,
              help="Exit 4 if any link's stated inertial differs from its geometry by more than "
                   "RTOL (mass, COM / link size, inertia in the 2-norm; all relative).")
@click.option("--write", "output_path", default=None, metavar="OUT",
              help="Write the description with the computed inertials (never over FILE).")
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never FILE).")
@click.option("--from", "source", type=click.Choice(("collision", "visual")),
              default="collision", show_default=True, help="Which geometry makes the link.")
@click.option("--density", type=float, callback=positive,
              help="Density in kg/m³ for every geometry (default: keep each stated mass).")
@click.option("--package-path", "package_paths", multiple=True, metavar="DIR",
              help="Folder holding packages for package:// and model:// (repeatable; "
                   "ROS_PACKAGE_PATH is searched too).")
@click.option("--allow-open", is_flag=True, help="Compute open meshes anyway (with warnings).")
@click.pass_context
def model(ctx: click.Context, description: str, as_json: bool, rtol: float | None,
          output_path: str | None, force: bool, source: str, density: float | None,
          package_paths: tuple[str, ...], allow_open: bool) -> None:
    """Inertials of every link of a robot description (URDF, SDF or MJCF FILE) from its meshes
    and primitives, against the inertials it states."""
    link_errors = []

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.robot.analyze import analyze_model

        report = analyze_model(description, source=source, density=density,
                               package_paths=package_paths, allow_open=allow_open)
        for w in report.model.warnings:
            say_warning(description, w)
        for line in report.errors:
            say_error(line)
        link_errors.extend(report.errors)
        if as_json:
            for r in report.links:
                emit_json(r.as_dict(description))
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_model

            print_model(report, rtol)
        if output_path is not None:
            report.write(output_path, force=force)
        if rtol is not None:
            report.require_agreement(rtol)

    code = guarded(ctx, run)
    ctx.exit(max(code, 1 if link_errors else 0))
