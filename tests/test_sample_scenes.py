"""The stiff and extreme sample scenes (sample_scenes/*.yaml) against independent truth: the
elliptic-function flip period, a closed-form spin-up, the gyroscopic precession rate, the creep of
an overdamped pivot, conservation laws over 1e6 steps, dimensional analysis, translation
invariance, exact impulses, rk4's stability limit, and the honesty of every run's error estimate.

Each test derives its truth here (from the numbers the scene's comment states), never from what
massprops printed."""

from __future__ import annotations

import copy
import dataclasses
import math
import re
from fractions import Fraction as F
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.special import ellipkm1

from massprops.dynamics import precision as precision_module
from massprops.dynamics.compiled.compiling import prepare
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.precision import precision
from massprops.dynamics.program import compile_forces
from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import choose_integrator, simulate
from massprops.dynamics.systems import methods
from massprops.dynamics.systems import run as system_run
from massprops.dynamics.systems.robot_scene import load_any_system
from massprops.errors import DivergenceError
from massprops.rotation import quat_to_matrix

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"
EPS = float(np.finfo(float).eps)
G = 9.81


def scene(name: str):
    return load_scene(SCENES / f"{name}.yaml")


def rotation_angle(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """(n,) rad between the rotations of unit quaternions (n, 4) row by row, sign-blind; stable
    for small angles: |qa ∓ qb| = 2 sin(θ/4)."""
    sign = np.where(np.sum(qa * qb, axis=1) < 0, -1.0, 1.0)
    chord = np.linalg.norm(qa - sign[:, None] * qb, axis=1)
    return 4.0 * np.arcsin(np.minimum(chord / 2.0, 1.0))


def zero_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times where the sampled x changes sign, by linear interpolation between samples."""
    i = np.flatnonzero(np.signbit(x[:-1]) != np.signbit(x[1:]))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def elliptic_motion(moments, e2, h2):
    """(λ², 1 - m) of a free body, I1 < I2 < I3 (moments), e2 = 2E = ωᵀJω, h2 = |Jω|², in the
    inputs' own number type (Fractions stay exact). Landau & Lifshitz §37: ω'_2 = A sn(λt + c | m);
    circling the I3 axis (h2 > e2 I2), λ² = (I3 - I2)(h2 - e2 I1) / (I1 I2 I3) and
    1 - m = (I3 - I1)(h2 - e2 I2) / ((I3 - I2)(h2 - e2 I1)); I1 and I3 swap roles otherwise."""
    i1, i2, i3 = moments
    if h2 < e2 * i2:
        i1, i3 = i3, i1
    return ((i3 - i2) * (h2 - e2 * i1) / (i1 * i2 * i3),
            (i3 - i1) * (h2 - e2 * i2) / ((i3 - i2) * (h2 - e2 * i1)))


def flip_period(moments, e2, h2) -> float:
    """Period 4 K(m) / λ (s) of ω'_2, K from 1 - m directly (no cancellation near m = 1)."""
    rate2, one_minus_m = elliptic_motion(moments, e2, h2)
    return 4.0 * float(ellipkm1(float(one_minus_m))) / math.sqrt(float(rate2))


def invariants(inertia, omega):
    """(2E, |H|²) = (ωᵀJω, |Jω|²) of a 3x3 inertia and a 3-vector, in their own number type."""
    jw = [sum(inertia[i][j] * omega[j] for j in range(3)) for i in range(3)]
    return sum(w * h for w, h in zip(omega, jw)), sum(h * h for h in jw)


def spread(x: np.ndarray) -> float:
    return float(np.max(np.abs(x - x[0])) / abs(x[0]))


# --- every scene documents itself ------------------------------------------------------------
SCENE_NAMES = sorted(p.stem for p in SCENES.glob("*.yaml"))


@pytest.mark.parametrize("name", SCENE_NAMES)
def test_scene_opens_with_its_story_and_the_readme_names_autos_choice(name):
    lines = (SCENES / f"{name}.yaml").read_text(encoding="utf-8").splitlines()
    story = lines[:next(i for i, line in enumerate(lines) if not line.startswith("#"))]
    assert len(story) >= 8 and any("What is right" in line for line in story)
    if any(line.startswith(("bodies:", "model:")) for line in lines):  # a system's rule
        loaded = load_any_system(SCENES / f"{name}.yaml")
        system, y0, _ = system_run.prepare(loaded)
        prepare(["outputs"])  # the stiffness probe evaluates the compiled right-hand side
        picked = methods.choose(system, y0, loaded.time.integrator, None, None)[0]
    else:
        loaded = scene(name)
        picked = choose_integrator(loaded, compile_forces(loaded), INTEGRATORS)[0]
    readme = (SCENES / "README.md").read_text(encoding="utf-8")
    row = next(r for r in readme.splitlines() if r.startswith(f"| `{name}.yaml`"))
    assert row.split(" | ")[3].split()[0] == picked


# --- free rotation: the flip and the separatrix ------------------------------------------------
def tetrahedron_inertia():
    """Corner tetrahedron a, b, c = 1, 2, 3 m at density 1 (V = abc/6 = 1): about its centre of
    mass J_xx = 3V(b² + c²)/80, ..., J_xy = +V a b / 80, ... (sample_meshes/README.md)."""
    a, b, c = F(1), F(2), F(3)
    v = a * b * c / 6
    return [[3 * v * (b * b + c * c) / 80, v * a * b / 80, v * a * c / 80],
            [v * a * b / 80, 3 * v * (a * a + c * c) / 80, v * b * c / 80],
            [v * a * c / 80, v * b * c / 80, 3 * v * (a * a + b * b) / 80]]


@pytest.mark.parametrize("integrator, step", [("auto", None), ("dop853", None),
                                              ("splitting", 1e-3), ("rk4", 1e-3)],
                         ids=["auto-exact", "dop853", "splitting", "rk4"])
def test_dzhanibekov_flip_period_matches_the_elliptic_formula(integrator, step):
    """ω'_2 = A sn(λt + c | m) changes sign every half period 2K(m)/λ. The crossings of the
    sampled run (0.01 s apart, linear interpolation: sn'' = 0 at a zero, so the interpolation
    error is O(h³) and nearly the same at every crossing) give the period to ~1e-7."""
    dz = scene("dzhanibekov")
    j = tetrahedron_inertia()
    assert np.abs(dz.body.inertia_body - np.array(j, dtype=float)).max() < 1e-14
    omega = [F(x) for x in dz.initial.angular_velocity]  # body frame, exact binary values
    e2, h2 = invariants(j, omega)
    moments, axes = np.linalg.eigh(np.array(j, dtype=float))
    period = flip_period(moments, e2, h2)
    result = simulate(dz, integrator=integrator, step=step)
    traj = result.trajectory
    crossings = zero_crossings(traj.t, traj.angular_velocity_body @ axes[:, 1])
    assert len(crossings) >= 9  # ten flips in 20 s
    measured = 2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert measured == pytest.approx(period, rel=1e-6)


def separatrix_invariants():
    """(moments, 2E, |H|²) of separatrix.yaml, exact: J = diag(2, 3, 4), ω as read (binary)."""
    moments = (F(2), F(3), F(4))
    omega = [F(x) for x in scene("separatrix").initial.angular_velocity]
    return (moments, *invariants([[moments[i] * (i == k) for k in range(3)] for i in range(3)],
                                 omega))


def test_separatrix_start_is_within_1e8_of_the_separatrix():
    assert 0 < elliptic_motion(*separatrix_invariants())[1] < F(1, 10**8)
    # the nearest separatrix point with the same ω2, ω3 has ω1 = √2 ω3 (4 ω3² = 2 ω1²)
    w = scene("separatrix").initial.angular_velocity
    assert abs(w[0] - math.sqrt(2) * w[2]) / np.linalg.norm(w) < 1e-8


def test_separatrix_flips_where_the_elliptic_formula_says():
    """The closed form (auto: exact) flips ω'_2 every 2K(m)/λ; near the separatrix K ~ ½ ln(16 /
    (1 - m)) is extremely sensitive to the invariants, which the formula takes exactly."""
    result = simulate(scene("separatrix"))
    assert result.integrator == "exact"
    crossings = zero_crossings(result.trajectory.t, result.trajectory.angular_velocity_body[:, 1])
    assert len(crossings) == 2
    half_period = flip_period(*separatrix_invariants()) / 2.0
    assert crossings[1] - crossings[0] == pytest.approx(half_period, rel=1e-6)


def test_separatrix_exact_and_tight_dop853_agree_within_the_runs_estimate():
    """rtol 1e-12: three passages near the saddle each amplify every step's round-off by
    ~1/sqrt(1 - m) = 1.7e4, so any step sequence ends at a noisy float64 floor of 1e-7 to 1e-6
    (scipy's DOP853 on Euler's equations in body axes: 2e-7 to 3e-7 at rtol 1e-11 to 1e-13; on
    the systems' form: 2e-8 to 1e-6). What must hold is the run's own error estimate (true
    error within 10× of it), and the floor's size."""
    sep = scene("separatrix")
    exact = simulate(sep, integrator="exact").trajectory
    tight = simulate(sep, integrator="dop853", rtol=1e-12)
    spin = np.linalg.norm(exact.angular_velocity, axis=1).max()
    error = max(rotation_angle(exact.orientation, tight.trajectory.orientation).max(),
                np.abs(exact.angular_velocity - tight.trajectory.angular_velocity).max() / spin)
    assert error < 10 * tight.diagnostics["error_estimate"]
    assert error < 1e-5


# --- fast spin, extreme inertia: needle and disk ----------------------------------------------
NEEDLE = {"I1": 1e-6, "I2": 1.0, "spin": 1000.0, "transverse": 0.1, "torque": 1e-6}
"""needle.yaml: J = diag(I1, I2, I2), ω_body(0) = (spin, transverse, 0), axial body torque."""
NEEDLE_TOLERANCE = {"splitting": 1e-7, "splitting6": 1e-7, "auto": 2e-3}
"""Relative errors allowed in ω1, ω⊥, E and |H|. Splitting: exact sub-flows, so round-off of a
phase of 1e4 rad over 1e4 steps (~1e-9 measured). auto (dop853, rtol 1e-9): its error control is
relative to the largest |ω| (1000 rad/s), while ω⊥ = 0.1 rad/s carries 99.99 % of |H|: a
per-step tolerance of 1e-6 rad/s on ω⊥ (1e-5 of it) over 1e4 steps; its own error estimate says
2e-4."""


def needle_truth(t: np.ndarray):
    """ω_body (n, 3), E (n,), |H| (n,) of needle.yaml: I2 = I3 and an axial torque n1 give
    ω1 = ω1(0) + n1 t / I1, and ω2 + i ω3 = |ω⊥| exp(-i φ), φ = (1 - I1/I2) ∫ω1 dt."""
    n = NEEDLE
    w1 = n["spin"] + n["torque"] / n["I1"] * t
    phi = (1.0 - n["I1"] / n["I2"]) * (n["spin"] * t + 0.5 * n["torque"] / n["I1"] * t * t)
    perp = n["transverse"] * np.exp(-1j * phi)
    omega = np.column_stack([w1, perp.real, perp.imag])
    energy = 0.5 * n["I1"] * w1**2 + 0.5 * n["I2"] * n["transverse"] ** 2
    momentum = np.hypot(n["I1"] * w1, n["I2"] * n["transverse"])
    return omega, energy, momentum


@pytest.mark.parametrize("integrator", list(NEEDLE_TOLERANCE))
def test_needle_follows_the_closed_form_spin_up(integrator):
    traj = simulate(scene("needle"), integrator=integrator).trajectory
    omega, energy, momentum = needle_truth(traj.t)
    w = traj.angular_velocity_body
    moments = np.array([NEEDLE["I1"], NEEDLE["I2"], NEEDLE["I2"]])
    tol = NEEDLE_TOLERANCE[integrator]
    assert np.abs(w[:, 0] / omega[:, 0] - 1).max() < tol
    assert np.abs(w[:, 1:] - omega[:, 1:]).max() / NEEDLE["transverse"] < tol
    assert np.abs(0.5 * (moments * w * w).sum(axis=1) / energy - 1).max() < tol
    assert np.abs(np.linalg.norm(traj.angular_momentum, axis=1) / momentum - 1).max() < tol


DISK_MOMENTS = np.array([2.0 * (3 * 0.25 + 1e-4) / 12, 2.0 * (3 * 0.25 + 1e-4) / 12, 0.25])
"""disk.yaml: m = 2 kg, R = 0.5 m, thickness 1 cm: m (3R² + t²)/12 twice, m R²/2."""


@pytest.mark.parametrize("integrator", ["auto", "splitting", "splitting4"])
def test_disk_keeps_energy_and_world_angular_momentum(integrator):
    """Torque-free: exact (auto) and the splitting methods' drifts are the exact free flow."""
    disk = scene("disk")
    assert np.allclose(disk.body.principal_moments, np.sort(DISK_MOMENTS), rtol=1e-15)
    traj = simulate(disk, integrator=integrator).trajectory
    w = traj.angular_velocity_body
    energy = 0.5 * (DISK_MOMENTS * w * w).sum(axis=1)
    h_world = np.einsum("nij,nj->ni", quat_to_matrix(traj.orientation), DISK_MOMENTS * w)
    assert spread(energy) < 1e-12
    assert np.linalg.norm(h_world - h_world[0], axis=1).max() / np.linalg.norm(h_world[0]) < 1e-12


@pytest.mark.parametrize("name", ["needle", "disk"])
def test_rk4_at_1ms_stays_finite_but_loses_the_fast_spin(name):
    """1000 rad/s at h = 1e-3 s is ωh = 1 rad (2 rad for the disk's precession): inside rk4's
    stability interval (2.83), so no divergence, but a phase error of ~1e-3 rad per step. The
    outcome is the second one of the brief: no DivergenceError, error > 1 rad."""
    sc = scene(name)
    reference = simulate(sc, integrator="exact" if name == "disk" else "splitting6").trajectory
    rk4 = simulate(sc, integrator="rk4", step=1e-3).trajectory
    assert np.isfinite(rk4.orientation).all()
    assert rotation_angle(rk4.orientation, reference.orientation).max() > 1.0
    if name == "needle":  # |R(i)| = 0.994 per step damps ω⊥, which carries |H|: 1e4 steps kill it
        h = np.linalg.norm(rk4.angular_momentum, axis=1)
        assert h[-1] < 0.5 * h[0]


# --- the heavy top on a stiff pivot spring ----------------------------------------------------
TOP_MASS = 3 * math.sqrt(3)  # hexagonal prism R = 1, h = 2, density 1 (sample_meshes/README.md)
TOP_MOMENTS = np.array([13 * math.sqrt(3) / 8, 13 * math.sqrt(3) / 8, 5 * math.sqrt(3) / 4])
TOP_PIVOT = np.array([0.0, 0.0, -1.0])  # body point; the centre of mass is the origin: l = 1 m
TOP_K = 1e8


def top_energy(traj, k: float = TOP_K) -> np.ndarray:
    """Kinetic + gravity + pivot spring energy (J) of the top, anchor at the world origin."""
    a = quat_to_matrix(traj.orientation)
    w = traj.angular_velocity_body
    pivot = traj.position + a @ TOP_PIVOT
    return (0.5 * TOP_MASS * np.sum(traj.velocity**2, axis=1)
            + 0.5 * np.sum(TOP_MOMENTS * w * w, axis=1) + TOP_MASS * G * traj.position[:, 2]
            + 0.5 * k * np.sum(pivot**2, axis=1))


def top_axis_and_pivot(traj) -> tuple[np.ndarray, np.ndarray]:
    a = quat_to_matrix(traj.orientation)
    return a[:, :, 2], traj.position + a @ TOP_PIVOT


@pytest.mark.slow
def test_heavy_top_on_a_stiff_pivot_precesses_at_the_gyroscopic_rate():
    top = scene("heavy_top_stiff")
    assert np.allclose(top.body.principal_moments, np.sort(TOP_MOMENTS), rtol=1e-14)
    assert top.body.mass == pytest.approx(TOP_MASS, rel=1e-14)
    result = simulate(top)
    traj = result.trajectory
    assert result.integrator == "dop853"
    energy = top_energy(traj)
    assert spread(energy) < 1e-10  # conservative: drift at the rtol 1e-9 × (steps) level, or less
    axis, pivot = top_axis_and_pivot(traj)
    spin = np.sum(traj.angular_velocity * axis, axis=1)  # ω3: no torque about the symmetry axis
    assert spread(spin) < 1e-9
    azimuth = np.unwrap(np.arctan2(axis[:, 1], axis[:, 0]))
    rate = np.polyfit(traj.t, azimuth, 1)[0]
    gyroscopic = TOP_MASS * G * 1.0 / (TOP_MOMENTS[2] * spin[0])
    assert rate == pytest.approx(gyroscopic, rel=0.03)
    assert np.abs(pivot).max() < 1e-5  # the pivot stays at the anchor to ~ m g / k


@pytest.mark.slow
def test_heavy_top_with_a_strong_damper_goes_implicit_and_the_pivot_creeps_home():
    """Overdamped pivot (c = 1e7, k = 1e8): the offset decays as exp(-k t / c) (the slow root
    k/c (1 + O(k m / c²)) with k m / c² = 5e-6) down to the dynamic deflection of the precessing,
    nutating top (~ m |a| / k, a few nm); the energy never increases."""
    top = scene("heavy_top_damped")
    result = simulate(top)
    traj = result.trajectory
    assert result.integrator == "implicit"
    assert all(np.isfinite(getattr(traj, f)).all() for f in ("position", "orientation",
                                                             "velocity", "angular_velocity"))
    energy = top_energy(traj)
    assert np.diff(energy).max() <= 64 * EPS * abs(energy[0])
    _, pivot = top_axis_and_pivot(traj)
    static = np.array([0.0, 0.0, -TOP_MASS * G / TOP_K])
    offset = np.linalg.norm(pivot - static, axis=1)
    i = np.searchsorted(traj.t, 0.2)
    assert offset[i] == pytest.approx(offset[0] * math.exp(-TOP_K / 1e7 * traj.t[i]), rel=1e-3)
    assert offset[traj.t >= 0.9 * traj.t[-1]].max() < 1e-8


# --- a long run: 1e6 steps of the splitting method ---------------------------------------------
@pytest.mark.slow
def test_long_run_keeps_momentum_and_norm_at_round_off_and_energy_without_drift():
    """1e6 Strang steps (1.4 s of compiled work here, so the full count). The spring acts at the
    centre of mass: the rotation is torque-free, each drift its exact flow, so |H| (world) may
    only wander by round-off; the energy error of a symplectic method oscillates, bounded."""
    long = scene("long_run")
    result = simulate(long)
    assert result.integrator == "splitting" and result.steps == 1_000_000
    traj = result.trajectory
    h = np.linalg.norm(traj.angular_momentum, axis=1)
    # Round-off: the drift evaluates the change of the closed form from its start, so its
    # rounding is unbiased (measured 2e-14; a bias of 0.07 ulp per call once gave 3.2e-12).
    assert spread(h) <= 1e-12
    assert result.diagnostics["quaternion_norm_error"] <= 1e-12
    first, last = energy_excursions(traj)
    assert 0 < last <= 2.0 * first


def energy_excursions(traj) -> tuple[float, float]:
    """Largest |E - E0| over the first and over the last tenth of a long_run.yaml trajectory:
    m = 1 kg, g = 9.81 m/s² down, k = 40 N/m of rest length 1 m from the origin, J = 1, 2, 2.9."""
    energy = (0.5 * np.sum(traj.velocity**2, axis=1) + G * traj.position[:, 2]
              + 20.0 * (np.linalg.norm(traj.position, axis=1) - 1.0) ** 2
              + 0.5 * np.sum([1.0, 2.0, 2.9] * traj.angular_velocity_body**2, axis=1))
    tenth = len(energy) // 10
    return np.abs(energy[:tenth] - energy[0]).max(), np.abs(energy[-tenth:] - energy[0]).max()


def test_long_run_with_rk4_drifts_instead():
    """The contrast that makes the test above meaningful: rk4 (not symplectic) loses energy
    linearly in time, so its last tenth is ~10x its first (1e5 steps at h = 1e-2 s)."""
    traj = simulate(scene("long_run"), integrator="rk4", step=1e-2).trajectory
    first, last = energy_excursions(traj)
    assert last > 5.0 * first


# --- tiny, huge, far: dimensional analysis and translation invariance ---------------------------
class _Yaml12Loader(yaml.SafeLoader):
    """PyYAML reads 1.0e8 (no exponent sign) as a string (YAML 1.1); massprops reads it as a
    number, and so must a test that rewrites scenes."""


_Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)(?:[eE][-+]?[0-9]+)?$"),
    list("-+0123456789."))

