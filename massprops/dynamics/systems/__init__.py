"""Systems of rigid bodies joined by joints: chains, trees, closed loops (notes' slides 15-16).

Formulation. The joints are split into a spanning tree rooted at ``world`` (a body not joined to
the world gets a free 6-dof joint: a floating base) and cut joints, the rest. Tree joints are
kept exactly by minimal joint coordinates q (a spherical or free rotation as a unit quaternion,
its rates u as an angular velocity, renormalised after each step: no singular chart). In
world-frame spatial vectors the mass matrix comes from the composite-rigid-body algorithm and the
bias from recursive Newton-Euler, so M(q) u̇ + b(q, u) = τ(q, u, t) + Gᵀλ. Cut joints are
constraints Φ(q) = 0 with Jacobian G; the accelerations and multipliers solve the augmented
system (minimum-norm λ where constraints are redundant, found by rank), and after every step the
positions and velocities are projected back onto Φ = 0 and Φ̇ = 0 (Newton, corrections of least
kinetic-energy norm): no Baumgarte gains, no penalties. Reactions are the notes' own
g^(c) = M ḣ + b - g per body, summed over each subtree from the leaves in.

Modules: ``model`` (value objects), ``scene`` (the YAML rules), ``assemble`` (the spanning tree,
cut joints, initial coordinates), ``tree`` (kinematics, CRBA, RNEA), ``loops`` (cut-joint
constraints), ``cutjoint`` (a cut joint measured from its bodies; its spring, damper, drive),
``system`` (accelerations, reactions, projection at the start and the outputs),
``program`` (the system as arrays for the compiled step loop, dynamics/compiled/systems_*),
``integrate`` (that loop's calls: DOP853 with projection and dense output, singular poses),
``outputs`` and ``run`` (simulate a system scene: outputs, diagnostics, error estimate),
``precision``, ``plots``; robot descriptions as systems: ``description`` (links and joints ->
bodies and joints), ``robot_scene`` (``model:`` scenes, ``simulate ROBOT``), ``holding`` (the
static torques). Here numpy, O(n) per tree pass (CRBA O(n·depth)); the step loop is compiled
(ABA for trees, O(n)), and nothing here imports numba itself.
"""
