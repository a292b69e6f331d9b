"""Random system scenes (``bodies:`` + ``joints:``) for ``fuzz_systems.py``, as plain dicts.

Every scene is built in its assembly pose, so its joints hold at t = 0 by construction (points
and axes in world coordinates at t = 0, as the contract says); a closed loop is assembled from
its link lengths (four-bar: the circle-circle intersection; slider-crank: the rod's reach).
Units SI: lengths m, masses kg, rates rad/s or m/s. ``random_case`` returns ``(scene, expect)``
with ``expect`` one of ``"run"`` (a valid scene: a result, or exit 2/3 with one line),
``"usage"`` (a method systems refuse: exit 2) or ``"invalid"`` (a deliberate scene error:
exit 1), and a short label of the mutation or shape.
"""

from __future__ import annotations

import math

import numpy as np

RUN_METHODS = ("auto", "dop853", "rk4", "midpoint", "implicit")
REFUSED_METHODS = ("splitting", "splitting4", "splitting6", "exact")
KINDS = ("revolute", "prismatic", "cylindrical", "universal", "spherical", "fixed", "distance")
NRATES = {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 3}


def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    """10**U(log10 lo, log10 hi)."""
    return float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))


def unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def perpendicular(rng: np.random.Generator, d: np.ndarray) -> np.ndarray:
    """A random unit vector perpendicular to the unit vector ``d``."""
    v = np.cross(d, unit(rng))
    return v / np.linalg.norm(v)


def rod_body(rng, p0, p1, mass: float, at: np.ndarray) -> dict:
    """An explicit body: a solid cylinder from p0 to p1 (world, m), radius 1e-3 ... 0.3 of its
    length; centre of mass at the middle, inertia about it in world axes (the body frame is the
    world frame at t = 0). ``at`` is added to the position (the far placement)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    length = float(np.linalg.norm(p1 - p0)) or 1.0
    d = (p1 - p0) / length
    radius = length * log_uniform(rng, 1e-3, 0.3)
    axial = mass * radius ** 2 / 2
    across = mass * (3 * radius ** 2 + length ** 2) / 12
    inertia = across * (np.eye(3) - np.outer(d, d)) + axial * np.outer(d, d)
    inertia = 0.5 * (inertia + inertia.T)
    return {"mass": mass, "inertia": inertia.tolist(), "position": (0.5 * (p0 + p1) + at).tolist()}


class Builder:
    """Bodies and joints of one scene, with the case's mass and length scales and far offset."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng
        self.size = log_uniform(rng, 1e-4, 1e3)
        self.mass = log_uniform(rng, 1e-6, 1e6)
        self.ratio = float(10 ** rng.choice([0, 1, 3, 6]))  # spread of masses
        self.offset = (log_uniform(rng, 1, 1e8) * unit(rng) if rng.random() < 0.3
                       else np.zeros(3))
        self.bodies: dict = {}
        self.joints: list = []
        self.ends: dict = {}  # body -> (p0, p1) of its rod, relative to the offset

    def a_mass(self) -> float:
        m = self.mass * log_uniform(self.rng, 1 / self.ratio, self.ratio) if self.ratio > 1 \
            else self.mass
        return float(min(max(m, 1e-6), 1e6))

    def rod(self, name: str, p0, p1) -> str:
        self.bodies[name] = rod_body(self.rng, p0, p1, self.a_mass(), self.offset)
        self.ends[name] = (np.asarray(p0, float), np.asarray(p1, float))
        return name

    def joint(self, kind: str, a: str, b: str, point, axis=None, **extra) -> dict:
        rng, at = self.rng, self.offset
        j = {"name": f"J{len(self.joints)}", "type": kind, "bodies": [a, b]}
        point = np.asarray(point, float)
        axis = unit(rng) if axis is None else np.asarray(axis, float)
        if kind == "distance":
            other = point + self.size * log_uniform(rng, 0.1, 1) * unit(rng)
            j["points"] = [(point + at).tolist(), (other + at).tolist()]
        elif kind != "fixed" or rng.random() < 0.7:
            j["point"] = (point + at).tolist()
        if kind in ("revolute", "prismatic", "cylindrical"):
            j["axis"] = axis.tolist()
        if kind == "universal":
            j["axes"] = [axis.tolist(), perpendicular(rng, axis).tolist()]
        j.update(extra)
        self.joints.append(j)
        return j

    def load(self, j: dict) -> None:
        """Maybe a spring (up to 1e12), a damper and a drive with a window on a one-axis joint."""
        rng = self.rng
        if j["type"] not in ("revolute", "prismatic"):
            return
        if rng.random() < 0.4:
            j["stiffness"] = log_uniform(rng, 1e-2, 1e12)
            if rng.random() < 0.5:
                j["rest"] = float(rng.uniform(-1, 1) * (1 if j["type"] == "revolute"
                                                         else self.size))
        if rng.random() < 0.3:
            j["damping"] = log_uniform(rng, 1e-4, 1e8)
        if rng.random() < 0.3:
            j["torque" if j["type"] == "revolute" else "force"] = float(
                rng.normal() * self.mass * 9.81 * log_uniform(rng, 1e-3, 1e3)
                * (self.size if j["type"] == "revolute" else 1))
            if rng.random() < 0.5:
                j["start"] = 0.0
                j["end"] = log_uniform(rng, 1e-4, 1e2)


