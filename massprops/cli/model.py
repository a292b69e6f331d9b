"""``massprops model``: the inertials of a robot description's links against their geometry."""

from __future__ import annotations

import click

from massprops.cli.app import cli
from massprops.cli.common import (
    check_outputs,
    emit_json,
    guarded,
    non_negative,
    positive,
    repair_flags,
    repair_options,
    robot_file_options,
    say_error,
    say_note,
    say_warning,
)


@cli.command()
@click.argument("description", metavar="FILE")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per link, one per line.")
@click.option("--check", "rtol", type=float, default=None, metavar="RTOL",
              callback=non_negative,
              help="Exit 4 if any link's stated inertial differs from its geometry by more than "
                   "RTOL (mass, COM / link size, inertia in the 2-norm; all relative).")
@click.option("--write", "output_path", default=None, metavar="OUT",
              help="Write the description with the inertials that are off replaced by the "
                   "computed ones (missing, invalid, or off by more than --check RTOL, default "
                   "1e-12); every other byte as in FILE (never over FILE).")
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never FILE).")
@click.option("--keep-mass", is_flag=True,
              help="With --write: keep each stated mass, with the geometry's distribution "
                   "(COM, and the tensor scaled to that mass).")
@click.option("--only-invalid", is_flag=True,
              help="With --write: replace only the inertials that fail a validity test.")
@click.option("--from", "source", type=click.Choice(("collision", "visual")), default=None,
              help="Which geometry makes every link (default: collision, or visual for a link "
                   "with no collision geometry, noted as source: visual).")
@click.option("--density", type=float, callback=positive,
              help="Density in kg/m³ for every geometry (default: keep each stated mass).")
@robot_file_options
@click.option("--allow-open", is_flag=True, help="Compute open meshes anyway (with warnings).")
@repair_flags
@click.pass_context
def model(ctx: click.Context, description: str, as_json: bool, rtol: float | None,
          output_path: str | None, force: bool, keep_mass: bool, only_invalid: bool,
          source: str | None, density: float | None,
          package_paths: tuple[str, ...], allow_open: bool, fill_holes: bool,
          max_hole: float | None, union: bool, shell: float | None,
          xacro_args: dict[str, str]) -> None:
    """Inertials of every link of a robot description (URDF, SDF, MJCF or .xacro FILE) from its
    meshes and primitives, against the inertials it states. Repairs apply to each mesh."""
    link_errors = []
    repairs = repair_options(fill_holes, max_hole, union, shell)

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.errors import UsageError, setting_ref
        from massprops.robot.analyze import analyze_model
        from massprops.robot.write.writeback import description_output

        for flag, on in (("keep_mass", keep_mass), ("only_invalid", only_invalid)):
            if on and output_path is None:
                raise UsageError(f"{setting_ref(flag)} changes what {setting_ref('write')} "
                                 f"writes; give {setting_ref('write')} OUT")

        check_outputs([(output_path, description_output(description))], force=force,
                      inputs=[description])

        report = analyze_model(description, source=source or "auto", density=density,
                               package_paths=package_paths, allow_open=allow_open,
                               xacro_args=xacro_args, repairs=repairs, check=rtol)
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
            changes = report.write(output_path, force=force, rtol=rtol, keep_mass=keep_mass,
                                   only_invalid=only_invalid)
            say_note(_rewritten(output_path, tuple(c.link for c in changes), report, rtol,
                                only_invalid))
            for c in changes:
                say_note(f"  {c.phrase()}")
        if rtol is not None:
            report.require_agreement(rtol)

    code = guarded(ctx, run)
    ctx.exit(max(code, 1 if link_errors else 0))


def _rewritten(output_path: str, written: tuple[str, ...], report, rtol: float | None,
               only_invalid: bool = False) -> str:
    """The note --write leaves on stderr: which links' inertials OUT has new (each link's
    changes follow, one note each)."""
    from massprops.tolerances import WRITE_KEEP_RTOL  # the default, said with the note

    computed = sum(r.computed is not None for r in report.links)
    within = ("valid (--only-invalid)" if only_invalid else
              f"within {WRITE_KEEP_RTOL if rtol is None else rtol:g} of the geometry")
    if not written:
        return (f"wrote {output_path}: every computed inertial "
                f"{'is' if only_invalid else 'agrees'} {within}; none rewritten")
    kept = computed - len(written)
    return (f"wrote {output_path}: rewrote the inertial of {', '.join(written)} "
            f"({len(written)} of {computed} computed link(s)"
            + (f"; the other {kept} {'are' if only_invalid else 'agree'} {within} and are kept)"
               if kept else ")"))
