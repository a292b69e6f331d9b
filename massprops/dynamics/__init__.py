"""Newton-Euler dynamics of one rigid body: scene, forces, integrators, exact solutions."""