# --- shapes -------------------------------------------------------------------------------------
def chain(b: Builder, branches: bool) -> list[str]:
    """A chain of 2-12 links from the world (or a tree: each link hangs from an earlier one)."""
    rng = b.rng
    names, tips = [], [("world", np.zeros(3))]
    for i in range(int(rng.integers(2, 13))):
        parent, p0 = tips[int(rng.integers(len(tips)))] if branches else tips[-1]
        p1 = p0 + b.size * log_uniform(rng, 0.1, 1) * unit(rng)
        name = b.rod(f"link{i}", p0, p1)
        kind = str(rng.choice(KINDS, p=[0.3, 0.12, 0.1, 0.12, 0.16, 0.08, 0.12]))
        b.load(b.joint(kind, parent, name, p0))
        tips.append((name, p1))
        names.append(name)
    if rng.random() < 0.25:  # close a loop back to the world with a distance rod or a sphere
        last, p1 = tips[-1]
        kind = str(rng.choice(["distance", "spherical", "revolute"]))
        b.joint(kind, last, "world", p1)
    return names


def four_bar(b: Builder) -> list[str]:
    """A planar four-bar of revolutes about y: Grashof or not, parallelogram, near flat."""
    rng = b.rng
    shape = str(rng.choice(["grashof", "any", "parallelogram", "near-flat"]))
    d = b.size
    a, bb, c = (d * log_uniform(rng, 0.1, 3) for _ in range(3))
    if shape == "parallelogram":
        a, bb, c = a, d * (1 + 1e-12 * rng.normal()), a
    if shape == "grashof":
        a = min(a, bb, c, d) * 0.5
    theta = float(rng.uniform(0, 2 * math.pi))
    if shape == "near-flat":
        theta = float(rng.choice([0.0, math.pi])) + 1e-7 * rng.normal()
    A, D = np.zeros(3), np.array([d, 0, 0])
    B = A + a * np.array([math.cos(theta), 0, math.sin(theta)])
    dist = float(np.linalg.norm(D - B))
    if not abs(bb - c) <= dist <= bb + c:  # cannot assemble at this angle: pick the coupler
        bb = math.sqrt(dist ** 2 + c ** 2) if rng.random() < 0.5 else dist + c * (1 - 1e-9)
    x = (dist ** 2 + bb ** 2 - c ** 2) / (2 * dist)
    h = math.sqrt(max(bb ** 2 - x ** 2, 0.0)) * (1 if rng.random() < 0.5 else -1)
    e = (D - B) / dist
    n = np.cross(e, [0, 1, 0])
    C = B + x * e + h * n
    y = np.array([0.0, 1.0, 0.0])
    names = [b.rod("crank", A, B), b.rod("coupler", B, C), b.rod("rocker", D, C)]
    for kind_pair, point in ((("world", "crank"), A), (("crank", "coupler"), B),
                             (("coupler", "rocker"), C), (("world", "rocker"), D)):
        b.load(b.joint("revolute", *kind_pair, point, y))
    return names