UNITS = {"m": 1.0, "mm": 1e-3}

# Dimensions of every scaled key with time unchanged: (power of L, power of M); "linear" and
# "angular" are drag coefficients (N·s/m, N·m·s).
DIMENSIONS = {"position": (1, 0), "velocity": (1, 0), "g": (1, 0), "anchor": (1, 0),
              "point": (1, 0), "rest_length": (1, 0), "stiffness": (0, 1), "damping": (0, 1),
              "linear": (0, 1), "angular": (2, 1), "mass": (0, 1), "inertia": (2, 1),
              "density": (-3, 1), "force": (1, 1), "torque": (2, 1)}


def read_doc(name: str) -> dict:
    return yaml.load((SCENES / f"{name}.yaml").read_text(encoding="utf-8"), Loader=_Yaml12Loader)


def scaled(doc: dict, length: float, mass: float) -> dict:
    """The scene with every length × L and every mass × M, time unchanged (forces × M L, torques
    and inertia × M L², stiffness and damping × M, accelerations × L)."""
    out = copy.deepcopy(doc)

    def times(value, key):
        p, q = DIMENSIONS[key]
        return (np.asarray(value, dtype=float) * length**p * mass**q).tolist()

    body = out["body"]
    if "mesh" in body:  # the same mesh read in a unit L times larger
        factor = UNITS[body.get("unit", "m")] * length
        body["unit"] = next(u for u, f in UNITS.items() if math.isclose(f, factor))
        body["mesh"] = str((SCENES / body["mesh"]).resolve())
    for key in set(body) & {"mass", "inertia", "density"}:
        body[key] = times(body[key], key)
    for key in set(out.get("initial", {})) & {"position", "velocity"}:
        out["initial"][key] = times(out["initial"][key], key)
    for term in out.get("forces", []):
        for key in set(term) & set(DIMENSIONS):
            term[key] = times(term[key], key)
        if term["type"] in ("force", "torque"):
            term["vector"] = times(term["vector"], term["type"])
    return out


