"""A link's inertial from its geometries (closed forms and the exact mesh integral), compared
with the stated one; a simulator compiler's mass rules."""