def slider_crank(b: Builder) -> list[str]:
    """Crank r about y at the origin, rod l, a slider on a prismatic joint along x (offset e)."""
    rng = b.rng
    r = b.size * log_uniform(rng, 0.05, 1)
    ell = r * log_uniform(rng, 1.0001, 10) if rng.random() < 0.8 else r * (1 + 1e-9)
    e = float(rng.uniform(-0.5, 0.5) * (ell - r)) if rng.random() < 0.3 else 0.0
    theta = float(rng.uniform(0, 2 * math.pi))
    B = r * np.array([math.cos(theta), 0, math.sin(theta)])
    dz = e - B[2]
    if abs(dz) > ell:
        theta, B, dz = 0.0, np.array([r, 0.0, 0.0]), e
    C = np.array([B[0] + math.sqrt(ell ** 2 - dz ** 2), 0.0, e])
    y = np.array([0.0, 1.0, 0.0])
    names = [b.rod("crank", [0, 0, 0], B), b.rod("rod", B, C),
             b.rod("slider", C - [0.1 * r, 0, 0], C + [0.1 * r, 0, 0])]
    for pair, point, kind, axis in ((("world", "crank"), [0, 0, 0], "revolute", y),
                                    (("crank", "rod"), B, "revolute", y),
                                    (("rod", "slider"), C, "revolute", y),
                                    (("world", "slider"), C, "prismatic", [1.0, 0, 0])):
        b.load(b.joint(kind, *pair, point, axis))
    return names


def free_bodies(b: Builder) -> list[str]:
    """1-3 unjoined bodies (free joints), maybe one fixed or spherical to another."""
    rng = b.rng
    names = []
    for i in range(int(rng.integers(1, 4))):
        p0 = b.size * 3 * i * np.array([1.0, 0, 0])
        names.append(b.rod(f"free{i}", p0, p0 + b.size * unit(rng)))
    if len(names) > 1 and rng.random() < 0.4:
        kind = str(rng.choice(["fixed", "spherical", "revolute", "distance"]))
        b.joint(kind, names[0], names[1], b.ends[names[1]][0])
    return names


# --- loads, start, time -------------------------------------------------------------------------
def forces(b: Builder, names: list[str]) -> list[dict]:
    """Gravity, body forces and torques with windows, springs between bodies (or to the world)."""
    rng, out = b.rng, []
    if rng.random() < 0.6:
        out.append({"type": "gravity", "g": [0.0, 0.0, -9.81]})
    for kind in ("torque", "force"):
        if rng.random() < 0.25:
            f = {"type": kind, "body": str(rng.choice(names)),
                 "vector": (rng.normal(size=3) * b.mass * 9.81 * log_uniform(rng, 1e-3, 1e3)
                            * (b.size if kind == "torque" else 1)).tolist(),
                 "frame": str(rng.choice(["world", "body"]))}
            if kind == "force" and rng.random() < 0.5:
                f["point"] = (b.size * rng.normal(size=3) + b.offset).tolist()
            if rng.random() < 0.5:
                f["start"] = log_uniform(rng, 1e-5, 1)
                f["end"] = f["start"] + log_uniform(rng, 1e-5, 10)
            out.append(f)
    if rng.random() < 0.3:
        a, c = ["world", *names][int(rng.integers(len(names) + 1))], str(rng.choice(names))
        if a == c:
            a = "world"
        pa = b.ends[a][1] if a in b.ends else b.size * rng.normal(size=3)
        s = {"type": "spring", "bodies": [a, c],
             "points": [(pa + b.offset).tolist(), (b.ends[c][1] + b.offset).tolist()],
             "stiffness": log_uniform(rng, 1e-2, 1e12)}
        if rng.random() < 0.4:
            s["rest_length"] = b.size * float(rng.uniform(0, 2))
        if rng.random() < 0.4:
            s["damping"] = log_uniform(rng, 1e-4, 1e8)
        out.append(s)
    return out


def initial(b: Builder, shape: str, names: list[str]) -> dict:
    """Named rates (up to 1e4 rad/s) and positions on random joints; loops get project_initial."""
    rng, out = b.rng, {}
    rate = log_uniform(rng, 1e-3, 1e4)
    movable = [j for j in b.joints if j["type"] in NRATES]
    if shape in ("four-bar", "slider-crank"):
        out["rates"] = {b.joints[0]["name"]: float(rate * rng.choice([-1, 1]))}
        out["project_initial"] = True
    elif shape == "free":
        held = {j["bodies"][1] for j in b.joints if j["type"] != "distance"}
        out["bodies"] = {n: {"velocity": (b.size * rate * rng.normal(size=3)).tolist(),
                             "angular_velocity": (rate * unit(rng)).tolist()}
                         for n in names if n not in held and rng.random() < 0.7}
        if b.joints:
            out["project_initial"] = True
    elif movable and rng.random() < 0.8:
        picked = [j for j in movable if rng.random() < 0.5] or movable[:1]
        out["rates"] = {j["name"]: (rate * rng.normal(size=NRATES[j["type"]])).tolist()
                        for j in picked}
        loop = any(j["type"] == "distance" or j["bodies"][1] == "world" for j in b.joints)
        if rng.random() < 0.4 and not loop:
            out["positions"] = {}
            for j in picked:
                if j["type"] == "spherical":
                    out["positions"][j["name"]] = unit(rng).tolist() + [0.0]
                else:
                    out["positions"][j["name"]] = rng.uniform(
                        -1, 1, NRATES[j["type"]]).tolist()
        if loop:  # a closed chain: the other rates follow from the named ones
            out["project_initial"] = True
    return {k: v for k, v in out.items() if v != {}}