def shifted(doc: dict, offset) -> dict:
    """The scene moved by -offset in the world: the initial position and the spring anchors."""
    out = copy.deepcopy(doc)
    out["initial"]["position"] = (np.array(out["initial"]["position"]) - offset).tolist()
    for term in out["forces"]:
        if "anchor" in term:
            term["anchor"] = (np.array(term["anchor"]) - offset).tolist()
    return out


def load_doc(doc: dict, path: Path):
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return load_scene(path)


def distance(a, b, size: float, length: float = 1.0, offset=0.0) -> float:
    """Largest relative difference of two trajectories: positions (a's shifted by -offset and
    divided by length) / body size, orientation angle, velocities and angular velocities over
    b's largest values (floored at one body size and one radian per run duration)."""
    duration = b.t[-1]
    v_scale = max(np.linalg.norm(b.velocity, axis=1).max(), size / duration)
    w_scale = max(np.linalg.norm(b.angular_velocity, axis=1).max(), 1.0 / duration)
    return max(np.abs((a.position - offset) / length - b.position).max() / size,
               rotation_angle(a.orientation, b.orientation).max(),
               np.abs(a.velocity / length - b.velocity).max() / v_scale,
               np.abs(a.angular_velocity - b.angular_velocity).max() / w_scale)


@pytest.mark.parametrize("name, length, mass", [("tiny", 1e-3, 1e-6), ("huge", 1e3, 1e12)],
                         ids=["tiny", "huge"])
