"""The inertia doctor: whether a link's inertial is one a body can have, and why a stated
inertial differs from the one its geometry gives.

- `bounds`: the link geometry's convex hull and an ellipsoid around it, in the link frame;
- `validity`: the four tests of an inertial (positive definite, triangle inequalities, COM
  inside the hull, density realizability inside the ellipsoid: Wensing, Kim & Slotine 2017);
- `frames`: causes of a tensor written in the wrong frame (``about_point``, ``rotated``,
  ``axes_permuted``);
- `writing`: causes of numbers written wrong (``length_unit``, ``mass_unit``,
  ``product_sign``, ``decimal_slip``, ``placeholder``);
- `shapes`: causes of another shape integrated (``bounding_box``, ``convex_hull``,
  ``thin_shell``, ``mujoco_legacy``, ``other_geometry``);
- `diagnose`: the search over causes and their compositions, the residual they leave.

Frames: link frame, SI units, inertia about the centre of mass (as `massprops.robot.model`).
"""
