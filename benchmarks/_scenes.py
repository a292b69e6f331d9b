"""The scenes the benchmarks against scipy run, as scene YAML (massprops' own parser reads them).

Explicit bodies (mass and inertia about the centre of mass), so no mesh file is needed. The
inertia of the torqued and free scenes is not diagonal in the body frame, so massprops' principal
frame (and the scipy model's) is a real rotation of the body frame.
"""

from __future__ import annotations

from dataclasses import dataclass

_TORQUED_BODY = """
body: {mass: 2.0, inertia: [[1.5, 0.3, 0.1], [0.3, 2.0, -0.2], [0.1, -0.2, 2.5]]}
initial:
  position: [0.1, 0.0, 0.2]
  orientation: [0.98006658, 0.0, 0.11920292, 0.15893723]
  velocity: [0.0, 0.3, 0.0]
  angular_velocity: [0.05, -0.03, 2.0]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
  - {type: torque, vector: [0.01, 0.005, 0.02], frame: body}
  - {type: force, vector: [0.05, 0.0, 0.02], frame: world, point: [0.0, 0.05, 0.0]}
  - {type: spring, anchor: [0, 0, 1], stiffness: 6.0}
"""


@dataclass(frozen=True)
class SceneCase:
    """A benchmark scene: title, YAML without its ``time`` section, duration (s), extra ``time``
    keys, and the massprops integrators to run (None: all applicable) with the reason for any
    left out."""

    title: str
    yaml: str
    duration: float
    time_extra: str = ""
    ours: tuple[str, ...] | None = None
    left_out: str = ""

    def text(self, duration: float | None = None) -> str:
        """The whole scene file, lasting ``duration`` s (default: the case's own)."""
        t = self.duration if duration is None else duration
        return f"{self.yaml}time: {{duration: {t!r}{self.time_extra}}}\n"


SCENES: dict[str, SceneCase] = {
    "torqued": SceneCase(
        "torqued asymmetric body, 30 s (gravity, body torque, off-centre force, spring)",
        _TORQUED_BODY, 30.0),
    "free": SceneCase(
        "torque-free asymmetric body spinning under gravity, 20 s (closed form exists)", """
body: {mass: 1.0, inertia: [[1.5, 0.3, 0.1], [0.3, 2.0, -0.2], [0.1, -0.2, 2.5]]}
initial:
  velocity: [1.0, 0.0, 5.0]
  angular_velocity: [1.0, 0.5, 3.0]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
""", 20.0),
    "stiff": SceneCase(
        "stiff overdamped spring-damper (k = c = 1e4, rates 1/s and 1e4/s) on a spinning "
        "body, 2 s", """
body: {mass: 1.0, inertia: [[0.02, 0, 0], [0, 0.03, 0], [0, 0, 0.04]]}
initial:
  position: [0.05, 0.0, -0.3]
  angular_velocity: [0.5, 0.0, 5.0]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
  - {type: spring, anchor: [0, 0, 0], point: [0, 0, 0.1], stiffness: 10000.0,
     damping: 10000.0}
""", 2.0, ours=("rk4", "dop853", "implicit", "midpoint"),
        left_out="splitting, splitting4, splitting6 left out: explicit force kicks at the "
                 "stability limit, their ladders take ~3.5 min of 1.6e6-step runs here"),
}
"""The work-precision scenes of bench_precision.py."""

LONG_DRAG = SceneCase(
    "fast-spinning torqued body with drag, 1000 s (spin driven to 20 rad/s, 2e4 rad turned)", """
body: {mass: 2.0, inertia: [[1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0]]}
initial:
  position: [0.1, 0.0, 0.2]
  orientation: [0.98006658, 0.0, 0.11920292, 0.15893723]
  velocity: [0.0, 0.3, 0.0]
  angular_velocity: [0.5, -0.3, 20.0]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
  - {type: torque, vector: [0.05, 0.02, 2.0], frame: body}
  - {type: force, vector: [0.5, 0.0, 0.2], frame: world, point: [0.0, 0.05, 0.0]}
  - {type: spring, anchor: [0, 0, 1], stiffness: 6.0}
  - {type: drag, linear: 0.05, angular: 0.1}
""", 1000.0, time_extra=", integrator: dop853, rtol: 1.0e-10")
"""bench_simulate.py (b): the whole-process race (scipy's DOP853 needs ~4e5 evaluations)."""
