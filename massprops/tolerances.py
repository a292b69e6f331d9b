"""Every numeric tolerance of massprops, each with the reason for its value.

One exception, by design: the constants compiled into the dynamics kernels (Newton's stopping
rule, the elliptic functions' and the exact solution's thresholds) stay in the module that
compiles them, each saying so, because the kernels' cache is keyed by the dynamics package's own
sources (`massprops.dynamics.compiled.cache`): a value here would not invalidate machine code
compiled with its old value."""

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

NEAR_WELD_ULPS = 8
"""Round-off cracks: when a mesh is open, the vertices at its open edges whose coordinates differ
by at most this many units of round-off of the file's largest |coordinate| (float64 eps, or
float32 eps for binary STL, times that coordinate) are one vertex. CAD and asset exporters compute
each copy of a shared corner separately (in the assembly's frame, then transformed), and the
copies differ in their last bits: seen 1.4 and 0.3 ulps of the largest coordinate on public
robot parts. Eight ulps welds those and nothing a modeller could have meant: a real feature of a
part is many orders above 1e-15 of its coordinates, and trimesh's fixed 1e-8 m is a guess that
merges real features of a small part and misses the cracks of a large one. The weld is bounded
too: only groups no wider than the tolerance are welded, and only if that leaves no open edge."""

INERTIA_VALIDITY_RTOL = 1e-12
"""A stated or computed inertial counts as physically valid when its tensor is symmetric, its
smallest principal moment is positive, and each principal moment is at most the sum of the other
two, each within this fraction of the largest moment (`robot.doctor.validity`; the
realizability trace within this fraction of the mass). It is round-off: each shift by the
parallel-axis rule or turn of the axes adds ~eps (|d|/size)² of the largest moment, so a tensor
on the triangle's edge (a thin plate, I3 = I1 + I2) shifted to points a body length away and
turned a few times stays within 1e-13 (tested, `tests/test_robot_doctor_valid.py`); a tensor
rounded to ~12 digits by another tool is within 1e-12; a placeholder that breaks it does so by
percent."""

COM_INSIDE_RTOL = 1e-9
"""A centre of mass counts as inside the link geometry's convex hull when it is at most this
fraction of the link's size outside a facet: the hull's facet planes carry ~1e-15 of the size of
round-off and the geometry's poses another few ulps; a COM really outside is outside by the
geometry's own dimensions."""

SHELL_LIMIT_THICKNESS = 1e-4
"""A surface that carries its mass (MuJoCo's ``inertia="shell"``, the doctor's ``thin_shell``)
is integrated as a ``--shell`` wall this fraction of the mesh's size thick, then divided by the
thickness: the through-thickness and mitre terms are O(thickness²) = 1e-8 of the moments
(measured 4e-8 against MuJoCo's own shell inertia), far below every tolerance they meet."""

DIAGNOSIS_RTOL = 1e-4
"""The inertia doctor names a cause only when the model it makes of the stated inertial leaves at
most this relative difference (measured as ``--check`` measures). Descriptions print five to
eight significant digits (rounding ≤ 5e-6 of each number) and meshes exported twice differ by
~1e-6; the causes themselves move the numbers by percent or by factors (a unit is 1e3 to 1e6, a
bounding box or a hull percent), so 1e-4 separates them from rounding with room on both sides."""

WRITE_KEEP_RTOL = 1e-12
"""``model --write`` without ``--check``: a stated inertial within this of the computed one
(relative, as ``--check`` measures: mass, COM / link size, inertia in the 2-norm) is kept byte
for byte; only the others are rewritten. 1e-12 is round-off, of the integral (~1e-15) and of
printing (repr reads back exact, 12 digits within 5e-13): an inertial massprops wrote is kept,
so a second ``--write`` changes nothing and ``--check 1e-12`` passes after ``--write``. With
``--check RTOL`` the check's own tolerance decides instead (1e-6 keeps values printed to six
digits)."""

MAX_HOLE_AREA_FRACTION = 0.1
"""``--fill-holes`` caps a boundary loop only if its cap is at most this fraction of the surface
area (``--max-hole`` overrides). Holes from scanning and export are small (well under 1 % of the
surface); a loop whose cap would be a tenth of the part is an opening (a cup, a bowl, a pipe's
end) or a missing face that the user should decide about: capping it would be a guess about a
large part of the boundary. A cube missing one face (a fifth of what remains) needs the override."""

HOLE_CREASE_ANGLE_DEG = 45.0
"""A face on a hole's rim tilted less than this from the cap's plane continues the surface across
the hole (a hole in a curved patch): the reasonable caps then include a dome continuing its slope,
and the error bar covers it. A steeper face meets the hole at a crease (the cube missing a face:
90°), where the surface turns rather than continues, and adds no dome."""

