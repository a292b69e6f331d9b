"""Every numeric tolerance of massprops, each with the reason for its value."""

from __future__ import annotations

import numpy as np

EPS = float(np.finfo(np.float64).eps)
"""2.22e-16: float64 unit round-off is EPS/2."""

EPS32 = float(np.finfo(np.float32).eps)
"""1.19e-7: float32 machine epsilon; half of it is the relative rounding of a float32 coordinate."""

DEGENERATE_MOMENT_RTOL = 1e-9
"""Two principal moments closer than this (relative to the largest) are treated as equal, so the
axes of that eigenspace are chosen by rule instead of by LAPACK. Round-off in the integral is
~1e-15 of the largest moment, six orders below, so two meshes that differ by round-off never fall
on different sides; a real part whose moments differ by less than 1e-9 is, to any measurement,
rotationally symmetric."""

AXIS_SIGN_TIE_ATOL = 1e-9
"""Components of a principal axis whose magnitudes differ by less than this count as tied for the
sign rule (largest component positive); the first of the tied ones decides, so round-off does not
flip an axis like [0.7071, -0.7071, 0]."""

MIN_VOLUME_TO_ERROR = 100.0
"""A mesh whose |volume| is not at least this many times its own rounding-error bound encloses
nothing we can resolve (flat, or inside-out halves cancelling) and is refused as degenerate,
rather than reported as 0, a random sign or NaN. A bound-based test, unlike a fraction of the
bounding box, accepts a needle of aspect 1e-6 lying along the box diagonal."""

JOINT_RTOL = 1e-9
"""How far a scene's joint geometry and initial state may miss the joints and still count as
consistent: positions relative to the body size, angles in rad, velocities relative to their
scale. Scene files carry ~10-17 digits, so a state typed from a closed form (sqrt(3)/2 written
with 10 digits) passes, while any real mistake (a sign, a swapped axis, a metre off) fails with
a message giving the consistent value. What passes is projected silently: the run always starts
exactly on the joints."""
