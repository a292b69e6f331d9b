"""Newton-Euler dynamics: scenes, force programs, integrators, exact solutions, joints.

    scene, yamlnodes, model   the scene file -> `Scene` (validated, lines kept for messages)
    program                   a scene's force program and initial state (free or held body)
    forces, frames            the force table and compiled right-hand side; frames at the edges
    integrators/              the registry and one module per method; compiled/ makes them code
    exact, elliptic           the torque-free body in closed form
    joints/                   bodies held by joints: the equivalent pinned body, reactions
    simulate, runner, budget  choosing a method, running it, the run bound
    accuracy, stiffness       the error metric and the global error estimate
    precision                 error against run time, integrator by integrator
    trajectory, plots         output files and figures

Importing the package imports nothing and changes nothing: numba is imported only by a stepping
integrator (`compiled.jit`), and where its kernels cache is decided when one is first loaded
(`compiled.cache`), without touching numba's settings or the environment.
"""