SHELL_WARN_FRACTION = 0.01
"""``--shell`` warns when the thin-wall model's error bound exceeds this fraction of the mass or
of a principal moment: the wall is thick against the surface's curvature or its facets (or the
thickness was given in the file's unit instead of metres)."""

RIM_NORMAL_RTOL = 1e-9
"""A hole's rim whose vector area (Newell) is below this fraction of its points' spread
Σ|p - c|² has no reliable normal (a figure of eight, a rim folded onto itself); its best-fit
plane is then the direction of least spread. Round-off in the vector area is ~1e-16 of that
spread, seven orders below; a real rim that flat is a sliver with no sensible cap plane anyway."""

JOINT_RTOL = 1e-9
"""How far a scene's joint geometry and initial state may miss the joints and still count as
consistent: positions relative to the body size, angles in rad, velocities relative to their
scale. Scene files carry ~10-17 digits, so a state typed from a closed form (sqrt(3)/2 written
with 10 digits) passes, while any real mistake (a sign, a swapped axis, a metre off) fails with
a message giving the consistent value. What passes is projected silently: the run always starts
exactly on the joints."""

QUATERNION_UNIT_RTOL = 1e-9
"""A scene's quaternion whose norm misses 1 by less than this is normalised silently: one typed
from cos and sin values with 10 digits misses by ~1e-10. A larger miss ([2, 0, 0, 0], a slipped
digit) is normalised too, but said: the scene may not mean the rotation it now gets."""

RTOL_FLOOR = 1e-15
"""The smallest relative tolerance an adaptive run accepts (time.rtol, --rtol). A step's result
is rounded to half an ulp (EPS / 2) per component and its error estimate is a difference of
stage sums that carries a few ulps more, so a tolerance below a few ulps asks for digits float64
does not have: the runs then stall, or their error stops falling (DOP853 on the system samples:
the same 1e-13 to 1e-10 from rtol 1e-14 to 1e-17, then steps collapsing by 1e-20). 1e-15 is
~4.5 ulps; Hairer and Wanner's dop853.f refuses below 10 × its unit round-off (2.3e-15), the same
order."""

WINDING_ATOL = 0.25
"""A winding number further than this from an integer belongs to a point on (or next to)
another piece's surface: inconclusive, ignored. Round-off is ~1e-12; a point on a face gives
±0.5 and one on an edge or corner less."""

ON_SURFACE_RTOL = 1e-9
"""A query point whose solid-angle numerator and denominator with a triangle are both below this
times the product of its distances to the corners lies in the triangle's plane and not outside
it: on the surface, where the winding number jumps and is reported as NaN. Round-off of those
terms is ~1e-16 of that product; a point off the surface by 1e-9 of its distances is reported as
on it, which only withdraws a sample from the nesting vote."""

BOOLEAN_VOLUME_RTOL = 1e-9
"""The union of pieces (manifold3d) may hold more volume than the pieces together only by this
fraction (its own float sums); beyond it the boolean's result is not trusted (a piece that cuts
through itself, which no boolean defines): the overlap is then bounded instead of measured, and
``--union`` refuses."""

INERTIA_SYMMETRY_RTOL = 1e-12
"""An explicit inertia tensor may be asymmetric by this fraction of its largest entry (a tensor
typed with ~15 digits, or computed and printed elsewhere); beyond it, it is no inertia tensor."""

INERTIA_POSITIVE_RTOL = 1e-15
"""A principal moment at most this fraction of the largest counts as zero (a line mass): no body
with volume has it, and Euler's equations divide by it."""

INERTIA_TRIANGLE_RTOL = 1e-12
"""A principal moment may exceed the sum of the other two by this fraction (rounding of a flat
plate's moments, for which I3 = I1 + I2 exactly) before the tensor is refused as unphysical."""

QUATERNION_NORM_ATOL = 0.5
"""A sample whose quaternion norm is this far from 1 is no rotation: the kernels keep it within
round-off of 1, so only a diverged state gets there."""

CAD_ADAPTIVE_EPS = (1e-12, 1e-14)
"""CAD solids on which one of our own rules does not settle (the fallback: every face is ours
otherwise): the nested relative tolerances given to OpenCASCADE's adaptive integration of the
whole solid. Its own error estimate cannot be trusted (it reports 2e-16 where the result is 1e-9
off), but its results at tolerances two decades apart converge geometrically (measured on NURBS
spheres, tori, cylinders, cones: each step ~14x closer), so the last difference bounds the
last result's error with a margin of ~15x. 1e-14 is the finest level that still moves: below it
the results no longer change (the rule's floor), so a finer level would fake agreement."""