@pytest.mark.parametrize("integrator", ["auto", "rk4"])
def test_scaled_scene_runs_the_unit_scene_scaled(name, length, mass, integrator, tmp_path):
    """The two runs differ only by the rounding of the scaled inputs (~1 ulp): same step choices,
    states equal to ~1e-12 relative (allowed 1e-10), error estimates equal to ~1e-6 relative (a
    difference of two runs ~1e-7 apart, each with ~1e-13 of noise; allowed 1e-4)."""
    extreme = scene(name)
    unit = load_doc(scaled(read_doc(name), 1.0 / length, 1.0 / mass), tmp_path / "unit.yaml")
    assert extreme.body.size == pytest.approx(unit.body.size * length, rel=1e-12)
    a, b = simulate(extreme, integrator=integrator), simulate(unit, integrator=integrator)
    assert a.integrator == b.integrator and a.steps == b.steps
    assert distance(a.trajectory, b.trajectory, unit.body.size, length) < 1e-10
    for key in ("error_estimate", "energy_rel_drift", "angular_momentum_rel_drift"):
        if b.diagnostics[key] is None:
            assert a.diagnostics[key] is None
        else:
            assert a.diagnostics[key] == pytest.approx(b.diagnostics[key], rel=1e-4, abs=1e-15)


