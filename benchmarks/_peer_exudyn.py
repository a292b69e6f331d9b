"""The system samples in exudyn: a kinematic tree (ObjectKinematicTree, minimal coordinates on a
NodeGenericODE2) built from the sample YAML's numbers; the four-bar's cut joint a spherical
joint (x and z constrained; y is redundant in the plane) between a marker on the rocker and the
ground, which only exudyn's implicit solvers take (an algebraic constraint).

``exudyn_runner(sample, q0, v0, solver, steps, rtol)`` returns ``(build_s, run)`` as the other
peers in _peer_models.py do; ``run()`` gives the tree's joint coordinates at the end.
"""

from __future__ import annotations

import time

import numpy as np
from _peer_models import _chain


def exudyn_runner(sample: dict, q0, v0, solver: str, steps: int, rtol: float | None = None):
    """(build_s, run): ``solver`` a DynamicSolverType name (RK44, RK67, DOPRI5,
    GeneralizedAlpha, TrapezoidalIndex2); ``steps`` fixed steps over the duration (for DOPRI5
    the largest step is duration / steps and ``rtol`` = atol drives its step control)."""
    import exudyn as exu  # optional peer
    from exudyn import itemInterface as ii

    bodies, tree, cut, gravity = _chain(sample)
    duration = float(sample["time"]["duration"])
    start = time.perf_counter()
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    n = len(tree)
    node = mbs.AddNode(ii.NodeGenericODE2(referenceCoordinates=[0.0] * n,
                                          initialCoordinates=list(map(float, q0)),
                                          initialCoordinates_t=list(map(float, v0)),
                                          numberOfODE2Coordinates=n))
    index = {"world": -1}
    points = {"world": np.zeros(3)}
    parents, offsets, inertias, coms, masses = [], [], [], [], []
    for k, (_, parent, child, point) in enumerate(tree):
        _, mass, com, inertia = bodies[child]
        parents.append(index[parent])
        offsets.append(list(point - points[parent]))
        inertias.append(inertia)
        coms.append(list(com - point))
        masses.append(mass)
        index[child], points[child] = k, point
    tree_object = mbs.AddObject(ii.ObjectKinematicTree(
        nodeNumber=node, gravity=list(gravity), jointTypes=[exu.JointType.RevoluteY] * n,
        linkParents=parents, jointTransformations=exu.Matrix3DList([np.eye(3)] * n),
        jointOffsets=exu.Vector3DList(offsets), linkInertiasCOM=exu.Matrix3DList(inertias),
        linkCOMs=exu.Vector3DList(coms), linkMasses=masses))
    if cut is not None:
        moving = cut[2] if cut[1] == "world" else cut[1]
        marker = mbs.AddMarker(ii.MarkerKinematicTreeRigid(
            objectNumber=tree_object, linkNumber=index[moving],
            localPosition=list(cut[3] - points[moving])))
        ground = mbs.AddObject(ii.ObjectGround())
        anchor = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=ground, localPosition=list(cut[3])))
        mbs.AddObject(ii.ObjectJointSpherical(markerNumbers=[anchor, marker],
                                              constrainedAxes=[1, 0, 1]))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.endTime, ti.numberOfSteps = duration, steps
    ti.verboseMode = 0
    settings.solution.file.write = False  # no solution file: the run alone is timed
    settings.solution.sensors.active = False
    if solver == "DOPRI5":
        ti.automaticStepSize = True
        ti.relativeTolerance = ti.absoluteTolerance = rtol
        ti.minimumStepSize = 1e-12
    if solver == "GeneralizedAlpha":  # no numerical damping: the trapezoidal rule (index 3)
        ti.generalizedAlpha.spectralRadius = 1.0
    if solver in ("GeneralizedAlpha", "TrapezoidalIndex2"):
        ti.newton.relativeTolerance = 1e-14
        ti.newton.absoluteTolerance = 1e-14
        ti.newton.useModifiedNewton = False
    kind = getattr(exu.DynamicSolverType, solver)
    build = time.perf_counter() - start

    def run():
        initial = exu.ConfigurationType.Initial
        mbs.systemData.SetODE2Coordinates(list(map(float, q0)), configuration=initial)
        mbs.systemData.SetODE2Coordinates_t(list(map(float, v0)), configuration=initial)
        try:
            ok = mbs.SolveDynamic(settings, solverType=kind)
        except exu.SolverError:  # e.g. Newton failing at a large step: no result
            ok = False
        q = np.array(mbs.systemData.GetODE2Coordinates())
        return (q if ok else np.full(n, np.nan)), 0.0

    return build, run