CAD_ADAPTIVE_FALLBACK_EPS = 1e-10
"""When the two levels above agree exactly (both at the rule's floor on that part), agreement
proves nothing: the level this much coarser is run too, and its difference makes the bar."""

CAD_INTEGRATION_SAFETY = 2.0
"""The integration bar is this multiple of the difference between the last two adaptive levels
(the geometric convergence above leaves a true error ~1/15 of it; 2 covers a slower step)."""

CAD_FLAT_RTOL = 1e-14
"""A B-spline or Bezier face whose poles lie within this fraction of their extent from one plane
is integrated as that plane (Green's theorem along its edges, `massprops.cad.planar`), the
poles' distance added to its bar (δ x area on the volume): NURBS conversions of planes keep
their poles coplanar to round-off (~1e-16), so this takes them and leaves any curved face,
whose bar would otherwise grow past 1e-14."""

CAD_ROUNDING_ULPS = 64.0
"""OpenCASCADE's integral offers no rounding bound: the bar charges this many units of
round-off per face on each quantity's natural scale about the local origin (Gauss sums of a few
hundred terms per face, each exact to a few ulps); measured errors on analytic solids are
1-4 ulps per solid, far inside."""

CONSTRAINT_RANK_RTOL = 1e-8
"""Singular values of a system's mass-weighted constraint Jacobian G M^(-1/2) below this
fraction of the largest count as zero: the constraint they belong to repeats others (a planar
four-bar of four revolutes in space has three such). Round-off leaves a repeated constraint's
singular value at ~1e-16 of the largest; a true one of a non-degenerate pose stays above ~1e-3
(unless the mechanism nears a singular pose, which is reported when its rank drops). 1e-8 sits
in the middle of that gap on the log scale."""

NEAR_SINGULAR_MARGIN = 1e-6
"""An accepted state of a system run whose smallest kept singular value of G M^(-1/2) is below
this fraction of the largest is a singular pose, reported like a rank drop: steps of ~1e-2 s
straddle the flat pose of a parallelogram four-bar landing at 1.2e-8..1.4e-8, just above
CONSTRAINT_RANK_RTOL, and would pass it on one branch without a word. Mechanisms away from a
singular pose stay above ~1e-3 (the samples: 0.05 to 0.5)."""

PROJECTION_ATOL_ULPS = 64
"""A system's positions and velocities are projected onto Φ = 0 and Φ̇ = 0 until the residual
is within this many ulps of the system size (positions, m) or of its speed scale (velocities):
a few Newton iterations from an integrator step's O(rtol) drift reach it; the round-off of
evaluating Φ itself (a sum of a few products of size-scale numbers) is ~10 ulps."""

NURBS_ORDER_STEP = 2
"""Free-form faces integrated by our own tensor-product Gauss rule (massprops.cad.nurbs): the
number of points per knot span grows by this many between the two orders compared (rational
quadratic patches of a NURBS sphere, torus, cylinder, measured: each step gains 2.3 digits,
so the last difference over-states the last result's error ~200x until both reach round-off)."""

NURBS_AGREEMENT = 4e-15
"""Two orders of that rule agree when every moment differs by at most this fraction of the
integral of its absolute integrand: the Gauss sums' round-off floor measured on those patches
is 1e-16..1.5e-15 of it, so agreement means the kept result is at round-off, and the bar (twice
the difference) of that size too."""

NURBS_MAX_ORDER = 48
"""The most points per knot span tried; a face not settled by then (a surface nearly singular
inside its domain, converging slowly: its last difference would not bound its error) sends the
whole solid to OpenCASCADE's adaptive rule and its two-level bar."""

NURBS_RATIONAL_START = 6
"""On a rational patch that rule starts this many points per span above the order exact for
polynomials: the rational quadratic patches measured reach round-off at 15-19 points, so the
orders below (7-11) are wasted work; the bar still comes from two orders compared."""

GLTF_UNSCALED_ATOL = 1e-5
"""A glTF mesh node counts as unscaled (`--write-physics` writes its motion) when the linear part
of its transform to the scene root, MᵀM, is the identity within this, entry by entry. Exporters
write rotations as float32 quaternions, unit to ~1e-7, so a rotation's MᵀM is 1 ± ~4e-7 (a few
nodes deep, a few times that); a scale an author set differs by percent, a unit mix-up (0.01,
0.001) by orders."""
