"""The torques a motion takes (``massprops torques ROBOT MOTION.csv``): the notes' equation
M ḣ + b = g read the other way, along a given motion of a robot description or a system scene,
closed loops included.

- `motion`: the motion from a CSV, rates and accelerations from a quintic spline, and the
  spline's own error;
- `along`: inverse dynamics at every sample (each motor's force and power, each joint's
  reaction), the summary per motor, and the check against the description's effort limits.

The library prints nothing; ``cli/torques.py`` renders.
"""

from massprops.torques.along import (
    Torques,
    load_robot,
    raise_if_failed,
    torques_along,
    warnings,
    with_inertials_spread,
)
from massprops.torques.motion import Motion, read_motion

__all__ = ["Motion", "Torques", "load_robot", "raise_if_failed", "read_motion", "torques_along",
           "warnings", "with_inertials_spread"]
