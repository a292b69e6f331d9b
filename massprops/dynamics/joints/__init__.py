"""Bodies held to the world by joints: a top or gyroscope on its tip (spherical), a pendulum,
door or rotor on a hinge (revolute, or two spherical joints on a line), and the reaction forces
the joints carry.

How joints enter the equations. The notes' constrained form, M ḣ + b = g + Φ_qᵀλ with
Φ(q) = 0, is solved here in reduced coordinates, which keep the constraint exactly (nothing to
project, nothing to tune): a body turning about a fixed point P is a free body whose "centre of
mass" is P, with the inertia J_P about P (parallel-axis theorem) and the same forces at the same
body points, whose total force the joint cancels. ``reduction`` rewrites a held scene into that
equivalent pinned body (for a hinge, with the isotropic inertia I_axis about it and the torque
across its axis removed) plus one force-table row, JOINT, so every integrator of the registry
steps it unchanged; ``edges`` turns the pinned body's states back into the body's own, and
computes the reactions λ as physical quantities (the joint's force m·a_com - Σf at its point, a
hinge's couple across its axis) and the diagnostics. ``lagrange`` is the heavy symmetric top in
closed form, which ``exact`` uses and ``auto`` picks. ``hold`` says which joint sets are
supported and checks the initial state against them; ``scene`` reads the ``joints:`` list;
``model`` holds the value objects. DESIGN.md ("Joints") has the conventions: frames, signs.

Importing this package imports numpy only; the compiled pieces load where they are used.
"""

from massprops.dynamics.joints.model import Joint, RevoluteJoint, SphericalJoint

__all__ = ["Joint", "RevoluteJoint", "SphericalJoint"]
