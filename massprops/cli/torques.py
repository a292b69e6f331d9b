"""``massprops torques``: each motor's torque and power along a motion (`massprops.torques`)."""

from __future__ import annotations

import json
from typing import Any

import click

from massprops.cli.app import cli
from massprops.cli.common import emit_json, guarded, robot_file_options, say_notes, say_warning


def _margin(ctx: click.Context, param: click.Parameter, value: str | None) -> float:
    if value is None:
        return 0.0
    text = value.strip()
    try:
        number = float(text[:-1]) / 100 if text.endswith("%") else float(text)
    except ValueError:
        raise click.BadParameter(f"expected a fraction or a percentage such as 20%, got "
                                 f"{value!r}") from None
    if not 0 <= number < 1:
        raise click.BadParameter(f"must be in [0, 100%), got {value!r}")
    return number


@cli.command()
@click.argument("robot_path", metavar="ROBOT|SCENE")
@click.argument("motion_path", metavar="MOTION.csv", required=False)
@click.option("--json", "as_json", is_flag=True,
              help="JSON lines: one object per sample, then the summary.")
@click.option("--format", "out_format", type=click.Choice(["csv", "json"]), default=None,
              help="Each sample's torques and powers as CSV (summary on stderr), or JSON lines.")
@click.option("--check", is_flag=True,
              help="Exit 4 when a motor's peak exceeds its effort limit or a joint's rate its "
                   "velocity limit (URDF <limit effort velocity>, SDF <effort> <velocity>), "
                   "naming the joint, the time and the margin.")
@click.option("--margin", callback=_margin, default=None, metavar="P",
              help="With --check: the headroom asked for, e.g. 20% (the peak must stay below "
                   "80 % of the limit).")
@click.option("--inertials", type=click.Choice(["stated", "computed"]), default=None,
              help="A description's inertials: as stated (default) or computed from its "
                   "geometry, as `massprops model` computes them.")
@click.option("--bars", is_flag=True,
              help="Widen each sample's bar by the spread between the stated and the computed "
                   "inertials' torques (a description's own disagreement).")
@robot_file_options
@click.pass_context
def torques(ctx: click.Context, robot_path: str, motion_path: str | None, as_json: bool,
            out_format: str | None, check: bool, margin: float, inertials: str | None,
            bars: bool, package_paths: tuple[str, ...], xacro_args: dict[str, str]) -> None:
    """Inverse dynamics along a motion: each motor's torque (or force) and power, each joint's
    reaction, per sample of MOTION.csv (t and one column per joint), for a robot description or
    a system scene; a summary per motor (peak, RMS, peak power, energy, limit)."""
    if as_json and out_format == "csv":
        raise click.UsageError("--json and --format csv contradict; give one")
    if motion_path is None:
        raise click.UsageError("give MOTION.csv (t and one column per joint coordinate); a "
                               "scene's motion: is not read yet")
    fmt = "json" if as_json else out_format

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.torques import (
            load_robot,
            raise_if_failed,
            read_motion,
            torques_along,
            warnings,
            with_inertials_spread,
        )

        def robot(which: str | None) -> Any:
            return load_robot(robot_path, inertials=which, package_paths=package_paths,
                              xacro_args=xacro_args)

        scene = robot(inertials)
        for w in warnings(scene):
            say_warning(robot_path, w)
        motion = read_motion(motion_path)
        result = torques_along(scene, motion, check=check, margin=margin)
        if bars:
            other = "stated" if inertials == "computed" else "computed"
            result = with_inertials_spread(result, torques_along(robot(other), motion))
        say_notes(result.notes)
        if fmt == "json":
            for row in result.rows:
                emit_json(row)
            emit_json(result.summary)
        elif fmt == "csv":
            _csv(result)
            click.echo(json.dumps(result.summary), err=True)
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_torques

            print_torques(robot_path, motion_path, result)
        raise_if_failed(result)

    ctx.exit(guarded(ctx, run))


def _csv(result: Any) -> None:
    names = list(result.rows[0]["joints"]) if result.rows else []
    click.echo(",".join(["t", *(f"{n}.{q}" for n in names for q in ("torque", "power"))]))
    for row in result.rows:
        cells = [repr(row["t"])]
        for n in names:
            cells += [repr(row["joints"][n]["torque"][0]), repr(row["joints"][n]["power"][0])]
        click.echo(",".join(cells))
