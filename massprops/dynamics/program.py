"""A scene's force program and initial state, whatever holds its body: the entry every run uses.

A free body's come from `forces` and `frames`; a body held by joints is stepped as its equivalent
pinned body (`joints.reduction`), which is built from those same two modules. The choice lives
here, above all three, so that none of them imports another upward.
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.forces import ForceProgram, compile_free_forces
from massprops.dynamics.frames import initial_free_state
from massprops.dynamics.joints.reduction import compile_held, model_of
from massprops.dynamics.model import Scene


def compile_forces(scene: Scene) -> ForceProgram:
    """The scene's `ForceProgram` (one row per force term, in scene order); a body held by
    joints gets the program of its equivalent pinned body (`massprops.dynamics.joints`)."""
    return compile_held(scene) if scene.joints else compile_free_forces(scene)


def initial_principal_state(scene: Scene) -> np.ndarray:
    """(13,) [r, v, q_p, omega'] at t = 0 from the scene's world/body initial values (a body
    held by joints: of its equivalent pinned body)."""
    return model_of(scene).y0.copy() if scene.joints else initial_free_state(scene)