FAR = np.array([1e6, 0.0, 0.0])


@pytest.mark.parametrize("integrator, step, stages", [("auto", None, 12), ("rk4", 1e-3, 4)])
def test_far_scene_equals_the_origin_scene_shifted(integrator, step, stages, tmp_path):
    """At 1e6 m every position operation rounds by up to ulp(1e6) = 1.16e-10 m; over N steps of
    s stages those errors add like a random walk, sqrt(N s) ulp, relative to the body size (not
    to 1e6 m). Allowed: 10 × that (measured: ~1/20 of the allowance)."""
    far = scene("far")
    origin = load_doc(shifted(read_doc("far"), FAR), tmp_path / "origin.yaml")
    a, b = simulate(far, integrator=integrator, step=step), simulate(origin, integrator=integrator,
                                                                     step=step)
    ulp = float(np.spacing(1e6))
    allowed = 10 * math.sqrt(b.steps * stages) * ulp / origin.body.size
    assert distance(a.trajectory, b.trajectory, origin.body.size, offset=FAR) < allowed


# --- a force window shorter than the step -------------------------------------------------------
BLOW = {"mass": 3.0, "force": np.array([2000.0, 0.0, 0.0]), "start": 0.5,
        "length": 1.0 / 2048, "point": np.array([0.0, 0.2, 0.0])}
