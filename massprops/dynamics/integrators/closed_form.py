"""``exact``: the torque-free body in closed form (massprops.dynamics.exact), as a registry entry.

It applies when no term makes a torque and every force is constant in world, so the caller passes
the rotation-only layout [q, omega'] and moves the centre of mass in closed form itself. Each
output time is evaluated directly from the segment's start: no steps, no truncation error, cost
independent of t (the error is round-off, ~1e-14 at |omega| t = 100). A body held at a fixed
point is the same free body about that point (massprops.dynamics.joints); a heavy symmetric top
(the program's JOINT row says so) goes to its own closed form, joints/lagrange.py.
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.exact import free_rotation
from massprops.dynamics.forces import JOINT
from massprops.dynamics.integrators.base import IntegratorSpec, check_arrays
from massprops.errors import UsageError


def run_segment(y, t0, t1, setting, program_arrays, rot_only, t_out, y_out, stats):
    """The contract's run_segment for the rotation-only layout; err is 0 (no truncation)."""
    check_arrays("exact", y, float(t0), float(t1), bool(rot_only), t_out, y_out, stats)
    if not rot_only:
        raise UsageError("integrator exact: needs the rotation-only state of a torque-free "
                         f"scene with constant forces, got a state of shape {y.shape}")
    inertia = program_arrays[4]
    codes, params = program_arrays[1], program_arrays[2]
    if codes.size and codes[-1] == JOINT and params[-1, 1] != 0.0:  # a heavy symmetric top
        # deferred: only a heavy symmetric top needs the Lagrange top's closed form
        from massprops.dynamics.joints.lagrange import run_segment as lagrange_segment

        return lagrange_segment(y, t0, t1, program_arrays, t_out, y_out)
    times = np.append(np.asarray(t_out, dtype=np.float64) - t0, t1 - t0)
    q, w = free_rotation(inertia, y[0:4], y[4:7], times)
    y_out[:, 0:4], y_out[:, 4:7] = q[:-1], w[:-1]
    y[0:4], y[4:7] = q[-1], w[-1]
    return 0.0, float(t1)


SPEC = IntegratorSpec(
    name="exact", kind="exact", order=0, run_segment=run_segment,
    description="closed-form torque-free rotation and ballistic translation; no time steps")
