"""A scene of either kind, decided once: the one body of a ``body:`` scene, or a system (a
``bodies:`` or ``model:`` scene, or a robot description given directly). `load` reads the file
and decides; `simulate`, `precision`, `write_trajectory` and `plot` take what it gave and call
the package that runs that kind (`dynamics.simulate` or `dynamics.systems`). The CLI and the
library's front door (`massprops.api`) go through here, so neither tells the kinds apart.

Each kind's modules are imported only when a scene of that kind is run: a one-body closed form
never imports the systems engine or numba.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, cast

if TYPE_CHECKING:
    from massprops.dynamics.model import Scene
    from massprops.dynamics.precision import PrecisionReport
    from massprops.dynamics.simulate import SimulationResult
    from massprops.dynamics.systems.model import SystemScene
    from massprops.dynamics.systems.run import SystemResult

    AnyScene = Scene | SystemScene
    AnyResult = SimulationResult | SystemResult


def load(path: str | os.PathLike, duration: float | None = None, *,
         package_paths: Sequence[str | os.PathLike] = (),
         xacro_args: Mapping[str, str] | None = None) -> AnyScene:
    """The scene at ``path`` (docs/interface.md, docs/systems.md): a `SystemScene` for a
    system file or a robot description (``package_paths``, ``xacro_args``: its packages and
    xacro arguments), else a one-body `Scene`; run for ``duration`` s where given. SceneError,
    RobotModelError (one line); UsageError for a one-body scene with duration 0 (the start
    pose's reactions are a system's) or description settings with a scene file."""
    # deferred: start-up (the sniffing is light; each kind's reader is not)
    from massprops.dynamics.systems.robot_scene import (
        check_description_settings,
        is_system_file,
        load_any_system,
    )

    check_description_settings(path, package_paths, xacro_args)
    if is_system_file(path):
        return load_any_system(path, duration, package_paths=package_paths,
                               xacro_args=xacro_args)
    from massprops.dynamics.scene import load_scene  # deferred: the one-body reader

    scene = load_scene(path)
    if duration is None:
        return scene
    if duration <= 0:
        from massprops.errors import UsageError, setting_ref  # deferred: rare path

        raise UsageError(f"{path}: {setting_ref('duration')} 0 gives a system's start pose "
                         "reactions; a one-body scene needs a duration > 0")
    return dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=duration))


def parse(text: str, *, source: str, base_dir: str | os.PathLike) -> AnyScene:
    """A scene file's text, of either kind (``source`` names it in messages; ``base_dir`` is
    where its relative paths start): what `load` gives for the file. SceneError,
    RobotModelError (one line)."""
    from massprops.dynamics.systems.scene import is_system_text  # deferred: a line scan

    if is_system_text(text):
        from massprops.dynamics.systems.robot_scene import parse_any_system  # deferred

        return parse_any_system(text, source=source, base_dir=Path(base_dir))
    from massprops.dynamics.scene import parse_scene  # deferred: the one-body reader

    return parse_scene(text, source=source, base_dir=Path(base_dir))


def is_system(scene: AnyScene) -> bool:
    """``scene`` is a system's (`load` gave a `SystemScene`)."""
    return _system(scene) is not None


def _system(scene: AnyScene) -> SystemScene | None:
    """``scene`` as a `SystemScene`, or None for one body's."""
    from massprops.dynamics.systems.model import SystemScene  # deferred: light, numpy only

    return scene if isinstance(scene, SystemScene) else None


def warnings(scene: AnyScene, path: str) -> list[tuple[str, str]]:
    """(file, text) of each warning reading ``scene`` gave: a one-body scene's are its mesh's
    (named by it), a system's its scene file's, ``path`` as the caller named it."""
    source = path if is_system(scene) else cast("Scene", scene).body_source
    return [(source, w) for w in scene.warnings]


def _of_system(result: AnyResult) -> bool:
    """``result`` is a system run's: its samples are per body and joint (a one-body result's
    are its ``trajectory``). Told by that attribute, so that a one-body run's caller never
    imports the systems engine to ask."""
    return hasattr(result, "samples")


def simulate(scene: AnyScene, *, integrator: str | None = None, rtol: float | None = None,
             step: float | None = None, every: float | None = None,
             max_steps: int | None = None, progress: Callable[[float], None] | None = None,
             notice: Callable[[str], None] | None = None, estimate: bool = True,
             interruptible: bool = False) -> AnyResult:
    """Run ``scene`` (options as for `dynamics.simulate.simulate`): a `SimulationResult` for
    one body, a `SystemResult` for a system, each with ``as_dict()`` the contract's JSON.
    Ctrl-C returns what was computed with ``interrupted`` set where ``interruptible`` (a
    one-body run always does); failures raise with the samples computed in ``partial``."""
    system = _system(scene)
    if system is not None:
        from massprops.dynamics.systems.run import simulate_system  # deferred: the systems

        return simulate_system(system, integrator=integrator, rtol=rtol, step=step, every=every,
                               max_steps=max_steps, progress=progress, notice=notice,
                               estimate=estimate, interruptible=interruptible)
    from massprops.dynamics.simulate import simulate as simulate_body  # deferred: one body

    return simulate_body(cast("Scene", scene), integrator=integrator, rtol=rtol, step=step,
                         every=every, max_steps=max_steps, progress=progress, notice=notice,
                         estimate=estimate)


def precision(scene: AnyScene, *, integrators: Sequence[str] | None = None,
              progress: Callable[[float], None] | None = None,
              notice: Callable[[str], None] | None = None) -> PrecisionReport:
    """Error against run time of ``scene``'s methods (`dynamics.precision`, or the systems'
    ladders `dynamics.systems.precision`)."""
    system = _system(scene)
    if system is not None:
        from massprops.dynamics.systems.precision import precision_system  # deferred

        return precision_system(system, integrators=integrators, progress=progress,
                                notice=notice)
    from massprops.dynamics.precision import precision as precision_body  # deferred

    return precision_body(cast("Scene", scene), integrators=integrators, progress=progress,
                          notice=notice)


def sample_count(result: AnyResult) -> int:
    """How many samples ``result`` holds (a failed run's part may hold none)."""
    if _of_system(result):
        return len(cast("SystemResult", result).samples.t)
    return len(cast("SimulationResult", result).trajectory.t)


def write_trajectory(result: AnyResult, path: str | Path, *, force: bool = False,
                     protect: Sequence = ()) -> None:
    """``result``'s samples as a CSV or NPZ trajectory (docs/interface.md; atomically, never
    over a file in ``protect``, nor over an existing one unless ``force``)."""
    if _of_system(result):
        from massprops.dynamics.systems.run import write_system_trajectory  # deferred

        write_system_trajectory(cast("SystemResult", result), path, force=force,
                                protect=protect)
        return
    from massprops.dynamics.trajectory import write_trajectory as write_body  # deferred

    write_body(cast("SimulationResult", result).trajectory, path, force=force, protect=protect)


def plot(result: AnyResult, path: str | Path, *, force: bool = False,
         protect: Sequence = ()) -> None:
    """``result`` drawn as a PNG (the plot extra): a body's rates, energy and momentum drift;
    a system's mechanism and joints."""
    if _of_system(result):
        from massprops.dynamics.systems.plots import plot_system  # deferred: matplotlib

        plot_system(result, path, force=force, protect=protect)
        return
    from massprops.dynamics.plots import plot_simulation  # deferred: matplotlib

    plot_simulation(result, path, force=force, protect=protect)