"""short_window.yaml: a world-frame force at a body point for 1/2048 s (bounds exact in binary)."""


@pytest.mark.parametrize("integrator", ["auto", *sorted(n for n in INTEGRATORS if n != "exact")])
def test_short_blow_gives_exactly_its_impulse(integrator):
    """m Δv = F Δt + m g T exactly (to a few ulp of m|v|), and the angular impulse is
    (A s) × F Δt to O((|ω| + |Δω|) Δt) = 1.4 rad/s × 4.9e-4 s ≈ 7e-4 relative."""
    result = simulate(scene("short_window"), integrator=integrator)
    traj = result.trajectory
    duration = traj.t[-1]
    impulse = BLOW["mass"] * (traj.velocity[-1] - traj.velocity[0]
                              - np.array([0.0, 0.0, -G]) * duration)
    expected = BLOW["force"] * BLOW["length"]
    scale = BLOW["mass"] * np.abs(traj.velocity).max()
    assert np.abs(impulse - expected).max() <= 8 * EPS * scale
    before = np.searchsorted(traj.t, BLOW["start"])  # samples at 0.50 and 0.51 s bracket it
    assert traj.t[before] == BLOW["start"]
    arm = quat_to_matrix(traj.orientation[before]) @ BLOW["point"]
    angular = np.cross(arm, BLOW["force"]) * BLOW["length"]
    jump = traj.angular_momentum[before + 1] - traj.angular_momentum[before]
    assert np.linalg.norm(jump - angular) <= 1e-3 * np.linalg.norm(angular)