def time_settings(rng: np.random.Generator, expect_usage: bool) -> dict:
    t = {"duration": log_uniform(rng, 1e-3, 1e3),
         "integrator": str(rng.choice(REFUSED_METHODS if expect_usage else RUN_METHODS))}
    if rng.random() < 0.3:
        t["step"] = t["duration"] * log_uniform(rng, 1e-6, 0.3)
    if rng.random() < 0.3:
        t["rtol"] = log_uniform(rng, 1e-13, 1e-3)
    return t


# --- deliberate errors ----------------------------------------------------------------------------
def _zero_axis(s):
    j = next((j for j in s["joints"] if "axis" in j), None)
    if j is None:
        return False
    j["axis"] = [0.0, 0.0, 0.0]
    return True


def _bad_inertia(s):
    body = next(iter(s["bodies"].values()))
    body["inertia"] = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 5.0]]
    return True


def _no_position(s):
    del next(iter(s["bodies"].values()))["position"]
    return True


def _unknown_body(s):
    s["joints"][0]["bodies"] = ["world", "nobody"]
    return True


def _unknown_key(s):
    s["joints"][-1]["stifness"] = 1.0
    return True


def _wrong_rates(s):
    j = next((j for j in s["joints"] if j["type"] in NRATES), None)
    if j is None:
        return False
    s.setdefault("initial", {}).setdefault("rates", {})[j["name"]] = [1.0] * (NRATES[j["type"]] + 1)
    return True


def _rate_on_fixed(s):
    j = next((j for j in s["joints"] if j["type"] in ("fixed", "distance")), None)
    if j is None:
        return False
    s.setdefault("initial", {}).setdefault("rates", {})[j["name"]] = 1.0
    return True


def _negative_stiffness(s):
    j = next((j for j in s["joints"] if j["type"] in ("revolute", "prismatic")), None)
    if j is None:
        return False
    j["stiffness"] = -1.0
    return True


def _bad_rtol(s):
    s["time"]["rtol"] = 2.0
    return True


def _duplicate_name(s):
    if len(s["joints"]) < 2:
        return False
    s["joints"][1]["name"] = s["joints"][0]["name"]
    return True


def _self_joint(s):
    a = s["joints"][0]["bodies"][1]
    s["joints"][0]["bodies"] = [a, a]
    return True


MUTATIONS = (_zero_axis, _bad_inertia, _no_position, _unknown_body, _unknown_key, _wrong_rates,
             _rate_on_fixed, _negative_stiffness, _bad_rtol, _duplicate_name, _self_joint)


def random_case(rng: np.random.Generator, invalid_share: float = 0.08,
                usage_share: float = 0.06) -> tuple[dict, str, str]:
    """One random system scene, what its run must give (run / usage / invalid) and a label."""
    b = Builder(rng)
    shape = str(rng.choice(["chain", "tree", "four-bar", "slider-crank", "free"],
                           p=[0.3, 0.2, 0.2, 0.15, 0.15]))
    names = {"chain": lambda: chain(b, False), "tree": lambda: chain(b, True),
             "four-bar": lambda: four_bar(b), "slider-crank": lambda: slider_crank(b),
             "free": lambda: free_bodies(b)}[shape]()
    expect = "usage" if rng.random() < usage_share else "run"
    scene = {"bodies": b.bodies, "joints": b.joints, "initial": initial(b, shape, names),
             "forces": forces(b, names), "time": time_settings(rng, expect == "usage")}
    for key in ("joints", "initial", "forces"):
        if not scene[key]:
            del scene[key]
    label = shape
    if rng.random() < invalid_share:
        for k in rng.permutation(len(MUTATIONS)):
            if "joints" in scene and MUTATIONS[k](scene):
                expect, label = "invalid", f"{shape}{MUTATIONS[k].__name__}"
                break
    return scene, expect, label