# --- beyond rk4's stability limit ---------------------------------------------------------------
def unstable_for(duration: float):
    sc = scene("unstable")
    return dataclasses.replace(sc, time=dataclasses.replace(sc.time, duration=duration))


@pytest.mark.parametrize("duration", [0.2, 1.0, 3.0],
                         ids=["energy-finite", "energy-overflows", "state-overflows"])
def test_rk4_beyond_its_stability_limit_raises_divergence(duration):
    """ωh = 10 > 2√2: |R| ≈ 400 per step. Whether the blow-up is still finite at the end (0.2 s:
    amplitude 1e52), overflows only in the energy (1 s, the scene: amplitude 1e258, energy inf)
    or overflows the state itself (3 s), the run must stop with a DivergenceError naming an early
    time (energy ×1.6e5 per step: past 1e6 by the 2nd step, 0.02 s) and the step against the
    stiffest rate's limit 2.8e-3 s, and must not warn."""
    with pytest.raises(DivergenceError) as caught:
        simulate(unstable_for(duration))
    message = str(caught.value)
    when = float(re.search(r"near t = ([0-9.eE+-]+) s", message).group(1))
    assert when <= 0.05
    assert "step here: 0.01" in message and "0.0028 s" in message


def test_cli_exits_3_naming_the_time_and_the_step(run):
    result = run("simulate", SCENES / "unstable.yaml")
    assert result.exit_code == 3
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "unstable.yaml" in lines[0]
    assert re.search(r"near t = 0\.0[1-5]? s", lines[0]) and "step here: 0.01" in lines[0]


def test_implicit_at_the_same_step_stays_bounded():
    """Radau IIA is L-stable: R(z) -> 0 as |z| -> ∞, so the unresolved 1000 rad/s mode is damped,
    not amplified: finite, energy non-increasing, never farther from rest than at the start."""
    traj = simulate(scene("unstable"), integrator="implicit").trajectory
    energy = traj.energy
    assert np.isfinite(energy).all()
    assert np.diff(energy).max() <= 64 * EPS * abs(energy[0])
    rest = np.array([0.0, 0.0, -G * 1.0 / 1e6])
    assert np.linalg.norm(traj.position - rest, axis=1).max() <= 0.01 + 1e-5


# --- honesty of the error estimates ---------------------------------------------------------------
HONESTY_SCENES = ("dzhanibekov", "separatrix", "needle", "tiny", "huge", "far", "short_window")
"""Several kinds of motion (free flip, near-separatrix, fast spin under torque, forced and
damped, scaled, far, windowed): ~26 s of ladders. Left out for time: disk (15 s, torque-free like
dzhanibekov), the heavy tops and long_run (about a minute each); unstable's ladders are covered
by the divergence tests above (its splitting rung's 2h companion overflows, see there).
benchmarks/estimate_honesty.py runs them all."""
HONESTY_FLOOR = 1e3
"""Only rungs whose true error exceeds this × the reference's own accuracy count."""


@pytest.mark.slow
def test_error_estimates_are_honest_over_the_suite(monkeypatch):
    """Issue requirement: true error <= 10 × error_estimate in at least 95 % of the runs, and the
    estimate is not uselessly pessimistic (median estimate / true within 0.1 ... 10). Every
    applicable integrator over the full ladders of `precision` (its timing repeats switched off:
    only errors matter here)."""
    monkeypatch.setattr(precision_module, "MIN_TIMED_S", 0.0)
    rungs = []
    for name in HONESTY_SCENES:
        report = precision(scene(name))
        floor = HONESTY_FLOOR * report.reference["accuracy"]
        rungs += [(name, run) for run in report.runs
                  if run.error is not None and run.estimate is not None and run.error > floor]
    ratios = np.array([run.error / run.estimate if run.estimate > 0 else np.inf
                       for _, run in rungs])
    assert len(ratios) >= 150
    cells: dict[str, list[bool]] = {}
    for (name, run), ratio in zip(rungs, ratios):
        cells.setdefault(f"{name}/{run.integrator}", []).append(bool(ratio > 10))
    worst = sorted(cells.items(), key=lambda kv: -sum(kv[1]))
    summary = ", ".join(f"{cell} {sum(bad)}/{len(bad)}" for cell, bad in worst if any(bad))
    # The bar, overall and for every integrator with enough rungs to say (measured over
    # all sample scenes: 98.9 % overall, each integrator >= 93 %; what is left is round-off
    # amplified near the separatrix, where three runs of a noise cannot always tell its size).
    assert np.mean(ratios <= 10) >= 0.95, f"dishonest rungs (true > 10 x estimate): {summary}"
    for name in {run.integrator for _, run in rungs}:
        mine = np.array([r for (_, run), r in zip(rungs, ratios) if run.integrator == name])
        assert mine.size < 20 or np.mean(mine <= 10) >= 0.9, summary
    assert 0.1 <= 1.0 / np.median(ratios) <= 10
